//! The update protocol over frames: host `Sender` ↔ module `Port`, frame by frame, with
//! frames lost on the way (docs/SERVICES.md §4).
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use rtcan_boot::can::{parse_reply, reply_frame, request_frame, request_payload, Port};
use rtcan_boot::sender::{Config, Outcome, Sender};
use rtcan_boot::update::{Msg, Reply, Why};
use rtcan_boot::{Crc32, Layout};
use rtcan_core::Frame;
use rtcan_pubsub::flash::F103Flash;

const LAYOUT: Layout = Layout {
    slot_page: [0, 30],
    slot_pages: 30,
    fingerprint_offset: 0x1D0,
};
type F = F103Flash<60>;

fn image(len: usize, fp: u32, salt: u8) -> Vec<u8> {
    let mut v: Vec<u8> = (0..len).map(|i| (i as u8).wrapping_mul(7) ^ salt).collect();
    let o = LAYOUT.fingerprint_offset as usize;
    v[o..o + 4].copy_from_slice(&fp.to_le_bytes());
    v
}

/// Runs the exchange with one frame per 100 µs; `lose(k, frame)` drops the k-th frame
/// (requests and replies counted together). Returns the outcome and the sender.
fn exchange<'i>(
    f: &mut F,
    img: &'i [u8],
    fp: u32,
    lose: impl Fn(u64, &Frame) -> bool,
) -> (Outcome, Sender<&'i [u8]>) {
    let mut s = Sender::new(2, img, fp, Config::default());
    // The module runs what its bootloader booted; the update goes to the other slot.
    let running = LAYOUT.boot_slot(f, None);
    let mut port = Port::new(2, &LAYOUT, running);
    let mut now = 0u64;
    let mut k = 0u64;
    for _ in 0..2_000_000 {
        if let Some(o) = s.outcome() {
            return (o, s);
        }
        now += 100_000;
        // The bus carries the module's reply first (same priority class; the replies'
        // IDs are numerically larger, but one frame per step keeps this simple).
        if let Some(r) = port.next() {
            port.sent();
            k += 1;
            if !lose(k, &r) {
                s.on_frame(&r, now);
            }
            continue;
        }
        if let Some(fr) = s.next_frame(now) {
            s.sent(now);
            k += 1;
            if !lose(k, &fr) {
                port.on_frame(f, &fr, now);
            }
        }
    }
    panic!("no outcome");
}

#[test]
fn wire_forms() {
    // Begin of a 28 KiB image: length byte 13, op 1, len, crc, fingerprint, 0xFF pad.
    let p = request_payload(&Msg::Begin {
        len: 28 * 1024,
        crc: 0x1122_3344,
        fingerprint: 0xDEAD_BEEF,
    })
    .unwrap();
    assert_eq!(
        &p[..15],
        &[13, 1, 0x00, 0x70, 0, 0, 0x44, 0x33, 0x22, 0x11, 0xEF, 0xBE, 0xAD, 0xDE, 0xFF]
    );
    assert!(p[14..].iter().all(|&b| b == 0xFF));
    // First fragment to module 2, transfer 1: counter 31, field 1 << 5 | 31.
    let fr = request_frame(2, 1, 31, &p).unwrap();
    assert_eq!(fr.id().raw(), (63 << 23) | (0xFF82 << 7) | 0x3F);
    assert_eq!(fr.data(), &p[..8]);
    let last = request_frame(2, 1, 0, &p).unwrap();
    assert_eq!(last.id().raw(), (63 << 23) | (0xFF82 << 7) | 0x20);
    assert_eq!(last.data(), &p[248..]);
    // A reply: Ack{next: 500} from module 2 on 0xFFC2.
    let r = reply_frame(2, Reply::Ack { next: 500 }).unwrap();
    assert_eq!(r.id().raw(), 0x1FFF_E100);
    assert_eq!(r.data(), &[2, 0xF4, 0x01, 0, 0, 0, 0, 0]);
    assert_eq!(parse_reply(&r), Some((2, Reply::Ack { next: 500 })));
    for rep in [
        Reply::Ready { slot: 1 },
        Reply::Done {
            slot: 0,
            seq: 0x1234,
        },
        Reply::Failed {
            why: Why::Fingerprint,
        },
    ] {
        assert_eq!(Reply::decode(&rep.encode()), Some(rep));
    }
    assert_eq!(Reply::decode(&[4, 99, 0, 0, 0, 0, 0, 0]), None);
    assert_eq!(Reply::decode(&[2, 0, 0, 0, 0]), None);
    // A request frame is not a reply.
    assert_eq!(parse_reply(&fr), None);
}

#[test]
fn lossless_28_kib_update_counts_exactly() {
    let mut f = F::new();
    let img = image(28 * 1024, 0xF00D, 3);
    let (o, s) = exchange(&mut f, &img, 0xF00D, |_, _| false);
    assert_eq!(o, Outcome::Done { slot: 0, seq: 1 });
    // Begin + ceil(28672 / 250) = 115 Data + End, 32 frames each; one reply each.
    assert_eq!(s.stats.requests, 117);
    assert_eq!(s.stats.frames, 117 * 32);
    assert_eq!(s.stats.replies, 117);
    assert_eq!(s.stats.retries, 0);
    assert_eq!(LAYOUT.boot_slot(&f, Some(0xF00D)), Some(0));
    assert_eq!(LAYOUT.image_crc(&f, 0, 28 * 1024), Some(Crc32::of(&img)));
}

#[test]
fn lost_frames_are_repeated_and_the_image_arrives_whole() {
    let mut f = F::new();
    let img = image(6001, 0xAB, 9);
    // Every 97th frame lost, requests and replies alike.
    let (o, s) = exchange(&mut f, &img, 0xAB, |k, _| k % 97 == 0);
    assert_eq!(o, Outcome::Done { slot: 0, seq: 1 });
    assert!(s.stats.retries >= 3, "{:?}", s.stats);
    assert!(s.stats.frames > 27 * 32, "{:?}", s.stats);
    assert_eq!(LAYOUT.image_crc(&f, 0, 6001), Some(Crc32::of(&img)));
    assert_eq!(LAYOUT.boot_slot(&f, Some(0xAB)), Some(0));
}

#[test]
fn bad_images_are_refused_over_the_bus() {
    let mut f = F::new();
    let good = image(3000, 7, 1);
    assert_eq!(
        exchange(&mut f, &good, 7, |_, _| false).0,
        Outcome::Done { slot: 0, seq: 1 }
    );
    // Built for robot 8, announced as robot 7.
    let other = image(3000, 8, 2);
    let mut f2 = f.clone();
    assert_eq!(
        exchange(&mut f2, &other, 7, |_, _| false).0,
        Outcome::Failed(Why::Fingerprint)
    );
    assert_eq!(LAYOUT.boot_slot(&f2, Some(7)), Some(0));
    // One data byte corrupted in a frame the CAN CRC would not catch (a sender bug):
    // the image CRC refuses it.
    let mut f3 = f.clone();
    let img = image(3000, 7, 4);
    let mut s = Sender::new(2, &img[..], 7, Config::default());
    let mut port = Port::new(2, &LAYOUT, Some(0));
    let mut last = None;
    for step in 0..100_000u64 {
        if let Some(r) = port.next() {
            port.sent();
            s.on_frame(&r, step);
            last = parse_reply(&r).map(|x| x.1);
        } else if let Some(fr) = s.next_frame(step) {
            s.sent(step);
            let fr = if s.stats.frames == 40 {
                let mut d = *fr.raw_data();
                d[3] ^= 0x10;
                Frame::from_parts(fr.id(), fr.dlc(), d).unwrap()
            } else {
                fr
            };
            port.on_frame(&mut f3, &fr, step);
        }
        if s.outcome().is_some() {
            break;
        }
    }
    assert_eq!(s.outcome(), Some(Outcome::Failed(Why::Crc)));
    assert_eq!(last, Some(Reply::Failed { why: Why::Crc }));
    assert_eq!(LAYOUT.boot_slot(&f3, Some(7)), Some(0));
    // A module that never answers: the sender gives up after its retries.
    let mut s = Sender::new(5, &img[..], 7, Config::default());
    let mut t = 0;
    while s.outcome().is_none() && t < 1_000_000_000_000 {
        t += 1_000_000;
        if s.next_frame(t).is_some() {
            s.sent(t);
        }
    }
    assert_eq!(s.outcome(), Some(Outcome::Timeout));
    assert_eq!(s.stats.retries, Config::default().max_retries + 1);
}
