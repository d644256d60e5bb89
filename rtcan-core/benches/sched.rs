//! Scheduling benches: admission of 200 HRT topics on a 64-slot cycle (target < 100 ms),
//! the paper's 9-message set, and EDF queue push + pop at N = 16.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use rtcan_core::admission::{admit, build_masks, HrtRequest, Placement};
use rtcan_core::queue::EdfQueue;

fn req(period_slots: u32, fragments: u8) -> HrtRequest {
    HrtRequest {
        period_slots,
        fragments,
    }
}

/// 200 harmonic topics (periods 64..512 slots, 1-2 frames) filling 476 of the 504
/// non-sync slots of the 512-slot hyperperiod (94 %).
fn harmonic_200() -> Vec<HrtRequest> {
    (0..200u32)
        .map(|i| match i {
            0..8 => req(64, 2),
            8..24 => req(128, 1),
            24..64 => req(256, 1),
            _ => req(512, 1 + (i % 2) as u8),
        })
        .collect()
}

fn admission(c: &mut Criterion) {
    let reqs = harmonic_200();
    let mut pl = vec![Placement::default(); reqs.len()];
    let stats = admit(64, &reqs, &mut pl, u64::MAX).unwrap();
    eprintln!("harmonic_200: {stats:?}");
    c.bench_function("admit 64 slots x 200 HRT", |b| {
        b.iter(|| admit(64, black_box(&reqs), &mut pl, u64::MAX).unwrap())
    });
    let mut masks = [0u64; 8];
    c.bench_function("build_masks 64 slots x 200 HRT", |b| {
        b.iter(|| build_masks(64, black_box(&reqs), &pl, &mut masks).unwrap())
    });
    let paper: Vec<HrtRequest> = [req(6, 1), req(30, 1), req(60, 1)]
        .iter()
        .cycle()
        .take(9)
        .copied()
        .collect();
    let mut pl9 = [Placement::default(); 9];
    c.bench_function("admit paper set (60 slots x 9 HRT)", |b| {
        b.iter(|| admit(60, black_box(&paper), &mut pl9, u64::MAX).unwrap())
    });
}

fn edf(c: &mut Criterion) {
    // Keys from a fixed pseudo-random sequence; the queue is kept half full so pushes
    // and pops both sift through a few levels.
    let keys: Vec<u64> = (0..1024u64).map(|i| (i * 2_654_435_761) % 1000).collect();
    let mut q: EdfQueue<u32, 16> = EdfQueue::new();
    for (i, &k) in keys.iter().take(8).enumerate() {
        q.push(k, i as u32).unwrap();
    }
    let mut i = 0usize;
    c.bench_function("EdfQueue<u32, 16> push+pop", |b| {
        b.iter(|| {
            i = (i + 1) % keys.len();
            q.push(black_box(keys[i]), i as u32).unwrap();
            black_box(q.pop())
        })
    });
}

criterion_group!(benches, admission, edf);
criterion_main!(benches);
