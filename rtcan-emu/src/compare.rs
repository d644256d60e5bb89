//! Emulation against rtcan-sim's CPU model (issue 10's `rtcan sim --cpu on`), per module:
//! the slot-boundary latency (slot timer match → TXRQ of the committed frame) and the
//! HRT period jitter of the module's topics. The emulated figures come from the images'
//! instruction stream (`probe`, the bus); the model's from the committed cost table at
//! the same CPI, once charging every activation its mean path (`--cpu-cost mean`) and
//! once its longest (`max`, the default). docs/EMULATOR.md states the tolerance.
use std::fmt::Write as _;

use rtcan_sim::triskar::TriskarRun;

/// One module's figures in both worlds (ns).
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub module: String,
    /// Slot timer → TXRQ, emulated: mean and max.
    pub emu_txrq_mean_ns: f64,
    pub emu_txrq_max_ns: u64,
    /// The CPU model's: mean with mean path costs, max with max path costs.
    pub model_txrq_mean_ns: f64,
    pub model_txrq_max_ns: u64,
    /// Largest |HRT period − nominal| of the module's HRT topics (None: it sends none).
    pub emu_jitter_ns: Option<i64>,
    pub model_jitter_ns: Option<i64>,
}

fn jitter_of(r: &TriskarRun, node: usize) -> Option<i64> {
    let tag = format!("@n{node}");
    r.run
        .figures
        .hrt
        .iter()
        .filter(|h| h.name.ends_with(&tag))
        .map(|h| h.jitter_min_ns.abs().max(h.jitter_max_ns.abs()))
        .max()
}

/// The rows of `emu` against `model_mean` (mean costs) and `model_max` (max costs).
pub fn rows(emu: &TriskarRun, model_mean: &TriskarRun, model_max: &TriskarRun) -> Vec<Row> {
    emu.run
        .cpu
        .modules
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let mm = model_mean.run.cpu.modules.get(i);
            let mx = model_max.run.cpu.modules.get(i);
            Row {
                module: e.name.clone(),
                emu_txrq_mean_ns: e.txrq_mean_ns,
                emu_txrq_max_ns: e.txrq_max_ns,
                model_txrq_mean_ns: mm.map_or(0.0, |m| m.txrq_mean_ns),
                model_txrq_max_ns: mx.map_or(0, |m| m.txrq_max_ns),
                emu_jitter_ns: jitter_of(emu, i),
                model_jitter_ns: jitter_of(model_max, i),
            }
        })
        .collect()
}

/// The table as text.
pub fn text(rows: &[Row], cpi: f64) -> String {
    let mut s = format!(
        "emulation vs CPU model at CPI {cpi}\nmodule       slot->TXRQ mean emu / model [us]   max emu / model [us]   HRT |jitter| max emu / model [us]\n"
    );
    let us = |ns: f64| ns / 1e3;
    let j = |v: Option<i64>| v.map_or("-".to_string(), |v| format!("{:.3}", us(v as f64)));
    for r in rows {
        let _ = writeln!(
            s,
            "{:<12} {:>14.3} / {:<14.3} {:>9.3} / {:<11.3} {:>14} / {}",
            r.module,
            us(r.emu_txrq_mean_ns),
            us(r.model_txrq_mean_ns),
            us(r.emu_txrq_max_ns as f64),
            us(r.model_txrq_max_ns as f64),
            j(r.emu_jitter_ns),
            j(r.model_jitter_ns)
        );
    }
    s
}
