//! Terminal tables and JSON (hand-written: the fields are documented in docs/SIM.md).
use std::fmt::Write as _;

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

pub(crate) fn json_str(s: &str) -> String {
    let mut o = String::from("\"");
    for ch in s.chars() {
        match ch {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(o, "\\u{:04x}", c as u32);
            }
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

pub(crate) fn num(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.3}")
    } else {
        "null".into()
    }
}

/// JSON object of one run.
pub fn run_json(run: &Run) -> String {
    let f = &run.figures;
    let hrt: Vec<String> = f
        .hrt
        .iter()
        .map(|h| {
            format!(
                "{{\"name\":{},\"count\":{},\"misses\":{},\"late\":{},\"missed\":{},\"max_response_us\":{},\"mean_period_us\":{},\"std_period_us\":{},\"jitter_min_us\":{},\"jitter_max_us\":{}}}",
                json_str(&h.name),
                h.count,
                h.misses,
                h.late.map_or("null".into(), |v| v.to_string()),
                h.missed.map_or("null".into(), |v| v.to_string()),
                h.max_response_ns
                    .map_or("null".into(), |r| num(us(r as f64))),
                num(us(h.mean_period_ns)),
                num(us(h.std_period_ns)),
                num(us(h.jitter_min_ns as f64)),
                num(us(h.jitter_max_ns as f64))
            )
        })
        .collect();
    let srt: Vec<String> = f
        .srt
        .iter()
        .map(|c| {
            format!(
                "{{\"class\":{},\"count\":{},\"misses\":{},\"miss_ratio\":{},\"mean_ms\":{},\"p95_ms\":{},\"max_ms\":{}}}",
                json_str(&c.name),
                c.count,
                c.misses,
                num(c.miss_ratio()),
                num(c.mean_ns() / 1e6),
                num(c.percentile_ns(95.0) as f64 / 1e6),
                num(c.max_ns() as f64 / 1e6)
            )
        })
        .collect();
    let l = &f.load;
    format!(
        "{{\"policy\":{},\"hrt\":[{}],\"srt\":[{}],\"load\":{{\"sync\":{},\"hrt\":{},\"srt\":{},\"nrt\":{},\"errors\":{}}},\"slot_overlaps\":{},\"error_frames\":{},\"unattributed_frames\":{},\"delivered_ok\":{},\"delivered_bad\":{}{}}}",
        json_str(run.policy),
        hrt.join(","),
        srt.join(","),
        num(l.sync),
        num(l.hrt),
        num(l.srt),
        num(l.nrt),
        num(l.errors),
        run.overlaps,
        run.bus.error_frames,
        f.unknown_frames,
        run.rx_ok,
        run.rx_bad,
        run.cpu.json_member()
    )
}

/// JSON object of a comparison.
pub fn comparison_json(c: &Comparison) -> String {
    let runs: Vec<String> = c
        .runs
        .iter()
        .map(|r| {
            let body = run_json(r);
            let extra = format!(
                ",\"srt_on_time\":{},\"srt_miss_ratio\":{},\"srt_mean_latency_ms\":{}}}",
                on_time(r),
                num(miss_ratio(r)),
                num(mean_latency_ns(r) / 1e6)
            );
            format!("{}{}", body.strip_suffix('}').unwrap_or(&body), extra)
        })
        .collect();
    format!(
        "{{\"load_scale\":{},\"offered_fraction_of_free_windows\":{},\"free_window_fraction_of_bus\":{},\"policies\":[{}]}}",
        num(c.load),
        num(c.offered_fraction),
        num(c.window_fraction),
        runs.join(",")
    )
}
