//! SVG plots written by hand: HRT jitter histogram, SRT latency distribution, the cycle
//! calendar (like the paper's Figs. 3–5), and the sweep curves.
use std::fmt::Write as _;

use rtcan_core::Nanos;

use crate::compare::{mean_latency_ns, miss_ratio, Comparison};
use crate::run::Run;

const W: f64 = 720.0;
const H: f64 = 360.0;
const M: f64 = 50.0;
const COLORS: [&str; 6] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
];

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn frame(title: &str, xlabel: &str, ylabel: &str) -> String {
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"{H}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"20\" text-anchor=\"middle\" font-size=\"14\">{}</text>",
        W / 2.0,
        esc(title)
    );
    let _ = writeln!(
        s,
        "<line x1=\"{M}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\"/>",
        H - M,
        W - 20.0,
        H - M
    );
    let _ = writeln!(
        s,
        "<line x1=\"{M}\" y1=\"30\" x2=\"{M}\" y2=\"{}\" stroke=\"black\"/>",
        H - M
    );
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
        W / 2.0,
        H - 12.0,
        esc(xlabel)
    );
    let _ = writeln!(
        s,
        "<text x=\"14\" y=\"{}\" transform=\"rotate(-90 14 {})\" text-anchor=\"middle\">{}</text>",
        H / 2.0,
        H / 2.0,
        esc(ylabel)
    );
    s
}

fn axis_labels(s: &mut String, x0: f64, x1: f64, y1: f64) {
    let _ = writeln!(
        s,
        "<text x=\"{M}\" y=\"{}\" text-anchor=\"middle\">{x0:.3}</text>",
        H - M + 15.0
    );
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{x1:.3}</text>",
        W - 20.0,
        H - M + 15.0
    );
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"34\" text-anchor=\"end\">{y1:.3}</text>",
        M - 4.0
    );
}

/// Histogram of `series` (label, values) over `bins` bins, one color per series.
pub fn histogram(title: &str, xlabel: &str, series: &[(String, Vec<f64>)], bins: usize) -> String {
    let all = series.iter().flat_map(|(_, v)| v.iter().copied());
    let (lo, hi) = all.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
    let (lo, hi) = if lo > hi {
        (0.0, 1.0)
    } else if hi - lo < 1e-9 {
        (lo - 0.5, hi + 0.5)
    } else {
        (lo, hi)
    };
    let bins = bins.max(1);
    let counts: Vec<Vec<f64>> = series
        .iter()
        .map(|(_, v)| {
            let mut c = vec![0.0; bins];
            for &x in v {
                let b = (((x - lo) / (hi - lo)) * bins as f64).floor() as usize;
                if let Some(slot) = c.get_mut(b.min(bins - 1)) {
                    *slot += 1.0;
                }
            }
            let n = v.len().max(1) as f64;
            c.iter().map(|k| k / n).collect()
        })
        .collect();
    let ymax = counts
        .iter()
        .flatten()
        .copied()
        .fold(0.0, f64::max)
        .max(1e-9);
    let mut s = frame(title, xlabel, "fraction");
    let pw = (W - 20.0 - M) / bins as f64;
    let ph = H - M - 30.0;
    let k = series.len().max(1) as f64;
    for (si, c) in counts.iter().enumerate() {
        let color = COLORS.get(si % COLORS.len()).copied().unwrap_or("black");
        for (b, &v) in c.iter().enumerate() {
            let h = v / ymax * ph;
            let x = M + b as f64 * pw + si as f64 * pw / k;
            let _ = writeln!(s, "<rect x=\"{x:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{h:.1}\" fill=\"{color}\"/>", H - M - h, pw / k);
        }
        if let Some((name, _)) = series.get(si) {
            let _ = writeln!(
                s,
                "<text x=\"{}\" y=\"{}\" fill=\"{color}\">{}</text>",
                W - 150.0,
                40.0 + 15.0 * si as f64,
                esc(name)
            );
        }
    }
    axis_labels(&mut s, lo, hi, ymax);
    s.push_str("</svg>\n");
    s
}

/// Line plot of `series` (label, points).
pub fn lines(
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[(String, Vec<(f64, f64)>)],
) -> String {
    let pts = series.iter().flat_map(|(_, p)| p.iter().copied());
    let (x0, x1, y1) = pts.fold((f64::MAX, f64::MIN, 0.0f64), |(a, b, c), (x, y)| {
        (a.min(x), b.max(x), c.max(y))
    });
    let (x0, x1) = if x0 >= x1 {
        (x0 - 1.0, x0 + 1.0)
    } else {
        (x0, x1)
    };
    let y1 = if y1 <= 0.0 { 1.0 } else { y1 };
    let mut s = frame(title, xlabel, ylabel);
    let px = |x: f64| M + (x - x0) / (x1 - x0) * (W - 20.0 - M);
    let py = |y: f64| H - M - y / y1 * (H - M - 30.0);
    for (si, (name, p)) in series.iter().enumerate() {
        let color = COLORS.get(si % COLORS.len()).copied().unwrap_or("black");
        let path: Vec<String> = p
            .iter()
            .map(|&(x, y)| format!("{:.1},{:.1}", px(x), py(y)))
            .collect();
        let _ = writeln!(
            s,
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{color}\" stroke-width=\"2\"/>",
            path.join(" ")
        );
        for &(x, y) in p {
            let _ = writeln!(
                s,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"3\" fill=\"{color}\"/>",
                px(x),
                py(y)
            );
        }
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" fill=\"{color}\">{}</text>",
            W - 150.0,
            40.0 + 15.0 * si as f64,
            esc(name)
        );
    }
    axis_labels(&mut s, x0, x1, y1);
    s.push_str("</svg>\n");
    s
}

/// HRT jitter histogram (µs) of a run, one series per HRT label.
pub fn hrt_jitter(run: &Run) -> String {
    let series: Vec<(String, Vec<f64>)> = run
        .figures
        .hrt
        .iter()
        .map(|h| {
            (
                h.name.clone(),
                h.jitter_ns.iter().map(|&j| j as f64 / 1e3).collect(),
            )
        })
        .collect();
    histogram(
        &format!("HRT period jitter ({})", run.policy),
        "interval - nominal period [us]",
        &series,
        40,
    )
}

/// SRT latency distribution (ms) per class.
pub fn srt_latency(run: &Run) -> String {
    let series: Vec<(String, Vec<f64>)> = run
        .figures
        .srt
        .iter()
        .map(|c| {
            (
                c.name.clone(),
                c.latency
                    .sample
                    .values
                    .iter()
                    .map(|&l| l as f64 / 1e6)
                    .collect(),
            )
        })
        .collect();
    histogram(
        &format!("SRT delivery latency ({})", run.policy),
        "latency [ms]",
        &series,
        50,
    )
}

/// The cycle calendar: one row per node, a cell per slot, colored by what the node
/// reserved, and the reservation mask below (cycle 0 of the hyperperiod).
pub fn calendar(slots: u8, mask: u64, rows: &[(String, Vec<(u32, String)>)]) -> String {
    let cw = ((W - 120.0) / f64::from(slots.max(1))).floor();
    let height = 60.0 + 25.0 * (rows.len() as f64 + 1.0);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"{height}\" font-family=\"sans-serif\" font-size=\"9\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"10\" y=\"20\" font-size=\"13\">HRT calendar, cycle 0 (reserved slots per node, mask below)</text>\n"
    );
    for (r, (name, cells)) in rows.iter().enumerate() {
        let y = 40.0 + 25.0 * r as f64;
        let _ = writeln!(s, "<text x=\"10\" y=\"{}\">{}</text>", y + 14.0, esc(name));
        for k in 0..u32::from(slots) {
            let x = 110.0 + f64::from(k) * cw;
            let label = cells.iter().find(|c| c.0 == k).map(|c| c.1.as_str());
            let fill = if label.is_some() {
                COLORS.get(r % COLORS.len()).copied().unwrap_or("gray")
            } else {
                "#eeeeee"
            };
            let _ = writeln!(s, "<rect x=\"{x:.1}\" y=\"{y}\" width=\"{:.1}\" height=\"20\" fill=\"{fill}\" stroke=\"white\"/>", cw);
            if let Some(l) = label {
                let _ = writeln!(
                    s,
                    "<text x=\"{:.1}\" y=\"{}\" fill=\"white\" text-anchor=\"middle\">{}</text>",
                    x + cw / 2.0,
                    y + 14.0,
                    esc(l)
                );
            }
        }
    }
    let y = 40.0 + 25.0 * rows.len() as f64;
    let _ = writeln!(s, "<text x=\"10\" y=\"{}\">mask</text>", y + 14.0);
    for k in 0..u32::from(slots) {
        let bit = (mask >> k) & 1;
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\">{bit}</text>",
            110.0 + f64::from(k) * cw + cw / 2.0,
            y + 14.0
        );
    }
    s.push_str("</svg>\n");
    s
}

/// Sweep: SRT miss ratio and mean latency vs offered load (fraction of free-window
/// capacity), per policy.
pub fn sweep(points: &[Comparison]) -> (String, String) {
    let names: Vec<&'static str> = points
        .first()
        .map(|c| c.runs.iter().map(|r| r.policy).collect())
        .unwrap_or_default();
    let series = |f: &dyn Fn(&Run) -> f64| -> Vec<(String, Vec<(f64, f64)>)> {
        names
            .iter()
            .enumerate()
            .map(|(i, n)| {
                (
                    n.to_string(),
                    points
                        .iter()
                        .filter_map(|c| c.runs.get(i).map(|r| (c.offered_fraction, f(r))))
                        .collect(),
                )
            })
            .collect()
    };
    (
        lines(
            "SRT miss ratio vs offered load",
            "offered SRT / free-window capacity",
            "miss ratio",
            &series(&miss_ratio),
        ),
        lines(
            "SRT mean latency vs offered load",
            "offered SRT / free-window capacity",
            "mean latency [ms]",
            &series(&|r| mean_latency_ns(r) / 1e6),
        ),
    )
}

/// Nanoseconds as ms, for labels.
pub fn ms(ns: Nanos) -> f64 {
    ns as f64 / 1e6
}
