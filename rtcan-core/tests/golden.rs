//! Golden vectors: every hex value printed in docs/PROTOCOL.md is asserted here, with the
//! same numbers, section by section (§ numbers refer to PROTOCOL.md).
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

use proptest::prelude::*;
use rtcan_core::fragment::{
    counter_bits, fragment_count, fragment_data, fragment_field, transfer_id_bits, wire_len,
    RxDrop, RxState, RxStep, MAX_PAYLOAD,
};
use rtcan_core::heartbeat::{heartbeat_frame, parse_heartbeat, Heartbeat};
use rtcan_core::id::{CanId, MsgId};
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::sync::{cycle_counter_wrap, parse_sync, sync_frame, Sync};
use rtcan_core::timing::{bits_to_ns, exact_bits, min_slot_ns, worst_case_bits};
use rtcan_core::Frame;

fn id(laxity: u8, msg: u16, frag: u8) -> u32 {
    CanId::new(laxity, MsgId(msg), frag).unwrap().raw()
}

// §2.4 identifier examples.
#[test]
fn s2_identifiers() {
    assert_eq!(id(0, 0x0140, 0), 0x0000_A000); // HRT topic 0x0140, last fragment
    assert_eq!(id(5, 0x0141, 2), 0x0280_A082); // SRT laxity 5, topic 0x0141, fragment 2
    assert_eq!(id(63, 0x0142, 0), 0x1F80_A100); // NRT topic 0x0142
    assert_eq!(id(63, 0x0103, 0), 0x1F80_8180); // heartbeat of module 3
    let d = CanId::from_raw(0x0280_A082).unwrap();
    assert_eq!(
        (d.laxity(), d.msg_id(), d.fragment()),
        (5, MsgId(0x0141), 2)
    );
    // Arbitration order is numeric order: sync < HRT < SRT(5) < NRT.
    let sync3 = sync_frame(Sync { cycle: 3, mask: 1 }, 60).id().raw();
    let order = [sync3, id(0, 0x0140, 0), id(5, 0x0141, 2), id(63, 0x0142, 0)];
    assert!(order.windows(2).all(|w| w[0] < w[1]), "{order:x?}");
}

// §3.5 sync examples.
#[test]
fn s3_sync_frames() {
    // Paper Fig. 3 (60 slots): sync + H_A (period 6) of nodes 1..3 at slots 1..3 mod 6,
    // H_B (period 30) at 4..6 and 34..36, H_C (period 60) at 10..12.
    let mut mask = 1u64;
    for k in (0..10)
        .flat_map(|j| (1..=3).map(move |o| 6 * j + o))
        .chain([4, 5, 6, 34, 35, 36, 10, 11, 12])
    {
        mask |= 1 << k;
    }
    assert_eq!(mask, 0x038E_38FF_8E38_FFFF);
    let f = sync_frame(Sync { cycle: 3, mask }, 60);
    assert_eq!(f.id().raw(), 0x0000_0003);
    assert_eq!(f.dlc(), 8);
    assert_eq!(f.data(), &[0xFF, 0xFF, 0x38, 0x8E, 0xFF, 0x38, 0x8E, 0x03]);
    assert_eq!(parse_sync(&f, 60), Some(Sync { cycle: 3, mask }));

    // 40-slot bus, same low 40 bits: DLC 5.
    let m40 = mask & ((1 << 40) - 1);
    assert_eq!(m40, 0x00FF_8E38_FFFF);
    let f = sync_frame(
        Sync {
            cycle: 3,
            mask: m40,
        },
        40,
    );
    assert_eq!((f.id().raw(), f.dlc()), (0x0000_0003, 5));
    assert_eq!(f.data(), &[0xFF, 0xFF, 0x38, 0x8E, 0xFF]);
    // The 60-slot frame is garbage on a 40-slot bus (DLC 8 != 5).
    assert_eq!(
        parse_sync(&sync_frame(Sync { cycle: 3, mask }, 60), 40),
        None
    );

    // Cycle 0x1234: message ID 0x0024, fragment field 0x34.
    let f = sync_frame(
        Sync {
            cycle: 0x1234,
            mask: 1,
        },
        60,
    );
    assert_eq!(f.id().raw(), 0x0000_1234);
    assert_eq!((f.id().msg_id(), f.id().fragment()), (MsgId(0x0024), 0x34));
    assert!(f.id().is_sync());

    // §3.4 counter wrap: hyperperiod 3 cycles -> 32766; 60-slot Fig. 3 (hyperperiod 1) -> 32768.
    assert_eq!(cycle_counter_wrap(3), Some(32_766));
    assert_eq!(cycle_counter_wrap(1), Some(32_768));
}

// §4.1 worst case: 80 + 10 * dlc bits.
#[test]
fn s4_worst_case_bits() {
    let table: Vec<u32> = (0..=8).map(worst_case_bits).collect();
    assert_eq!(table, [80, 90, 100, 110, 120, 130, 140, 150, 160]);
    assert_eq!(worst_case_bits(15), 160);
}

// §4.2 exact length of concrete frames, derived by hand below.
//
// Frame A: ID 0x00000000 (sync, cycle 0), DLC 0. Unstuffed bits (54):
//   SOF 0 | base ID 00000000000 | SRR 1 | IDE 1 | ext ID 000000000000000000 | RTR 0 r1 0 r0 0
//   | DLC 0000 | CRC-15
// CRC-15 (register r, init 0; per bit: n = bit ^ r[14]; r = (r << 1) & 0x7FFF; if n: r ^= 0x4599):
//   12 zeros keep r = 0; SRR 1 -> 4599; IDE 1 (r[14]=1, n=0) -> 0B32; then the 25 zeros
//   (ext ID, RTR, r1, r0, DLC) shift with n = r[14]:
//   1664 2CC8 5990 76B9 28EB 51D6 6635 09F3 13E6 27CC 4F98 5AA9 70CB
//   240F 481E 55A5 6ED3 183F 307E 60FC 0461 08C2 1184 2308 4610  -> CRC = 0x4610
//   = 100 0110 0001 0000.
// Stuffed stream ([b] = stuff bit, complement of the run; it starts the next run):
//   00000[1]00000[1]0011 00000[1]00000[1]00000[1]00000[1]00000[1] 100011000010000
//   SOF + base ID = 12 zeros -> 2 stuff bits (2 zeros left, then SRR IDE = 11);
//   ext ID + RTR + r1 + r0 + DLC = 25 zeros -> exactly 5 runs of five -> 5 stuff bits;
//   the CRC 100 0110 0001 0000 has no run of five (its leading 1 joins the last stuff 1:
//   a run of 2). Stuff bits: 7. Total = 54 + 7 + 13 (CRC delim 1, ACK 2, EOF 7, IFS 3) = 74.
//
// Frame B: ID 0x00000000, DLC 8, data 00 x 8. 118 unstuffed bits, CRC-15 = 0x3DAF
//   = 011 1101 1010 1111 (same register rule, 64 more zero steps after DLC 1000).
//   00000[1]00000[1]0011 00000[1]00000[1]00000[1]00000[1]0 1 000 <64 zeros> 0 11110110101111
//   12 zeros -> 2; ext ID + RTR + r1 + r0 = 21 zeros -> 4 (1 left, ended by the DLC's 1);
//   DLC tail 000 + 64 data zeros + the CRC's leading 0 = 68 zeros -> 13 stuff bits
//   (3 zeros left); the CRC tail 1111 0 11 0 1 0 1111 has no run of five.
//   Stuff bits: 2 + 4 + 13 = 19. Total = 118 + 19 + 13 = 150.
//
// Frame C: HRT topic 0x0140 fragment 0, ID 0x0000A000, DLC 0: base ID = ID[28:18] = 0,
//   ext ID = ID[17:0] = 0x0A000 = 00 1010 0000 0000 0000, CRC-15 = 0x228D = 010 0010 1000 1101.
//   00000[1]00000[1]0011 00101 00000[1]00000[1]00000[1]00000[1]0 10001010001101
//   12 zeros -> 2; the 13 zeros ending the ext ID + RTR r1 r0 (3) + DLC (4) + the CRC's
//   leading 0 = 21 zeros -> 4 stuff bits (1 left). Stuff bits: 6. Total = 54 + 6 + 13 = 73.
#[test]
fn s4_exact_bits_hand_computed() {
    let a = Frame::new(CanId::from_raw(0).unwrap(), &[]).unwrap();
    assert_eq!(exact_bits(&a), 74);
    assert_eq!(reference_bits(&a), (0x4610, 7, 74));
    let b = Frame::new(CanId::from_raw(0).unwrap(), &[0; 8]).unwrap();
    assert_eq!(exact_bits(&b), 150);
    assert_eq!(reference_bits(&b), (0x3DAF, 19, 150));
    let c = Frame::new(CanId::from_raw(0x0000_A000).unwrap(), &[]).unwrap();
    assert_eq!(exact_bits(&c), 73);
    assert_eq!(reference_bits(&c), (0x228D, 6, 73));
    // All-recessive ID and data: 149.
    let d = Frame::new(CanId::from_raw(0x1FFF_FFFF).unwrap(), &[0xFF; 8]).unwrap();
    assert_eq!(exact_bits(&d), 149);
    assert_eq!(reference_bits(&d).2, 149);
    // §9 heartbeat of module 3 (below): 115.
    let hb = heartbeat_frame(Heartbeat {
        module: 3,
        state: 1,
        fingerprint: 0xDEAD_BEEF,
    })
    .unwrap();
    assert_eq!(exact_bits(&hb), 115);
    assert_eq!(reference_bits(&hb).2, 115);
}

// §4.3 slot arithmetic of the paper's bus (1 Mbit/s, 10 ms cycle, 60 slots).
#[test]
fn s4_slot_figures() {
    assert_eq!(bits_to_ns(worst_case_bits(8), 1_000_000), 160_000);
    let slot_ns = 10_000_000 / 60;
    assert_eq!(slot_ns, 166_666);
    let guard = slot_ns - 160_000;
    assert_eq!(guard, 6_666);
    assert_eq!(min_slot_ns(1_000_000, guard), slot_ns);
    // Payload capacity: 59 free-or-HRT slots x 64 bits per 10 ms.
    assert_eq!(59 * 64 * 100, 377_600);
    // Raw CAN: 64 payload bits per 160-bit frame at 1 Mbit/s.
    assert_eq!(64 * 1_000_000 / 160, 400_000);
    assert_eq!(bits_to_ns(1, 3), 333_333_334); // rounding up
}

// §6.4 laxity examples.
#[test]
fn s6_laxity() {
    let lin = LaxityEncoding::Linear { unit_ns: 100_000 };
    assert_eq!(lin.encode(450_000), Some(5)); // the SRT example of §2.4
    assert_eq!(lin.encode(-1), None);
    assert_eq!(lin.max_laxity_ns(), 6_100_000);
    let log = LaxityEncoding::Log { unit_ns: 10_000 };
    let codes: Vec<u8> = [
        0, 150_000, 160_000, 170_000, 180_000, 320_000, 1_000_000, 5_000_000, 8_320_000,
    ]
    .iter()
    .map(|&l| log.encode(l).unwrap())
    .collect();
    assert_eq!(codes, [1, 16, 17, 17, 18, 25, 37, 56, 62]);
    assert_eq!(log.max_laxity_ns(), 8_320_000);
    assert_eq!(log.lower_bound_ns(37), Some(960_000));
    // The §2.4 example ID with the laxity computed, not typed.
    assert_eq!(id(lin.encode(450_000).unwrap(), 0x0141, 2), 0x0280_A082);
}

// §7.5 a 20-byte message 00 01 .. 13 on HRT topic 0x0140, transfer ID 5.
#[test]
fn s7_fragment_example() {
    let p: Vec<u8> = (0..20).collect();
    assert_eq!((wire_len(20), fragment_count(20)), (20, 3));
    assert_eq!((counter_bits(3), transfer_id_bits(3)), (2, 5));
    assert_eq!((wire_len(8), fragment_count(8)), (8, 1));
    assert_eq!((wire_len(9), fragment_count(9)), (9, 2));
    assert_eq!((wire_len(16), fragment_count(16)), (16, 2));
    assert_eq!(
        (wire_len(MAX_PAYLOAD), fragment_count(MAX_PAYLOAD)),
        (256, 32)
    );
    let bits: Vec<u8> = [2u8, 4, 8, 16, 32]
        .iter()
        .map(|&c| transfer_id_bits(c))
        .collect();
    assert_eq!(bits, [6, 5, 4, 3, 2]);
    let expect: [(u32, &[u8]); 3] = [
        (
            0x0000_A016,
            &[0x00, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07],
        ),
        (
            0x0000_A015,
            &[0x08, 0x09, 0x0A, 0x0B, 0x0C, 0x0D, 0x0E, 0x0F],
        ),
        (0x0000_A014, &[0x10, 0x11, 0x12, 0x13]),
    ];
    let mut rx = RxState::default();
    let mut buf = [0u8; 20];
    let mut sent = Vec::new();
    for (k, (raw, data)) in expect.iter().enumerate() {
        let counter = 2 - k as u8;
        let mut out = [0; 8];
        let dlc = fragment_data(&p, counter, &mut out);
        assert_eq!(&out[..dlc as usize], *data);
        let f = Frame::new(
            CanId::new(0, MsgId(0x0140), fragment_field(3, 5, counter)).unwrap(),
            &out[..dlc as usize],
        )
        .unwrap();
        assert_eq!(f.id().raw(), *raw);
        sent.push(f);
        let r = rx.step(&mut buf, 20, &f, 100 + k as u64);
        if counter > 0 {
            assert_eq!(r, RxStep::Pending);
        } else {
            assert_eq!(r, RxStep::Complete(&p[..], 100));
        }
    }
    // The next transfer (ID 6) starts 0x0000A01A; its 2nd fragment after transfer 5's
    // first is dropped as another transfer's.
    assert_eq!(id(0, 0x0140, fragment_field(3, 6, 2)), 0x0000_A01A);
    assert_eq!(id(0, 0x0140, fragment_field(3, 6, 1)), 0x0000_A019);
    let next = Frame::new(CanId::from_raw(0x0000_A019).unwrap(), &[0; 8]).unwrap();
    assert_eq!(rx.step(&mut buf, 20, &sent[0], 0), RxStep::Pending);
    assert_eq!(
        rx.step(&mut buf, 20, &next, 0),
        RxStep::Dropped(RxDrop::OtherTransfer)
    );
    // Transfer ID 37 on 5 bits is 5 again.
    assert_eq!(fragment_field(3, 37, 2), 0x16);
}

// §9 heartbeat example.
#[test]
fn s9_heartbeat() {
    let hb = Heartbeat {
        module: 3,
        state: 1,
        fingerprint: 0xDEAD_BEEF,
    };
    let f = heartbeat_frame(hb).unwrap();
    assert_eq!(f.id().raw(), 0x1F80_8180);
    assert_eq!(f.data(), &[0xEF, 0xBE, 0xAD, 0xDE, 0x01]);
    assert_eq!(parse_heartbeat(&f), Some(hb));
}

/// Independent bit-level model of a CAN 2.0B extended data frame: builds the unstuffed
/// bit vector, computes CRC-15 by polynomial long division, then stuffs it. Returns
/// (crc, stuff bits, total bits incl. delimiter, ACK, EOF, intermission).
fn reference_bits(f: &Frame) -> (u16, u32, u32) {
    let raw = f.id().raw();
    let mut bits: Vec<u8> = vec![0];
    let field = |bits: &mut Vec<u8>, v: u32, n: u32| {
        bits.extend((0..n).rev().map(|i| ((v >> i) & 1) as u8))
    };
    field(&mut bits, raw >> 18, 11);
    bits.extend([1, 1]);
    field(&mut bits, raw & 0x3FFFF, 18);
    bits.extend([0, 0, 0]);
    field(&mut bits, u32::from(f.dlc()), 4);
    for &b in f.data() {
        field(&mut bits, u32::from(b), 8);
    }
    // Long division of bits * x^15 by the generator (1 << 15 | 0x4599).
    let mut rem: Vec<u8> = bits.clone();
    rem.extend([0; 15]);
    let gen: Vec<u8> = (0..16)
        .rev()
        .map(|i| (((1u32 << 15 | 0x4599) >> i) & 1) as u8)
        .collect();
    for i in 0..bits.len() {
        if rem[i] == 1 {
            for (j, g) in gen.iter().enumerate() {
                rem[i + j] ^= g;
            }
        }
    }
    let crc = rem[bits.len()..]
        .iter()
        .fold(0u16, |a, &b| a << 1 | u16::from(b));
    field(&mut bits, u32::from(crc), 15);
    let (mut stuffed, mut run, mut last) = (0u32, 0u32, 2u8);
    for &b in &bits {
        if b == last {
            run += 1;
        } else {
            (last, run) = (b, 1);
        }
        if run == 5 {
            stuffed += 1;
            (last, run) = (1 - b, 1);
        }
    }
    (crc, stuffed, bits.len() as u32 + stuffed + 13)
}

fn any_frame() -> impl Strategy<Value = Frame> {
    (
        0u32..=0x1FFF_FFFF,
        proptest::collection::vec(any::<u8>(), 0..=8),
    )
        .prop_map(|(raw, data)| Frame::new(CanId::from_raw(raw).unwrap(), &data).unwrap())
}

proptest! {
    // exact_bits agrees with the independent model and never exceeds the worst case
    // the schedule is built on.
    #[test]
    fn exact_bits_matches_reference_and_bound(f in any_frame()) {
        let e = exact_bits(&f);
        prop_assert_eq!(e, reference_bits(&f).2);
        prop_assert!(e <= worst_case_bits(f.dlc()));
        prop_assert!(e >= 54 + 8 * u32::from(f.dlc()) + 13);
    }
}
