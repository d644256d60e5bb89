//! Terminal tables and JSON (serde_json values; the fields are documented in
//! docs/SIM.md). Numbers keep their full precision: a ratio of 2 misses in 5 623 is
//! 0.00035567... in the JSON, not a rounded 0.000.
use std::fmt::Write as _;

use serde_json::{json, Value};

use crate::compare::{mean_latency_ns, miss_ratio, on_time, Comparison};
use crate::run::Run;

fn us(ns: f64) -> f64 {
    ns / 1_000.0
}

/// Tables of one run.
pub fn text(run: &Run) -> String {
    let mut s = String::new();
    let f = &run.figures;
    let _ = writeln!(s, "== policy {} ==", run.policy);
    if !f.hrt.is_empty() {
        let _ = writeln!(
            s,
            "HRT message        count  misses    late  missed  mean period [us]  std dev [us]  jitter min/max [us]  max resp. [us]"
        );
        let opt = |v: Option<u64>| v.map_or("-".to_string(), |v| v.to_string());
        for h in &f.hrt {
            let _ = writeln!(
                s,
                "{:<16} {:>7} {:>7} {:>7} {:>7} {:>17.2} {:>13.3} {:>10.3} / {:<8.3} {:>14}",
                h.name,
                h.count,
                h.misses,
                opt(h.late),
                opt(h.missed),
                us(h.mean_period_ns),
                us(h.std_period_ns),
                us(h.jitter_min_ns as f64),
                us(h.jitter_max_ns as f64),
                h.max_response_ns
                    .map_or("-".to_string(), |r| format!("{:.3}", us(r as f64)))
            );
        }
    }
    if !f.srt.is_empty() {
        let _ = writeln!(
            s,
            "SRT class          count  miss ratio  mean [ms]  p95 [ms]  max [ms]"
        );
        for c in &f.srt {
            let _ = writeln!(
                s,
                "{:<16} {:>7} {:>10.2}% {:>10.3} {:>9.3} {:>9.3}",
                c.name,
                c.count,
                100.0 * c.miss_ratio(),
                c.mean_ns() / 1e6,
                c.percentile_ns(95.0) as f64 / 1e6,
                c.max_ns() as f64 / 1e6
            );
        }
    }
    let l = &f.load;
    let _ = writeln!(
        s,
        "bus load: sync {:.1}%  HRT {:.1}%  SRT {:.1}%  NRT {:.1}%  errors {:.1}%  total {:.1}%",
        100.0 * l.sync,
        100.0 * l.hrt,
        100.0 * l.srt,
        100.0 * l.nrt,
        100.0 * l.errors,
        100.0 * (l.sync + l.hrt + l.srt + l.nrt + l.errors)
    );
    let _ = writeln!(
        s,
        "slot overlaps {}  error frames {}  unattributed frames {}  delivered ok/bad {}/{}",
        run.overlaps, run.bus.error_frames, f.unknown_frames, run.rx_ok, run.rx_bad
    );
    s.push_str(&run.cpu.text());
    s
}

/// Side-by-side summary of a comparison.
pub fn comparison_text(c: &Comparison) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "load x{:.2}: offered SRT = {:.1}% of usable free-window time (free windows = {:.1}% of the bus)",
        c.load,
        100.0 * c.offered_fraction,
        100.0 * c.window_fraction
    );
    let _ = writeln!(
        s,
        "policy            SRT on time  miss ratio  mean latency [ms]  HRT misses  HRT late  HRT missed  overlaps"
    );
    for r in &c.runs {
        let hrt = &r.figures.hrt;
        let hrt_miss: u64 = hrt.iter().map(|h| h.misses).sum();
        let sum = |f: &dyn Fn(&crate::metrics::HrtStats) -> Option<u64>| -> String {
            hrt.iter()
                .map(f)
                .sum::<Option<u64>>()
                .map_or("-".into(), |v| v.to_string())
        };
        let _ = writeln!(
            s,
            "{:<16} {:>12} {:>10.2}% {:>18.3} {:>11} {:>9} {:>11} {:>9}",
            r.policy,
            on_time(r),
            100.0 * miss_ratio(r),
            mean_latency_ns(r) / 1e6,
            hrt_miss,
            sum(&|h| h.late),
            sum(&|h| h.missed),
            r.overlaps
        );
    }
    s
}

/// A number as JSON at full precision (shortest text that reads back the same f64);
/// NaN and infinities, which JSON cannot hold, as null.
pub(crate) fn num(x: f64) -> Value {
    serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)
}

/// JSON object of one run.
pub fn run_value(run: &Run) -> Value {
    let f = &run.figures;
    let hrt: Vec<Value> = f
        .hrt
        .iter()
        .map(|h| {
            json!({
                "name": h.name,
                "count": h.count,
                "misses": h.misses,
                "late": h.late,
                "missed": h.missed,
                "max_response_us": h.max_response_ns.map_or(Value::Null, |r| num(us(r as f64))),
                "mean_period_us": num(us(h.mean_period_ns)),
                "std_period_us": num(us(h.std_period_ns)),
                "jitter_min_us": num(us(h.jitter_min_ns as f64)),
                "jitter_max_us": num(us(h.jitter_max_ns as f64)),
            })
        })
        .collect();
    let srt: Vec<Value> = f
        .srt
        .iter()
        .map(|c| {
            json!({
                "class": c.name,
                "count": c.count,
                "misses": c.misses,
                "miss_ratio": num(c.miss_ratio()),
                "mean_ms": num(c.mean_ns() / 1e6),
                "p95_ms": num(c.percentile_ns(95.0) as f64 / 1e6),
                "max_ms": num(c.max_ns() as f64 / 1e6),
            })
        })
        .collect();
    let l = &f.load;
    let mut v = json!({
        "policy": run.policy,
        "hrt": hrt,
        "srt": srt,
        "load": {
            "sync": num(l.sync),
            "hrt": num(l.hrt),
            "srt": num(l.srt),
            "nrt": num(l.nrt),
            "errors": num(l.errors),
        },
        "slot_overlaps": run.overlaps,
        "error_frames": run.bus.error_frames,
        "unattributed_frames": f.unknown_frames,
        "delivered_ok": run.rx_ok,
        "delivered_bad": run.rx_bad,
    });
    if let (Some(cpu), Some(o)) = (run.cpu.json_value(), v.as_object_mut()) {
        o.insert("cpu".into(), cpu);
    }
    v
}

/// JSON text of one run.
pub fn run_json(run: &Run) -> String {
    run_value(run).to_string()
}

/// JSON object of a comparison.
pub fn comparison_value(c: &Comparison) -> Value {
    let runs: Vec<Value> = c
        .runs
        .iter()
        .map(|r| {
            let mut v = run_value(r);
            if let Some(o) = v.as_object_mut() {
                o.insert("srt_on_time".into(), on_time(r).into());
                o.insert("srt_miss_ratio".into(), num(miss_ratio(r)));
                o.insert("srt_mean_latency_ms".into(), num(mean_latency_ns(r) / 1e6));
            }
            v
        })
        .collect();
    json!({
        "load_scale": num(c.load),
        "offered_fraction_of_free_windows": num(c.offered_fraction),
        "free_window_fraction_of_bus": num(c.window_fraction),
        "policies": runs,
    })
}

/// JSON text of a comparison.
pub fn comparison_json(c: &Comparison) -> String {
    comparison_value(c).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_keep_their_precision() {
        // Issue 13: 2 misses of 5 623 printed as 0.000 with three decimals.
        let r = 2.0 / 5623.0;
        let text = num(r).to_string();
        assert_eq!(text.parse::<f64>().unwrap(), r, "{text}");
        assert_eq!(text, "0.00035568202027387515");
        assert_eq!(num(0.1).to_string(), "0.1");
        assert_eq!(num(100.0).to_string(), "100.0");
        assert_eq!(num(f64::NAN), Value::Null);
        assert_eq!(num(f64::INFINITY), Value::Null);
    }
}
