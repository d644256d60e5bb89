//! What a run of the emulated robot shows: bus load, per-identifier counts and period
//! jitter, per-module instructions, unknown register accesses and decoded defmt lines.
use crate::bus::Bus;
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// Per-identifier statistics of the bus log: count, mean period and the largest
/// deviation of one period from the mean (µs, at 1 bit = `bit_ps`).
pub fn id_stats(bus: &Bus) -> BTreeMap<u32, (usize, f64, f64)> {
    let mut sofs: BTreeMap<u32, Vec<u64>> = BTreeMap::new();
    for (_, f, sof) in &bus.log {
        sofs.entry(f.id).or_default().push(*sof);
    }
    let us_per_bit = bus.bit_ps as f64 / 1e6;
    sofs.into_iter()
        .map(|(id, s)| {
            let periods: Vec<f64> = s
                .windows(2)
                .map(|w| match w {
                    [a, b] => (b - a) as f64 * us_per_bit,
                    _ => 0.0,
                })
                .collect();
            let mean = if periods.is_empty() {
                0.0
            } else {
                periods.iter().sum::<f64>() / periods.len() as f64
            };
            let jitter = periods.iter().map(|p| (p - mean).abs()).fold(0.0, f64::max);
            (id, (s.len(), mean, jitter))
        })
        .collect()
}

/// Fraction of bus time occupied by frames and error frames (intermissions included, as
/// rtcan-sim's bus counts it) up to bit `bits`.
pub fn bus_load(bus: &Bus, bits: u64) -> f64 {
    let busy_bits = bus.sim.stats.busy_ns / (bus.bit_ps / 1_000).max(1);
    busy_bits as f64 / bits.max(1) as f64
}

/// The report as JSON; `logs` are the decoded defmt lines per module.
pub fn json(bus: &Bus, seconds: f64, cpu_seconds: f64, logs: &[Vec<String>]) -> Value {
    let bits = (seconds * 1e12) as u64 / bus.bit_ps.max(1);
    let modules: Vec<Value> = bus
        .mcus
        .iter()
        .enumerate()
        .map(|(i, m)| {
            json!({
                "module": m.name,
                "frames_sent": bus.log.iter().filter(|(n, _, _)| *n == i).count(),
                "instructions": m.st.instructions,
                "unknown_accesses": m.st.unknown.iter().map(|u| json!({
                    "addr": format!("{:#010x}", u.addr), "pc": format!("{:#010x}", u.pc),
                    "write": u.write, "time_us": u.time_ps / 1_000_000 })).collect::<Vec<_>>(),
                "tec": m.st.can.tec,
                "runs": runs_json(&m.st.slices),
                "log": logs.get(i).cloned().unwrap_or_default(),
            })
        })
        .collect();
    let ids: Vec<Value> = id_stats(bus)
        .into_iter()
        .map(|(id, (n, mean, jit))| json!({"id": format!("{id:#x}"), "frames": n, "mean_period_us": mean, "max_period_deviation_us": jit}))
        .collect();
    json!({
        "seconds": seconds,
        "speed_x_real_time": if cpu_seconds > 0.0 { seconds / cpu_seconds } else { 0.0 },
        "bus_load": bus_load(bus, bits),
        "frames": bus.log.len(),
        "modules": modules,
        "ids": ids,
    })
}

/// Unicorn runs of one MCU by what ended them (docs/EMULATOR.md, "Figures": the cost of
/// the emulation is mostly in starting and ending runs).
fn runs_json(s: &crate::mcu::Slices) -> Value {
    json!({
        "total": s.event + s.until + s.chunk + s.unmask + s.replan + s.sleep + s.exc_return + s.other,
        "event": s.event, "until": s.until, "chunk": s.chunk, "unmask": s.unmask,
        "replan": s.replan, "sleep": s.sleep, "exc_return": s.exc_return, "other": s.other,
        "returns_in_run": s.returns_in_run,
        "entries_in_run": s.entries_in_run,
        // Runs that ended past their planned instruction (at the next block boundary),
        // and by how many instructions: the emulator's own event latency (mcu::on_block).
        "late": {
            "runs": s.late,
            "mean_instructions": if s.late == 0 { 0.0 } else { s.late_sum as f64 / s.late as f64 },
            "max_instructions": s.late_max,
        },
    })
}
