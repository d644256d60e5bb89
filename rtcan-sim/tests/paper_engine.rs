//! The RTCAN paper's benchmark on the real engine: HRT isolation under SRT load.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]
use rtcan_core::engine::Policy;
use rtcan_sim::paper;
use rtcan_sim::policy::PolicyKind;
use rtcan_sim::run::{run_engine, SimConfig};

#[test]
fn paper_hrt_never_misses_and_never_overlaps() {
    let cfg = SimConfig {
        seconds: 0.5,
        ..SimConfig::default()
    };
    let sc = paper::scenario(paper::our_laxity(), 1.0).unwrap();
    let run = run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS).unwrap();
    for h in &run.figures.hrt {
        eprintln!(
            "{} count {} misses {} mean {:.1} std {:.2} jit {}..{}",
            h.name,
            h.count,
            h.misses,
            h.mean_period_ns,
            h.std_period_ns,
            h.jitter_min_ns,
            h.jitter_max_ns
        );
    }
    for s in &run.figures.srt {
        eprintln!(
            "{} count {} miss {:.3} mean {:.0} p95 {} max {}",
            s.name,
            s.count,
            s.miss_ratio(),
            s.mean_ns(),
            s.percentile_ns(95.0),
            s.max_ns()
        );
    }
    eprintln!(
        "{:?}\n{:?}\noverlaps {} rx_ok {} rx_bad {} unknown {}",
        run.figures.load,
        run.counters,
        run.overlaps,
        run.rx_ok,
        run.rx_bad,
        run.figures.unknown_frames
    );
    assert_eq!(run.overlaps, 0);
    assert_eq!(run.figures.hrt.len(), 9);
    for h in &run.figures.hrt {
        assert_eq!(h.misses, 0, "{}", h.name);
        assert!(h.count > 0);
    }
    assert_eq!(run.rx_bad, 0);
    assert!(run.rx_ok > 0);
}

#[test]
fn four_policies_on_one_trace() {
    let cfg = SimConfig {
        seconds: 1.0,
        ..SimConfig::default()
    };
    let c = rtcan_sim::compare::paper_comparison(&cfg).unwrap();
    eprintln!("{}", rtcan_sim::report::comparison_text(&c));
    for r in &c.runs {
        eprintln!("{}", rtcan_sim::report::text(r));
    }
    // Same events for every policy.
    let counts: Vec<Vec<u64>> = c
        .runs
        .iter()
        .map(|r| r.figures.srt.iter().map(|s| s.count).collect())
        .collect();
    assert!(counts.iter().all(|k| *k == counts[0]), "{counts:?}");
    // TDMA policies keep isolation; plain CAN cannot (its HRT frames miss or jitter).
    for r in &c.runs[..3] {
        assert_eq!(r.overlaps, 0, "{}", r.policy);
        assert!(r.figures.hrt.iter().all(|h| h.misses == 0), "{}", r.policy);
    }
    // Overload handling (drop hopeless, fit window ends) delivers more on time than the
    // paper's policy on the same trace; the omniscient EDF is within a few percent.
    let on_time = |i: usize| rtcan_sim::compare::on_time(&c.runs[i]);
    assert!(
        on_time(1) > on_time(0),
        "ours {} paper {}",
        on_time(1),
        on_time(0)
    );
    assert!(on_time(2) as f64 >= 0.97 * on_time(1) as f64);
    // Without TDMA the HRT messages miss periods.
    assert!(c.runs[3].figures.hrt.iter().map(|h| h.misses).sum::<u64>() > 0);
    assert!(
        c.offered_fraction > 1.0,
        "the paper's load does not fit its free windows"
    );
}
