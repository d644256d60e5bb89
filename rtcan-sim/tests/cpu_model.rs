//! The simulator's CPU model (issue 10): with the prioritised design the Triskar2 robot
//! and the paper's benchmark keep HRT without misses or slot overlaps and the slot
//! timer's TXRQ latency is its path alone; the single-priority design breaks temporal
//! isolation on the same runs; with the model off nothing changes.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan_model::costs::Design;
use rtcan_sim::cpu::Cost;
use rtcan_sim::cpu_compare::{before_after, Row};
use std::path::PathBuf;

fn rows(cpis: &[f64], cost: Cost) -> Vec<Row> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../robot.toml");
    let plan = rtcan_model::Robot::load(path).unwrap();
    before_after(&plan, 2.0, 2.0, cpis, cost).unwrap()
}

fn find<'a>(rows: &'a [Row], scenario: &str, design: &str, cpi: f64) -> &'a Row {
    rows.iter()
        .find(|r| r.scenario == scenario && r.design == design && r.cpi == cpi)
        .unwrap()
}

#[test]
fn prioritised_design_keeps_hrt_and_single_priority_breaks_it() {
    // Every path at its mean, and at its max (a stress bound: every activation the
    // longest), over CPI 1.0 ... 2.0 (the 20 s runs: `cpu_before_after`, which fails on
    // any HRT miss, overlap after warm-up or overrun of the prioritised design).
    check(&[1.0, 2.0], Cost::Mean);
    check(&[1.0, 2.0], Cost::Max);
}

fn check(cpis: &[f64], cost: Cost) {
    let rows = rows(cpis, cost);
    assert_eq!(rows.len(), 2 * (1 + 2 * cpis.len()));
    for scenario in ["triskar2", "rtcan-paper"] {
        for r in rows.iter().filter(|r| r.scenario == scenario) {
            assert_eq!(r.overlaps_recomputed, r.overlaps, "{r:?}");
        }
        let off = find(&rows, scenario, "off", 0.0);
        assert_eq!(
            (off.txrq_max_ns, off.cpu_load),
            (0, 0.0),
            "no model, no CPU figures"
        );
        for &cpi in cpis {
            let new = find(&rows, scenario, "prioritised", cpi);
            assert_eq!(new.hrt_misses, 0, "{new:?}");
            // After the warm-up none; before it, a slave whose second sync is processed
            // after slot 1's boundary loads that slot's HRT frame late (engine: a
            // boundary handled late but before its successor still loads; README "Not
            // done"). Bounded by the startup: at most one frame per module.
            assert_eq!(new.overlaps_after_warmup, 0, "{new:?}");
            assert!(new.overlaps <= 5, "{new:?}");
            assert_eq!(new.rx_overruns, 0, "{new:?}");
            // The timer is the top priority: its TXRQ comes after exception entry and its
            // path (min(path to TXRQ, isr_slot_timer)), plus at most what runs at its
            // priority when it fires: the protocol task's critical section, or the rest of
            // an earlier timer activation (a compare that fired early, before a sync
            // correction moved the boundary, re-arms: docs/SIM.md). The 99th percentile
            // stays within the timing check's worst case (12 + slot_boundary_to_txrq.max
            // * CPI cycles).
            let t = Design::Prioritised.table().unwrap();
            let fig = |p: &str| match cost {
                Cost::Max => t.path(p).max,
                Cost::Mean => t.path(p).mean,
            };
            let ns = |instr: u32| ((12.0 + f64::from(instr) * cpi) * 1e9 / 72e6_f64).ceil() as u64;
            let txrq = t.path("slot_boundary_to_txrq");
            let cs = fig("critical_section_slot");
            let path = match cost {
                Cost::Max => txrq.max - cs,
                Cost::Mean => txrq.mean,
            }
            .min(fig("isr_slot_timer"));
            let timer_rest = fig("isr_slot_timer") - path;
            assert!(new.txrq_p99_ns >= ns(path), "{new:?}");
            assert!(new.txrq_max_ns <= ns(path + cs.max(timer_rest)), "{new:?}");
            assert!(
                new.txrq_p99_ns <= ns(txrq.max),
                "within the check's bound: {new:?}"
            );
            // HRT jitter never exceeds the largest latency (a window-close wake-up just
            // before a boundary can load the frame up to one latency early).
            assert!(new.jitter_ns as u64 <= new.txrq_max_ns, "{new:?}");
            assert!(new.cpu_load > 0.0 && new.cpu_load < 1.0, "{new:?}");
            let old = find(&rows, scenario, "single-priority", cpi);
            assert!(old.overlaps_after_warmup > 100, "{old:?}");
            assert!(old.txrq_max_ns > 50_000, "{old:?}");
            assert!(old.jitter_ns > 50_000, "{old:?}");
            assert!(old.cpu_load > 0.05, "{old:?}");
        }
        // At CPI 1.0 the jitter is within the RTCAN paper's ±3 µs hardware figure.
        for &cpi in cpis {
            assert!(find(&rows, scenario, "prioritised", cpi).jitter_ns <= 3_000);
        }
    }
}
