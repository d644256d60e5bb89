//! The build-time timing check (issue 10): the reference robots pass with the
//! prioritised design's cost table, fail with the single-priority design's, and a guard
//! too short for the slot timer path is rejected with the exact error.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan_model::costs::{CostTable, Design};
use rtcan_model::timing::{self, MAX_CPU_LOAD};
use rtcan_model::{analyze, report, Analysis, Code, Diagnostic, Diagnostics, Status};
use std::path::PathBuf;

fn read(rel: &str) -> String {
    std::fs::read_to_string(
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join(rel),
    )
    .unwrap()
}

fn load(rel: &str) -> Analysis {
    analyze(rel, &read(rel))
}

/// Worst-case latency of a module without blocking or interference: exception entry plus
/// the table's `slot_boundary_to_txrq`, at 72 MHz, in whole ns rounded up.
fn path_ns(t: &CostTable) -> u64 {
    let cycles = f64::from(t.irq_entry_cycles) + t.cycles(t.path("slot_boundary_to_txrq").max);
    (cycles * 1e9 / 72e6).ceil() as u64
}

fn us(ns: u64) -> String {
    rtcan_model::units::fmt_ns(ns as f64)
}

/// Diagnostics the check gives `rel` with `table` for every module.
fn check_with(rel: &str, table: &CostTable) -> Vec<Diagnostic> {
    let a = load(rel);
    let (model, plan) = (a.model.unwrap(), a.plan.unwrap());
    let t = timing::analyze(&plan, Some(table)).unwrap();
    let mut d = Vec::new();
    timing::diagnose(&model, &plan, &t, Some(table), &mut d);
    d
}

#[test]
fn reference_robots_pass_with_the_prioritised_design() {
    let new = Design::Prioritised.table().unwrap();
    for rel in [
        "robot.toml",
        "robots/rtcan-paper.toml",
        "robots/accept-all.toml",
        "robots/qemu-test.toml",
    ] {
        let a = load(rel);
        assert_eq!(a.status(), Status::Admissible, "{rel}");
        let plan = a.plan.unwrap();
        let t = timing::analyze(&plan, Some(&new)).unwrap();
        assert_eq!(t.guard_ns, plan.bus.guard_ns);
        assert_eq!(t.modules.len(), plan.modules.len());
        for m in &t.modules {
            assert!(
                m.slot_latency_worst_ns + m.clock_error_ns <= t.guard_ns,
                "{rel} {}: {m:?}",
                m.name
            );
            // The issue's goals: latency <= 3 us, protocol load <= 50 %.
            assert!(m.slot_latency_worst_ns <= 3_000, "{rel} {m:?}");
            assert!(m.cpu_load > 0.0 && m.cpu_load <= 0.5, "{rel} {m:?}");
        }
    }
}

#[test]
fn prioritised_latency_is_entry_plus_the_txrq_path_exactly() {
    // The slot timer alone at the top priority: no blocking, no interference, so the
    // latency is (12 + slot_boundary_to_txrq * 1.25) cycles at 72 MHz, rounded up.
    let new = Design::Prioritised.table().unwrap();
    assert_eq!(new.cpi, 1.25);
    assert_eq!(new.irq_entry_cycles, 12);
    let plan = load("robot.toml").plan.unwrap();
    let t = timing::analyze(&plan, Some(&new)).unwrap();
    let gw = &t.modules[0];
    assert_eq!(gw.name, "gateway");
    assert_eq!(gw.slot_latency_worst_ns, path_ns(&new));
    assert_eq!(gw.blocking_cycles, 0.0);
    assert_eq!(gw.interference_cycles, 0.0);
    assert_eq!(gw.clock_error_ns, 0, "the master defines bus time");
    let m1 = &t.modules[1];
    assert_eq!(m1.slot_latency_worst_ns, path_ns(&new));
    assert_eq!(m1.clock_error_ns, 2_000, "two bit times at 1 Mbit/s");
    // motor1 accepts the sync (8 B), heartbeats (5 B) and velocity (Twist, 12 B: last
    // fragment 4 B, no transfer CRC since PROTOCOL §7.4): the shortest is velocity's last
    // fragment, 54 + 32 + 13 = 99 bits.
    assert_eq!(m1.rx_frame_min_ns, 99_000);
    // Its load: per 99 us frame the RX interrupt and task, per slot the timer and the
    // preparation, per cycle the sync, its frames, SysTick; every activation + 12 cycles.
    let c = |p: &str| new.cycles(new.path(p).max);
    // Frames per 10 ms cycle: heartbeat every cycle (Triskar2 is supervised:
    // `on_missing`), encoder1 (200 Hz, 1 frame), wheel_setpoints (100 Hz, 2 frames), its
    // and at their declared 10 Hz its health (1 frame) and its module table as a backup
    // master (12 frames).
    let tx_per_cycle = 1.0 + 2.0 * 1.0 + 1.0 * 2.0;
    let tx_10hz = 1.0 + 12.0;
    let per_s = (12.0 + c("isr_can_rx") + c("task_rx_process")) / 99e-6
        + (12.0 + c("isr_slot_timer") + c("task_prepare_slot")) / 166_666e-9
        + c("task_sync_slave") / 9_999_960e-9
        + (12.0 + c("isr_can_tx") + c("task_tx_done")) * tx_per_cycle / 9_999_960e-9
        + (12.0 + c("isr_can_tx") + c("task_tx_done")) * tx_10hz * 10.0
        + (12.0 + c("systick")) / 1e-3;
    assert!(
        (m1.cpu_load - per_s / 72e6).abs() < 1e-9,
        "{} vs {}",
        m1.cpu_load,
        per_s / 72e6
    );
}

#[test]
fn single_priority_design_fails_the_reference_robots() {
    let old = Design::SinglePriority.table().unwrap();
    for rel in ["robot.toml", "robots/rtcan-paper.toml"] {
        let d = check_with(rel, &old);
        let plan = load(rel).plan.unwrap();
        let guard: Vec<&Diagnostic> = d.iter().filter(|d| d.code == Code::GuardTooShort).collect();
        let cpu: Vec<&Diagnostic> = d.iter().filter(|d| d.code == Code::CpuOverload).collect();
        assert_eq!(
            guard.len(),
            plan.modules.len(),
            "{rel}: every module misses the guard"
        );
        assert_eq!(
            cpu.len(),
            plan.modules.len(),
            "{rel}: every module overloads"
        );
    }
    let plan = load("robot.toml").plan.unwrap();
    let t = timing::analyze(&plan, Some(&old)).unwrap();
    let gw = &t.modules[0];
    // Blocking: one RX handler at the timer's priority, 12 + 7665 * 1.25 cycles.
    assert_eq!(gw.blocking_cycles, 12.0 + 7665.0 * 1.25);
    // SysTick (above everything) interferes once: 12 + 60 * 1.25 cycles.
    assert_eq!(gw.interference_cycles, 12.0 + 60.0 * 1.25);
    // (12 + 274 * 1.25 + 9593.25 + 87) cycles / 72 MHz = 139.372 us.
    assert_eq!(
        gw.slot_latency_worst_ns,
        ((12.0 + 274.0 * 1.25 + 9593.25 + 87.0) * 1e9 / 72e6_f64).ceil() as u64
    );
    assert!(gw.cpu_load > MAX_CPU_LOAD);
    // The gateway receives odometry (24 B: three full 8-byte fragments) and heartbeats
    // (5 B): 54 + 40 + 13 = 107 bits, the shortest frame it accepts.
    assert_eq!(gw.rx_frame_min_ns, 107_000);
}

#[test]
fn single_priority_error_text_is_exact() {
    let old = Design::SinglePriority.table().unwrap();
    let d = check_with("robot.toml", &old);
    let src = read("robot.toml");
    let rendered = Diagnostics {
        file: "robot.toml".into(),
        source: src,
        items: d.into_iter().take(2).collect(),
    }
    .render();
    assert_eq!(
        rendered,
        r#"error[guard-too-short]: module `gateway`: worst-case latency from a slot boundary to its TXRQ (139.372 us) plus its clock error bound (0 ns) is 139.372 us, more than the guard (5 us)
  --> robot.toml:61:10
   |
61 | [modules.gateway]       # host link (uROSnode); master of the bus
   |          ^^^^^^^
   = help: set `guard = "139.372us"` in `[bus]` and use at most 33 slots per 10 ms cycle (slot >= 160 us frame + guard)
   = note: cost table `single-priority`, CPI 1.25 at 72 MHz; docs/ROBOT_TOML.md "Timing check"

error[cpu-overload]: module `gateway`: protocol CPU load 109% at 100% bus load of the shortest frames its filters accept (107 us each)
  --> robot.toml:61:10
   |
61 | [modules.gateway]       # host link (uROSnode); master of the bus
   |          ^^^^^^^
   = help: lower the bitrate, use fewer slots per cycle, or exact filters (`filters = "exact"`) so that fewer frames reach the CPU
   = note: cost table `single-priority`, CPI 1.25 at 72 MHz; docs/ROBOT_TOML.md "Timing check"

error: 2 errors in robot.toml
"#
    );
}

#[test]
fn a_one_microsecond_guard_is_rejected_by_analyze() {
    let lat = path_ns(&Design::Prioritised.table().unwrap());
    let src = read("robot.toml").replace("guard = \"5us\"", "guard = \"1us\"");
    let a = analyze("robot.toml", &src);
    assert_eq!(a.status(), Status::NotAdmissible);
    assert!(a.plan.is_none(), "check and build must not get a plan");
    let codes: Vec<Code> = a.diagnostics.items.iter().map(|d| d.code).collect();
    assert_eq!(codes, vec![Code::GuardTooShort; 6]);
    let first = &a.diagnostics.items[0];
    assert_eq!(
        first.message,
        format!("module `gateway`: worst-case latency from a slot boundary to its TXRQ ({}) plus its clock error bound (0 ns) is {}, more than the guard (1 us)", us(lat), us(lat))
    );
    assert_eq!(
        first.help,
        vec![format!("set `guard = \"{}\"` in `[bus]` (the 166.666 us slot still holds the 160 us frame plus that guard)", us(lat).replace(' ', ""))]
    );
    // Exactly the bound passes: the slaves need the latency + 2 us.
    let at = |g: u64| read("robot.toml").replace("guard = \"5us\"", &format!("guard = \"{g}ns\""));
    assert_eq!(
        analyze("robot.toml", &at(lat + 2_000)).status(),
        Status::Admissible
    );
    let a = analyze("robot.toml", &at(lat + 1_999));
    assert_eq!(
        a.diagnostics.items.len(),
        5,
        "the five slaves, not the master"
    );
    let a = analyze("robot.toml", &at(lat - 1));
    assert_eq!(a.diagnostics.items.len(), 6, "and the master");
}

#[test]
fn json_has_the_timing_fields_exactly() {
    let v: serde_json::Value =
        serde_json::from_str(&report::json_text(&load("robot.toml"))).unwrap();
    let t = &v["timing"];
    assert_eq!(t["guard_ns"], 5_000);
    let mods = t["modules"].as_array().unwrap();
    assert_eq!(mods.len(), 6);
    for m in mods {
        let mut keys: Vec<&str> = m.as_object().unwrap().keys().map(String::as_str).collect();
        keys.sort_unstable();
        assert_eq!(keys, ["cpu_load", "name", "slot_latency_worst_ns"]);
    }
    let lat = path_ns(&Design::Prioritised.table().unwrap());
    assert_eq!(mods[0]["name"], "gateway");
    assert_eq!(mods[0]["slot_latency_worst_ns"], lat);
    let text = report::text(&load("robot.toml").plan.unwrap());
    assert!(text.contains("\ntiming (guard 5 us;"), "{text}");
    let row = format!(
        "  {:<16} {:>12} {:>12} {:>12}",
        "motor1",
        us(lat),
        "2 us",
        us(5_000 - 2_000 - lat)
    );
    assert!(text.contains(&row), "{row}\n{text}");
}

#[test]
fn latency_grows_with_the_cpi_and_interference_is_counted_per_arrival() {
    let base = Design::Prioritised.table().unwrap();
    let txrq = f64::from(base.path("slot_boundary_to_txrq").max);
    let plan = load("robot.toml").plan.unwrap();
    let at = |t: &CostTable| timing::analyze(&plan, Some(t)).unwrap().modules[0].clone();
    let ns = |cycles: f64| (cycles * 1e9 / 72e6_f64).ceil() as u64;
    assert_eq!(
        at(&base.clone().with_cpi(1.0)).slot_latency_worst_ns,
        ns(12.0 + txrq)
    );
    assert_eq!(
        at(&base.clone().with_cpi(2.0)).slot_latency_worst_ns,
        ns(12.0 + 2.0 * txrq)
    );
    // RX above the timer's priority: it preempts, so it interferes (once: its period,
    // the 83 us odometry fragment, is longer than the latency) instead of never.
    let mut t = base.clone();
    for (name, p) in &mut t.paths {
        if name == "isr_can_rx" {
            p.priority = Some(5);
        }
    }
    let m = at(&t);
    let rx = f64::from(base.path("isr_can_rx").max);
    assert_eq!(m.interference_cycles, 12.0 + rx * 1.25);
    assert_eq!(m.blocking_cycles, 0.0);
    assert_eq!(
        m.slot_latency_worst_ns,
        ns(12.0 + txrq * 1.25 + 12.0 + rx * 1.25)
    );
    // At the timer's own priority it blocks instead: one whole activation.
    for (name, p) in &mut t.paths {
        if name == "isr_can_rx" {
            p.priority = Some(4);
        }
    }
    let m = at(&t);
    assert_eq!(m.blocking_cycles, 12.0 + rx * 1.25);
    assert_eq!(m.interference_cycles, 0.0);
}

#[test]
fn rx_fifo_overrun_when_the_rx_interrupt_outlasts_the_fifo() {
    // Single-priority design on robot.toml's gateway (shortest accepted frame: 107 us, so
    // the 3-frame FIFO lasts 321 us). Its RX interrupt (5168 + 2497 inline) is blocked by
    // the slot timer at the same priority (1725) and preempted once by SysTick (60).
    let plan = load("robot.toml").plan.unwrap();
    let old = Design::SinglePriority.table().unwrap();
    let ns = |cycles: f64| (cycles * 1e9 / 72e6_f64).ceil() as u64;
    for (cpi, overrun) in [(1.25, false), (2.0, false), (2.5, true)] {
        let t = old.clone().with_cpi(cpi);
        let gw = &timing::analyze(&plan, Some(&t)).unwrap().modules[0];
        let r = (12.0 + 7665.0 * cpi) + (12.0 + 1725.0 * cpi) + (12.0 + 60.0 * cpi);
        assert_eq!(gw.rx_response_worst_ns, ns(r), "CPI {cpi}");
        assert_eq!(gw.rx_response_worst_ns > 3 * 107_000, overrun, "CPI {cpi}");
        let a = load("robot.toml");
        let mut d = Vec::new();
        let tm = timing::analyze(&plan, Some(&t)).unwrap();
        timing::diagnose(&a.model.unwrap(), &plan, &tm, Some(&t), &mut d);
        let gw_codes: Vec<Code> = d
            .iter()
            .filter(|d| d.message.starts_with("module `gateway`"))
            .map(|d| d.code)
            .collect();
        let mut want = vec![Code::GuardTooShort];
        if overrun {
            want.push(Code::RxFifoOverrun);
        }
        want.push(Code::CpuOverload);
        assert_eq!(gw_codes, want, "CPI {cpi}");
    }
    // The prioritised design: the RX interrupt is short and only the timer preempts it.
    let new = Design::Prioritised.table().unwrap();
    for cpi in [1.0, 2.0] {
        let tm = timing::analyze(&plan, Some(&new.clone().with_cpi(cpi))).unwrap();
        for m in &tm.modules {
            assert!(m.rx_response_worst_ns < 20_000, "{m:?}");
        }
    }
}
