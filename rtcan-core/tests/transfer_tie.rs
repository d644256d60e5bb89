#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! Transfers cannot mix (docs/PROTOCOL.md §7.4): every fragment carries its transfer ID,
//! so the receiver never glues frames of two transfers, whatever the data. Exhaustive over
//! loss patterns; the old transfer CRC's blind spot is reproduced to show what changed.
use rtcan_core::fragment::split_field;
use rtcan_core::fragment::{
    fragment_count, fragment_data, fragment_field, transfer_id_bits, RxState, RxStep, MAX_PAYLOAD,
};
use rtcan_core::id::{CanId, MsgId};
use rtcan_core::Frame;

mod common;
mod paper_bus;

const TOPIC: MsgId = MsgId(0x0161);

fn frames(payload: &[u8], tid: u8) -> Vec<Frame> {
    let count = fragment_count(payload.len());
    (0..count)
        .rev()
        .map(|c| {
            let mut out = [0; 8];
            let dlc = fragment_data(payload, c, &mut out);
            let id = CanId::new(0, TOPIC, fragment_field(count, tid, c)).unwrap();
            Frame::from_parts(id, dlc, out).unwrap()
        })
        .collect()
}

/// Feeds `frames` to a fresh receiver; returns the payloads delivered.
fn receive(size: usize, frames: &[Frame]) -> Vec<Vec<u8>> {
    let mut rx = RxState::default();
    let mut buf = vec![0u8; size];
    let mut out = Vec::new();
    for f in frames {
        if let RxStep::Complete(p, _) = rx.step(&mut buf, size, f, 0) {
            out.push(p.to_vec());
        }
    }
    out
}

/// The old transfer CRC (CRC-16/CCITT-FALSE), kept here only to reproduce its blind spot.
fn old_crc16(data: &[u8]) -> u16 {
    let mut crc: u16 = 0xFFFF;
    for &b in data {
        crc ^= u16::from(b) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ 0x1021
            } else {
                crc << 1
            };
        }
    }
    crc
}

fn twist(vx: f32, vy: f32, wz: f32) -> Vec<u8> {
    [vx, vy, wz].iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// Issue 11's glued delivery: message A's first fragment + message B's remaining
/// fragments. With the old 2-byte CRC, any A and B whose first 8 bytes differ by the CRC
/// generator's pattern passed the check every time (the CRC is linear: the difference
/// cancels). With transfer IDs, the glue is dropped, for every pair.
#[test]
fn glued_first_fragment_of_a_and_rest_of_b_is_never_delivered() {
    // The generator x^16 + x^12 + x^5 + 1 as the last 17 bits of the first fragment.
    let pattern = [0u8, 0, 0, 0, 0, 0x01, 0x10, 0x21];
    let mut colliding = 0;
    for vx in [0.0f32, 0.1, 0.25, 0.3604, 0.5, -0.5, 1.0] {
        for wz in [0.0f32, 0.5, -1.25] {
            let b = twist(vx, 0.0, wz);
            let mut a = b.clone();
            for (x, p) in a.iter_mut().zip(pattern) {
                *x ^= p;
            }
            // The old scheme: A's first 8 bytes, B's last 4 and B's CRC: accepted.
            let mut glued = a[..8].to_vec();
            glued.extend_from_slice(&b[8..]);
            if old_crc16(&glued) == old_crc16(&b) {
                colliding += 1;
            }
            // The new scheme, consecutive transfers (and any two IDs that differ).
            for (ta, tb) in [(0u8, 1u8), (63, 0), (7, 9), (200, 201)] {
                let fa = frames(&a, ta);
                let fb = frames(&b, tb);
                assert_eq!(fa.len(), 2);
                let got = receive(12, &[fa[0], fb[1]]);
                assert!(got.is_empty(), "glue delivered {got:?}");
                // And each alone still arrives.
                assert_eq!(receive(12, &fa), vec![a.clone()]);
                assert_eq!(receive(12, &[fa[0], fb[0], fb[1]]), vec![b.clone()]);
            }
        }
    }
    assert_eq!(colliding, 21, "the old CRC accepted every such glue");
}

/// Every subset of at most `max_lost` indices of `0..n`, by increasing size.
fn loss_patterns(n: usize, max_lost: usize, mut f: impl FnMut(&[usize])) {
    f(&[]);
    if max_lost >= 1 {
        for a in 0..n {
            f(&[a]);
            if max_lost >= 2 {
                for b in a + 1..n {
                    f(&[a, b]);
                    if max_lost >= 3 {
                        for c in b + 1..n {
                            f(&[a, b, c]);
                        }
                    }
                }
            }
        }
    }
}

/// Three consecutive transfers of one topic; every pattern of up to 3 lost frames among
/// their frames. Delivered = exactly the transfers none of whose frames was lost, in order:
/// nothing wrong, nothing mixed, and nothing complete withheld. Returns patterns checked.
fn three_transfers(size: usize, first_tid: u8, tie: bool) -> Result<u64, String> {
    let count = usize::from(fragment_count(size));
    let payloads: Vec<Vec<u8>> = (0..3u8)
        .map(|t| {
            (0..size)
                .map(|i| (i as u8).wrapping_mul(7) ^ ((t + 1) * 0x35))
                .collect()
        })
        .collect();
    let tid = |t: u8| {
        if tie {
            first_tid.wrapping_add(t)
        } else {
            first_tid
        }
    };
    let all: Vec<Frame> = (0..3u8)
        .flat_map(|t| frames(&payloads[t as usize], tid(t)))
        .collect();
    let mut checked = 0u64;
    let mut failure = None;
    loss_patterns(all.len(), 3, |lost| {
        if failure.is_some() {
            return;
        }
        let kept: Vec<Frame> = (0..all.len())
            .filter(|i| !lost.contains(i))
            .map(|i| all[i])
            .collect();
        let expect: Vec<Vec<u8>> = (0..3)
            .filter(|t| !lost.iter().any(|l| l / count == *t))
            .map(|t| payloads[t].clone())
            .collect();
        let got = receive(size, &kept);
        if got != expect {
            failure = Some(format!(
                "size {size}, first transfer ID {first_tid}, lost frames {lost:?}: delivered {} of {} expected, wrong: {}",
                got.len(),
                expect.len(),
                got.iter().filter(|g| !payloads.contains(g)).count()
            ));
        }
        checked += 1;
    });
    failure.map_or(Ok(checked), Err)
}

#[test]
fn every_loss_of_up_to_3_frames_across_3_transfers_is_never_delivered_wrong() {
    let mut patterns = 0;
    // Sizes giving 1, 2, 3, 4, 5, 8, 9, 16, 17 and 32 frames, full and partial last frames.
    for size in [
        1,
        8,
        9,
        12,
        16,
        20,
        24,
        33,
        40,
        64,
        65,
        100,
        128,
        129,
        200,
        MAX_PAYLOAD,
    ] {
        let count = fragment_count(size);
        let wrap = (1u16 << transfer_id_bits(count)) as u8;
        // Transfer IDs from 0, and across their wrap (2^bits - 1, 0, 1 on the wire); the
        // long messages (up to 96 frames, 147 537 patterns each) across the wrap only.
        let firsts = if count > 16 {
            vec![wrap.wrapping_sub(2)]
        } else {
            vec![0u8, wrap.wrapping_sub(1), wrap.wrapping_sub(2)]
        };
        for first in firsts {
            patterns += three_transfers(size, first, true).unwrap();
        }
    }
    assert!(patterns > 300_000, "{patterns} patterns");
}

/// The enumeration bites: without the transfer ID in the fragments (every transfer
/// sending the same field values), some loss pattern of at most 3 frames delivers a
/// message that was never sent, for every size of 2 or 3 frames. (A glue of transfer
/// `t`'s head and `t+1`'s tail loses `t`'s tail and `t+1`'s head: `count` frames, so with
/// 4 or more frames it needs more than 3 losses, and single frames cannot mix.)
#[test]
fn without_transfer_ids_the_same_enumeration_finds_mixes() {
    for size in [9, 12, 16, 17, 20, 24] {
        let err = three_transfers(size, 0, false).unwrap_err();
        assert!(!err.contains("wrong: 0"), "{err}");
    }
    assert!(three_transfers(8, 0, false).is_ok());
    assert!(three_transfers(25, 0, false).is_ok());
}

/// In the engine: consecutive SRT transfers of one topic (5 queued at once, so several
/// first fragments share the mailboxes) take consecutive transfer IDs, every fragment
/// carries its transfer's, and every message arrives whole.
#[test]
fn engine_numbers_the_transfers_of_a_topic() {
    let (mut bus, p) = paper_bus::paper_bus_with_backups();
    bus.run(5 * paper_bus::CYCLE_NS);
    let topic = paper_bus::msg_id(1, 3);
    let payloads: Vec<Vec<u8>> = (0..5u8)
        .map(|k| {
            (0..paper_bus::S_SIZE as u8)
                .map(|b| b ^ (k * 0x11))
                .collect()
        })
        .collect();
    for pl in &payloads {
        bus.submit(1, 3, pl).expect("queued");
    }
    let t = bus.now;
    bus.run(t + 10 * paper_bus::CYCLE_NS);
    let fields: Vec<(u8, u8)> = bus
        .log
        .iter()
        .filter(|w| w.frame.id().msg_id() == topic)
        .map(|w| split_field(3, w.frame.id().fragment()))
        .collect();
    let expect: Vec<(u8, u8)> = (0..5u8).flat_map(|t| [(t, 2), (t, 1), (t, 0)]).collect();
    assert_eq!(fields, expect);
    for rx_node in [0, 2] {
        let got: Vec<Vec<u8>> = bus.nodes[rx_node]
            .host
            .delivered
            .iter()
            .filter(|(rx, _, _)| p.tables[rx_node].rx[*rx as usize].msg_id == topic)
            .map(|d| d.1.clone())
            .collect();
        assert_eq!(got, payloads, "node {rx_node}");
        assert_eq!(bus.nodes[rx_node].engine.counters().rx_other_transfer, 0);
    }
}
