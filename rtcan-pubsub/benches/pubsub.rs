//! Local publish → delivered to 1, 2, 4, 8 subscribers (alloc + fill + publish; the
//! subscribers' take/release is measured separately so the publish path stands alone).
//! `CARGO_TARGET_DIR=/work/tgt/pubsub cargo bench -p rtcan-pubsub --bench pubsub`
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use rtcan_pubsub::bench::{bench_drain, bench_publish_local};
use rtcan_pubsub::{Remote, Topic, TopicCells};
use std::hint::black_box;

fn publish<const N: usize, const S: usize>(c: &mut Criterion, group: &str) {
    let topic: &'static Topic<u32, N, S, 2> = Box::leak(Box::new(Topic::new(
        Box::leak(Box::new(TopicCells::new())),
        Remote::None,
        None,
    )));
    let mut g = c.benchmark_group(group);
    g.bench_function(BenchmarkId::new("publish", S), |b| {
        let mut v = 0u32;
        b.iter(|| {
            v = v.wrapping_add(1);
            // The queues stay full after the first rounds: every publish then also drops
            // each subscriber's oldest message (the slow-subscriber path).
            black_box(bench_publish_local(topic, black_box(v), 0))
        })
    });
    g.bench_function(BenchmarkId::new("publish+recv", S), |b| {
        let mut v = 0u32;
        b.iter(|| {
            v = v.wrapping_add(1);
            let ok = bench_publish_local(topic, black_box(v), 0);
            black_box((ok, bench_drain(topic)))
        })
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    // Drain first so `publish+recv` starts from empty queues.
    publish::<4, 1>(c, "local");
    publish::<7, 2>(c, "local");
    publish::<13, 4>(c, "local");
    publish::<25, 8>(c, "local");
}

criterion_group!(pubsub, benches);
criterion_main!(pubsub);
