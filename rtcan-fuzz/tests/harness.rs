#![allow(clippy::reversed_empty_ranges)] // a reversed span is one of the bad cases
//! The harnesses on hand-written inputs: what they exercise is what they claim, and a
//! finding is reported (a panic), not swallowed.
use rtcan_fuzz::engine_rx::run_stats;

/// Header of an `engine_rx` input: a slave on 40 slots, module 2, one receive topic of
/// `size` bytes at 0x0140, zero masks, start time 0.
fn header(size: u16) -> Vec<u8> {
    let mut v = vec![0, 38, 2, 0];
    v.extend_from_slice(&size.to_le_bytes());
    v.push(0); // message-ID step
    v.extend_from_slice(&[0; 24]); // master masks
    v.extend_from_slice(&[0; 4]); // now
    v
}

#[test]
fn a_whole_transfer_is_delivered_and_a_lossy_one_is_not() {
    let mut v = header(20);
    // op 3: transfer of topic 0, transfer ID 5, laxity 0, no loss, no duplicate, fill 0x10.
    v.extend_from_slice(&[1, 3, 0, 5, 0, 0, 0, 0x10]);
    let s = run_stats(&v);
    assert_eq!(s.counts.delivered, 1);
    assert_eq!(s.multi_frame_deliveries, 1);
    // The same transfer, then transfer 6 without its first fragment (loss mask bit 0):
    // its two tail fragments are dropped (out of order: no transfer in progress).
    v.extend_from_slice(&[1, 3, 0, 6, 0, 1, 1, 0, 0, 0, 0, 0x20]);
    let s = run_stats(&v);
    assert_eq!(s.counts.delivered, 1);
    assert_eq!(s.counts.out_of_order, 2);
}

#[test]
fn heartbeats_and_syncs_reach_the_model() {
    let mut v = header(4);
    // op 5: heartbeat of module 7, this robot's fingerprint, state 3.
    v.extend_from_slice(&[1, 5, 7, 0, 3]);
    // op 5: heartbeat with a wrong format (how & 2): laxity 1, fragment 0, DLC 5.
    v.extend_from_slice(&[1, 5, 7, 2, 3, 1, 0, 5]);
    // op 4: a sync with DLC 8 on a 40-slot bus (how & 0x80: raw DLC 8).
    v.extend_from_slice(&[1, 4, 3, 0]);
    v.extend_from_slice(&[0xFF; 8]);
    v.push(0x86); // raw: DLC 0x86 % 9 = 8
    let s = run_stats(&v);
    assert_eq!(s.heartbeats, 1);
    assert_eq!(s.counts.bad_heartbeat, 1);
    assert_eq!(s.counts.bad_sync, 1);
}

#[test]
fn a_span_outside_the_input_or_inside_a_character_is_a_finding() {
    use rtcan_model::{Code, Diagnostic};
    let text = "a = \"é\"\n";
    let at = |span: std::ops::Range<usize>| {
        let d = [Diagnostic::new(Code::BadValue, Some(span), "x")];
        std::panic::catch_unwind(|| rtcan_fuzz::robot_toml::assert_spans_inside(text, &d)).is_ok()
    };
    assert!(at(0..text.len()));
    assert!(at(5..7), "the whole `é`");
    assert!(!at(5..6), "inside `é`");
    assert!(!at(0..text.len() + 1));
    assert!(!at(3..2));
}
