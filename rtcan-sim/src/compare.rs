//! The four policies side by side on one event trace, and the load sweep.
use rtcan_core::engine::Policy;

use crate::ideal::{offered_ns, window_capacity};
use crate::paper;
use crate::policy::PolicyKind;
use crate::run::{run_engine, run_fixed, run_ideal, window, Run, SimConfig};

/// One load point: every policy on the same trace.
#[derive(Clone, Debug, Default)]
pub struct Comparison {
    /// SRT rate scale.
    pub load: f64,
    /// Offered SRT bus time / usable free-window time (bit-exact).
    pub offered_fraction: f64,
    /// Usable free-window time as a fraction of the bus.
    pub window_fraction: f64,
    /// Runs in `PolicyKind::ALL` order.
    pub runs: Vec<Run>,
}

/// Runs the paper's benchmark at `cfg.load` under all four policies. The event trace
/// depends only on the seed and the load, so every policy sees the same events.
pub fn paper_comparison(cfg: &SimConfig) -> Result<Comparison, String> {
    let ours_sc = paper::scenario(paper::our_laxity(), cfg.load)?;
    let paper_sc = paper::scenario(paper::PAPER_LAXITY, cfg.load)?;
    // The wire log file, when asked for, is the `ours` run's.
    let others = SimConfig {
        wire_log: None,
        ..cfg.clone()
    };
    let a = run_engine(&paper_sc, &others, PolicyKind::Paper, Policy::PAPER)?;
    let b = run_engine(&ours_sc, cfg, PolicyKind::Ours, Policy::OURS)?;
    let c = run_ideal(&ours_sc, &others, &b);
    let d = run_fixed(&ours_sc, &others)?;
    let w = window(cfg);
    let (usable, hyper) = window_capacity(&ours_sc);
    let span = w.to.saturating_sub(w.from);
    let cap = usable as f64 * span as f64 / hyper.max(1) as f64;
    let offered = offered_ns(&ours_sc, cfg.seed, w.from, w.to) as f64;
    Ok(Comparison {
        load: cfg.load,
        offered_fraction: if cap > 0.0 { offered / cap } else { 0.0 },
        window_fraction: usable as f64 / hyper.max(1) as f64,
        runs: vec![a, b, c, d],
    })
}

/// On-time SRT deliveries of a run (events − misses over every class).
pub fn on_time(run: &Run) -> u64 {
    run.figures.srt.iter().map(|s| s.count - s.misses).sum()
}

/// Overall SRT miss ratio of a run.
pub fn miss_ratio(run: &Run) -> f64 {
    let (c, m) = run
        .figures
        .srt
        .iter()
        .fold((0, 0), |(c, m), s| (c + s.count, m + s.misses));
    if c == 0 {
        0.0
    } else {
        m as f64 / c as f64
    }
}

/// Mean latency of delivered SRT messages over every class, ns.
pub fn mean_latency_ns(run: &Run) -> f64 {
    let (sum, n) = run.figures.srt.iter().fold((0u128, 0u64), |(s, n), c| {
        (s + c.latency.sum, n + c.latency.n)
    });
    if n == 0 {
        0.0
    } else {
        sum as f64 / n as f64
    }
}

/// The sweep: loads 0.5, 0.6, …, 1.2 of the scenario's SRT rates; `progress` is told
/// each finished point.
pub fn paper_sweep(
    cfg: &SimConfig,
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<Comparison>, String> {
    let loads: Vec<f64> = (5..=12).map(|k| k as f64 / 10.0).collect();
    let mut out = Vec::new();
    for (i, &load) in loads.iter().enumerate() {
        let c = SimConfig {
            load,
            record_wire: false,
            wire_log: None,
            ..cfg.clone()
        };
        out.push(paper_comparison(&c)?);
        progress(i + 1, loads.len());
    }
    Ok(out)
}

/// Policy order of `Comparison::runs`.
pub const ORDER: [PolicyKind; 4] = PolicyKind::ALL;
