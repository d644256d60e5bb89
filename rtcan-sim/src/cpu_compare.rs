//! The before/after table of issue 10: the Triskar2 robot and the RTCAN paper's
//! benchmark run with the CPU model off, with the prioritised design and with the
//! single-priority design at several CPIs (`cargo run --release -p rtcan-sim --example
//! cpu_before_after`; the README and docs/SIM.md quote its output).
use std::fmt::Write as _;

use rtcan_core::engine::Policy;
use rtcan_model::costs::Design;
use rtcan_model::Plan;

use rtcan_core::tables::BusConfig;

use crate::bus::WireFrame;
use crate::cpu::{Cost, CpuModel};
use crate::policy::PolicyKind;
use crate::run::{run_engine, Run, SimConfig};
use crate::slots::overlaps;
use crate::traffic::WARMUP_NS;
use crate::triskar::{self, TriskarConfig};

/// One scenario under one CPU model.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// `triskar2` or `rtcan-paper`.
    pub scenario: &'static str,
    /// `off`, or the design name.
    pub design: &'static str,
    /// CPI (0 with the model off).
    pub cpi: f64,
    /// HRT misses over every HRT message.
    pub hrt_misses: u64,
    /// Frames breaking temporal isolation.
    pub overlaps: u64,
    /// The same recomputed from the wire log (equal to `overlaps`: checks the mapping).
    pub overlaps_recomputed: u64,
    /// Of them, frames starting after the warm-up (`WARMUP_NS`: the first syncs, locks).
    pub overlaps_after_warmup: u64,
    /// Largest |HRT period jitter|, ns.
    pub jitter_ns: i64,
    /// Largest slot timer → TXRQ latency of any module, ns (0 with the model off).
    pub txrq_max_ns: u64,
    /// Largest per-module 99th percentile of it, ns.
    pub txrq_p99_ns: u64,
    /// Largest per-module CPU load (0..=1).
    pub cpu_load: f64,
    /// Receive FIFO overruns over every module.
    pub rx_overruns: u64,
}

/// Frames of `wire` breaking temporal isolation, in the master's bus time (node 0, ideal
/// clock, engine started at time 0: cycle 0 starts one slot later, `Engine::new`).
fn overlaps_of(wire: &[WireFrame], bus: &BusConfig, masks: &[u64]) -> u64 {
    let slot = bus.slot_ns;
    overlaps(wire, bus, masks, |g| g.checked_sub(slot))
}

fn row(
    scenario: &'static str,
    design: &'static str,
    cpi: f64,
    run: &Run,
    bus: &BusConfig,
    masks: &[u64],
) -> Row {
    let f = &run.figures;
    let steady: Vec<WireFrame> = run
        .wire
        .iter()
        .filter(|w| w.sof >= WARMUP_NS)
        .copied()
        .collect();
    Row {
        scenario,
        design,
        cpi,
        hrt_misses: f.hrt.iter().map(|h| h.misses).sum(),
        overlaps: run.overlaps,
        overlaps_recomputed: overlaps_of(&run.wire, bus, masks),
        overlaps_after_warmup: overlaps_of(&steady, bus, masks),
        jitter_ns: f
            .hrt
            .iter()
            .map(|h| h.jitter_min_ns.abs().max(h.jitter_max_ns.abs()))
            .max()
            .unwrap_or(0),
        txrq_max_ns: run
            .cpu
            .modules
            .iter()
            .map(|m| m.txrq_max_ns)
            .max()
            .unwrap_or(0),
        txrq_p99_ns: run
            .cpu
            .modules
            .iter()
            .map(|m| m.txrq_p99_ns)
            .max()
            .unwrap_or(0),
        cpu_load: run.cpu.modules.iter().map(|m| m.load).fold(0.0, f64::max),
        rx_overruns: run.counters.iter().map(|c| u64::from(c.rx_overrun)).sum(),
    }
}

/// A column of the table: design name (`off`), CPI, the model.
pub type Model = (&'static str, f64, Option<CpuModel>);

/// The CPU models of the table: off, prioritised at each of `cpis`, single-priority at
/// each of `cpis`.
pub fn models(cpis: &[f64], cost: Cost) -> Result<Vec<Model>, String> {
    let mut v = vec![("off", 0.0, None)];
    for d in Design::ALL {
        for &c in cpis {
            v.push((d.name(), c, Some(CpuModel::new(d, c)?.with_cost(cost))));
        }
    }
    Ok(v)
}

/// Runs the Triskar2 robot (`plan` = the workspace robot.toml) for `triskar_s` and the
/// paper's benchmark (our policy) for `paper_s` simulated seconds under every model,
/// each activation charged its path's `cost` figure.
pub fn before_after(
    plan: &Plan,
    triskar_s: f64,
    paper_s: f64,
    cpis: &[f64],
    cost: Cost,
) -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    let tables = plan
        .tables(plan.bus.master)
        .ok_or("robot without a master")?;
    for (design, cpi, cpu) in models(cpis, cost)? {
        let cfg = TriskarConfig {
            sim: SimConfig {
                seconds: triskar_s,
                cpu: cpu.clone(),
                record_wire: true,
                ..SimConfig::default()
            },
            ..TriskarConfig::default()
        };
        let r = triskar::run(plan, &cfg)?;
        rows.push(row(
            "triskar2",
            design,
            cpi,
            &r.run,
            &tables.bus,
            &plan.master_masks,
        ));
        let cfg = SimConfig {
            seconds: paper_s,
            cpu,
            ..SimConfig::default()
        };
        let sc = crate::paper::scenario(crate::paper::our_laxity(), cfg.load)?;
        let run = run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS)?;
        let bus = sc.bus().ok_or("paper scenario without tables")?;
        rows.push(row("rtcan-paper", design, cpi, &run, &bus, sc.masks()));
    }
    rows.sort_by(|a, b| a.scenario.cmp(b.scenario).reverse());
    Ok(rows)
}

/// The table in Markdown.
pub fn markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "| scenario | CPU model | CPI | HRT misses | slot overlaps (after 30 ms warm-up) | HRT jitter max [µs] | slot→TXRQ max / p99 [µs] | CPU load max | RX overruns |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let model_off = r.design == "off";
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} ({}) | ±{:.3} | {} | {} | {} |",
            r.scenario,
            if model_off {
                "off (zero-time handlers, 2 µs IRQ latency)"
            } else {
                r.design
            },
            if model_off {
                "–".to_string()
            } else {
                format!("{:.2}", r.cpi)
            },
            r.hrt_misses,
            r.overlaps,
            r.overlaps_after_warmup,
            r.jitter_ns as f64 / 1e3,
            if model_off {
                "–".to_string()
            } else {
                format!(
                    "{:.3} / {:.3}",
                    r.txrq_max_ns as f64 / 1e3,
                    r.txrq_p99_ns as f64 / 1e3
                )
            },
            if model_off {
                "–".to_string()
            } else {
                format!("{:.1} %", 100.0 * r.cpu_load)
            },
            r.rx_overruns
        );
    }
    s
}
