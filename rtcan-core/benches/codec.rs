//! Wire codec costs on the host: what the engine spends per frame in its ISR paths.
//! `cargo bench -p rtcan-core --bench codec -- --warm-up-time 1 --measurement-time 2`
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use rtcan_core::fragment::{
    fragment_count, fragment_data, fragment_field, wire_len, RxState, RxStep, MAX_PAYLOAD,
};
use rtcan_core::id::{CanId, MsgId};
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::timing::exact_bits;
use rtcan_core::Frame;

fn frames(payload: &[u8]) -> Vec<Frame> {
    let count = fragment_count(payload.len());
    (0..count)
        .rev()
        .map(|c| {
            let mut out = [0; 8];
            let dlc = fragment_data(payload, c, &mut out);
            let field = fragment_field(count, 3, c);
            Frame::from_parts(CanId::new(9, MsgId(0x0150), field).unwrap(), dlc, out).unwrap()
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    c.bench_function("id_encode", |b| {
        b.iter(|| CanId::new(black_box(17), black_box(MsgId(0x0141)), black_box(3)))
    });

    let log = LaxityEncoding::Log { unit_ns: 10_000 };
    let lin = LaxityEncoding::Linear { unit_ns: 100_000 };
    c.bench_function("laxity_encode_log", |b| {
        b.iter(|| log.encode(black_box(3_456_789)))
    });
    c.bench_function("laxity_encode_linear", |b| {
        b.iter(|| lin.encode(black_box(3_456_789)))
    });

    let f8 = Frame::new(
        CanId::new(9, MsgId(0x0150), 0).unwrap(),
        &[0x55, 0, 0xFF, 0x12, 0x34, 0, 0, 7],
    )
    .unwrap();
    c.bench_function("exact_bits_dlc8", |b| b.iter(|| exact_bits(black_box(&f8))));

    // Single-frame message: one step completes it (no CRC).
    let single = frames(&[1, 2, 3, 4, 5, 6, 7, 8]);
    let mut buf8 = [0u8; 8];
    c.bench_function("rx_step_single_frame", |b| {
        b.iter(|| {
            let mut rx = RxState::default();
            matches!(
                rx.step(&mut buf8, 8, black_box(&single[0]), 0),
                RxStep::Complete(..)
            )
        })
    });

    // Middle fragment of a 20-byte message: copy 8 bytes, no CRC.
    let p20: Vec<u8> = (0..20).collect();
    let f20 = frames(&p20);
    let mut buf20 = [0u8; 22];
    let mut pre = RxState::default();
    pre.step(&mut buf20, 20, &f20[0], 0);
    let mut check = pre;
    assert_eq!(
        check.step(&mut buf20.clone(), 20, &f20[1], 0),
        RxStep::Pending
    );
    c.bench_function("rx_step_middle_fragment", |b| {
        b.iter(|| {
            let mut rx = pre;
            matches!(
                rx.step(&mut buf20, 20, black_box(&f20[1]), 0),
                RxStep::Pending
            )
        })
    });

    // Last fragment of the largest message (no transfer CRC: the same cost as any).
    let pmax: Vec<u8> = (0..MAX_PAYLOAD).map(|i| i as u8).collect();
    let fmax = frames(&pmax);
    let mut bufmax = vec![0u8; wire_len(MAX_PAYLOAD)];
    let mut pre = RxState::default();
    for f in &fmax[..fmax.len() - 1] {
        pre.step(&mut bufmax, MAX_PAYLOAD, f, 0);
    }
    let last = *fmax.last().unwrap();
    // The measured paths are the intended ones.
    let mut check = pre;
    assert!(matches!(
        check.step(&mut bufmax.clone(), MAX_PAYLOAD, &last, 0),
        RxStep::Complete(..)
    ));
    c.bench_function("rx_step_last_fragment_256B", |b| {
        b.iter(|| {
            let mut rx = pre;
            matches!(
                rx.step(&mut bufmax, MAX_PAYLOAD, black_box(&last), 0),
                RxStep::Complete(..)
            )
        })
    });

    let mut out = [0u8; 8];
    c.bench_function("tx_fragment_data", |b| {
        b.iter(|| fragment_data(black_box(&p20), black_box(1), &mut out))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
