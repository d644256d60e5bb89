//! The simulator's plots, drawn with `plotters` (SVG backend, no font files: plotters'
//! built-in text metrics): HRT jitter histogram, SRT latency distribution, the cycle
//! calendar (like the RTCAN paper's Figs. 3–5), and the sweep curves. Every plot has
//! ticks, a grid, axis titles and a legend with the series' names, and comes with the
//! numbers it shows as CSV, so a reader can re-plot or check a figure.
use std::error::Error;
use std::fmt::Write as _;

use plotters::coord::Shift;
use plotters::prelude::*;
use rtcan_core::Nanos;

use crate::compare::{mean_latency_ns, miss_ratio, Comparison};
use crate::run::{Run, Scenario};

/// One plot: the SVG and the CSV of the data drawn in it.
#[derive(Clone, Debug, PartialEq)]
pub struct Plot {
    /// The picture.
    pub svg: String,
    /// The numbers behind it (a header line, then one row per point or bin).
    pub csv: String,
}

const W: u32 = 800;
const H: u32 = 420;

/// Ten well-separated colours (Tableau 10) for up to ten series; beyond them plotters'
/// 99-colour palette, so no two of a robot's modules share a colour.
pub(crate) fn colour(i: usize) -> RGBColor {
    const TAB10: [(u8, u8, u8); 10] = [
        (31, 119, 180),
        (214, 39, 40),
        (44, 160, 44),
        (148, 103, 189),
        (255, 127, 14),
        (140, 86, 75),
        (227, 119, 194),
        (127, 127, 127),
        (188, 189, 34),
        (23, 190, 207),
    ];
    match TAB10.get(i) {
        Some(&(r, g, b)) => RGBColor(r, g, b),
        None => {
            let c = Palette99::pick(i).to_rgba();
            RGBColor(c.0, c.1, c.2)
        }
    }
}

pub(crate) type DrawResult = Result<(), Box<dyn Error>>;

/// Runs `draw` on a white `w`×`h` SVG canvas and returns the SVG text.
pub(crate) fn svg(
    w: u32,
    h: u32,
    draw: impl FnOnce(&DrawingArea<SVGBackend, Shift>) -> DrawResult,
) -> Result<String, String> {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        draw(&root).map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(out)
}

/// The legend every plot has: the series' names in a framed, nearly opaque box.
pub(crate) fn legend<'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, SVGBackend<'a>, CT>,
    position: SeriesLabelPosition,
) -> DrawResult {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// A CSV field: quoted when it holds a comma, quote or line break.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

/// The histogram's range: the data's, widened when empty or a single value.
fn range(series: &[(String, Vec<f64>)]) -> (f64, f64) {
    let all = series.iter().flat_map(|(_, v)| v.iter().copied());
    let (lo, hi) = all.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
    if lo > hi {
        (0.0, 1.0)
    } else if hi - lo < 1e-9 {
        (lo - 0.5, hi + 0.5)
    } else {
        (lo, hi)
    }
}

/// Histogram of `series` (label, values) over `bins` equal bins, as the fraction of each
/// series' values per bin; the series' bars stand side by side in each bin.
pub fn histogram(
    title: &str,
    xlabel: &str,
    series: &[(String, Vec<f64>)],
    bins: usize,
) -> Result<Plot, String> {
    let (lo, hi) = range(series);
    let bins = bins.max(1);
    let width = (hi - lo) / bins as f64;
    let fractions: Vec<Vec<f64>> = series
        .iter()
        .map(|(_, v)| {
            let mut c = vec![0.0; bins];
            for &x in v {
                let b = (((x - lo) / (hi - lo)) * bins as f64).floor();
                let b = if b.is_finite() && b > 0.0 {
                    b as usize
                } else {
                    0
                };
                if let Some(slot) = c.get_mut(b.min(bins - 1)) {
                    *slot += 1.0;
                }
            }
            let n = v.len().max(1) as f64;
            c.iter().map(|k| k / n).collect()
        })
        .collect();
    let ymax = fractions
        .iter()
        .flatten()
        .copied()
        .fold(0.0, f64::max)
        .max(1e-3);
    let k = series.len().max(1) as f64;
    let picture = svg(W, H, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(60)
            // Head room for the legend above the tallest bar.
            .build_cartesian_2d(lo..hi, 0.0..ymax * 1.3)?;
        chart
            .configure_mesh()
            .x_desc(xlabel)
            .y_desc("fraction of samples")
            .x_labels(10)
            .y_labels(8)
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 14))
            .draw()?;
        for (si, ((name, _), f)) in series.iter().zip(&fractions).enumerate() {
            let c = colour(si);
            chart
                .draw_series(
                    f.iter()
                        .enumerate()
                        .filter(|(_, &v)| v > 0.0)
                        .map(|(b, &v)| {
                            let x0 = lo + b as f64 * width + si as f64 * width / k;
                            Rectangle::new([(x0, 0.0), (x0 + width / k, v)], c.filled())
                        }),
                )?
                .label(name.as_str())
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], c.filled()));
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })?;
    let mut csv = String::from("bin_low,bin_high");
    for (name, _) in series {
        let _ = write!(csv, ",{}", field(name));
    }
    csv.push('\n');
    for b in 0..bins {
        let _ = write!(
            csv,
            "{},{}",
            lo + b as f64 * width,
            lo + (b + 1) as f64 * width
        );
        for f in &fractions {
            let _ = write!(csv, ",{}", f.get(b).copied().unwrap_or(0.0));
        }
        csv.push('\n');
    }
    Ok(Plot { svg: picture, csv })
}

/// Line plot of `series` (label, points), each point marked.
pub fn lines(
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[(String, Vec<(f64, f64)>)],
) -> Result<Plot, String> {
    let pts = series.iter().flat_map(|(_, p)| p.iter().copied());
    let (x0, x1, y1) = pts.fold((f64::MAX, f64::MIN, 0.0f64), |(a, b, c), (x, y)| {
        (a.min(x), b.max(x), c.max(y))
    });
    let (x0, x1) = if x0 >= x1 {
        let x = if x0 == f64::MAX { 0.0 } else { x0 };
        (x - 1.0, x + 1.0)
    } else {
        let pad = (x1 - x0) * 0.03;
        (x0 - pad, x1 + pad)
    };
    let y1 = if y1 > 0.0 { y1 * 1.08 } else { 1.0 };
    let picture = svg(W, H, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, 0.0..y1)?;
        chart
            .configure_mesh()
            .x_desc(xlabel)
            .y_desc(ylabel)
            .x_labels(10)
            .y_labels(8)
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 14))
            .draw()?;
        for (si, (name, p)) in series.iter().enumerate() {
            let c = colour(si);
            chart
                .draw_series(LineSeries::new(p.iter().copied(), c.stroke_width(2)))?
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], c.stroke_width(2)));
            chart.draw_series(p.iter().map(|&xy| Circle::new(xy, 3, c.filled())))?;
        }
        legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        Ok(())
    })?;
    let mut csv = String::from("series,x,y\n");
    for (name, p) in series {
        for (x, y) in p {
            let _ = writeln!(csv, "{},{x},{y}", field(name));
        }
    }
    Ok(Plot { svg: picture, csv })
}

/// HRT jitter histogram (µs) of a run, one series per HRT label.
pub fn hrt_jitter(run: &Run) -> Result<Plot, String> {
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
        "interval - nominal period [µs]",
        &series,
        40,
    )
}

/// SRT latency distribution (ms) per class.
pub fn srt_latency(run: &Run) -> Result<Plot, String> {
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

/// One calendar row: the module's name and its reserved slots of cycle 0 with the
/// topic each carries.
pub type CalendarRow = (String, Vec<(u32, String)>);

/// The calendar rows of a scenario's cycle 0: one per module (its name), a cell per slot
/// it reserves, labelled with the topic.
pub fn calendar_rows(sc: &Scenario) -> Vec<CalendarRow> {
    let slots = sc.bus().map_or(0, |b| u32::from(b.slots_per_cycle));
    sc.tables
        .iter()
        .enumerate()
        .map(|(n, t)| {
            let cells = t
                .calendar
                .iter()
                .filter(|e| e.slot < slots)
                .map(|e| {
                    let label = sc
                        .topics
                        .iter()
                        .find(|i| i.node == n && i.tx == e.tx)
                        .map_or("?", |i| i.label.as_str());
                    (e.slot, label.to_owned())
                })
                .collect();
            let name = sc
                .names
                .get(n)
                .cloned()
                .unwrap_or_else(|| format!("node {n}"));
            (name, cells)
        })
        .collect()
}

/// The cycle calendar: one row per module, a cell per slot it reserved, coloured by the
/// topic the slot carries (legend), and the master's reservation mask as the last row
/// (cycle 0 of the hyperperiod).
pub fn calendar(slots: u8, mask: u64, rows: &[CalendarRow]) -> Result<Plot, String> {
    let n_slots = u32::from(slots.max(1));
    let n_rows = rows.len() + 1;
    // Topics in order of first appearance, each with its colour.
    let mut topics: Vec<&str> = Vec::new();
    for (_, cells) in rows {
        for (_, t) in cells {
            if !topics.contains(&t.as_str()) {
                topics.push(t);
            }
        }
    }
    let height = 150 + 34 * n_rows as u32;
    let picture = svg(W.max(130 + 22 * n_slots), height, |root| {
        let names: Vec<String> = rows
            .iter()
            .map(|r| r.0.clone())
            .chain(std::iter::once("mask".to_owned()))
            .collect();
        // Row r of `rows` is drawn top-down: segment n_rows - 1 - r.
        let seg = |r: usize| n_rows - 1 - r;
        let mut chart = ChartBuilder::on(root)
            .caption(
                "HRT calendar, cycle 0: reserved slots per module (colour: topic), mask below",
                ("sans-serif", 16),
            )
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(90)
            .build_cartesian_2d(0u32..n_slots, (0..n_rows - 1).into_segmented())?;
        chart
            .configure_mesh()
            .x_desc("slot")
            .x_labels(n_slots as usize + 1)
            .y_labels(n_rows)
            .label_style(("sans-serif", 12))
            .axis_desc_style(("sans-serif", 13))
            .y_label_formatter(&|y| match y {
                SegmentValue::CenterOf(i) => (n_rows - 1)
                    .checked_sub(*i)
                    .and_then(|k| names.get(k))
                    .cloned()
                    .unwrap_or_default(),
                _ => String::new(),
            })
            .disable_y_mesh()
            .draw()?;
        let cell = |slot: u32, r: usize| {
            [
                (slot, SegmentValue::Exact(seg(r) + 1)),
                (slot + 1, SegmentValue::Exact(seg(r))),
            ]
        };
        for (ti, topic) in topics.iter().enumerate() {
            let c = colour(ti);
            let cells = rows.iter().enumerate().flat_map(|(r, (_, cells))| {
                cells
                    .iter()
                    .filter(|(_, t)| t == topic)
                    .map(move |(slot, _)| (r, *slot))
            });
            chart
                .draw_series(cells.map(|(r, slot)| Rectangle::new(cell(slot, r), c.filled())))?
                .label(*topic)
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], c.filled()));
        }
        // White cell borders, so adjacent slots of one topic stay countable.
        chart.draw_series(rows.iter().enumerate().flat_map(|(r, (_, cells))| {
            cells
                .iter()
                .map(move |(slot, _)| Rectangle::new(cell(*slot, r), WHITE.stroke_width(1)))
        }))?;
        let last = n_rows - 1;
        for k in 0..n_slots {
            let reserved = (mask >> k) & 1 == 1;
            let fill = if reserved {
                BLACK.mix(0.75)
            } else {
                BLACK.mix(0.08)
            };
            chart.draw_series(std::iter::once(Rectangle::new(
                cell(k, last),
                fill.filled(),
            )))?;
            chart.draw_series(std::iter::once(Text::new(
                if reserved { "1" } else { "0" },
                (k, SegmentValue::CenterOf(0)),
                ("sans-serif", 11)
                    .into_font()
                    .color(if reserved { &WHITE } else { &BLACK }),
            )))?;
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })?;
    let mut csv = String::from("row,slot,topic\n");
    for (name, cells) in rows {
        for (slot, label) in cells {
            let _ = writeln!(csv, "{},{slot},{}", field(name), field(label));
        }
    }
    for k in 0..n_slots {
        let _ = writeln!(csv, "mask,{k},{}", (mask >> k) & 1);
    }
    Ok(Plot { svg: picture, csv })
}

/// Sweep: SRT miss ratio and mean latency vs offered load (fraction of free-window
/// capacity), per policy.
pub fn sweep(points: &[Comparison]) -> Result<(Plot, Plot), String> {
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
    Ok((
        lines(
            "SRT miss ratio vs offered load",
            "offered SRT / free-window capacity",
            "miss ratio",
            &series(&miss_ratio),
        )?,
        lines(
            "SRT mean latency vs offered load",
            "offered SRT / free-window capacity",
            "mean latency [ms]",
            &series(&|r| mean_latency_ns(r) / 1e6),
        )?,
    ))
}

/// Nanoseconds as ms, for labels.
pub fn ms(ns: Nanos) -> f64 {
    ns as f64 / 1e6
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The contents of the SVG's `<text>` elements, trimmed.
    fn texts(svg: &str) -> Vec<String> {
        svg.split("<text")
            .skip(1)
            .filter_map(|t| {
                let body = t.split_once('>')?.1;
                Some(body.split_once("</text>")?.0.trim().to_owned())
            })
            .collect()
    }

    #[test]
    fn histogram_csv_holds_the_fractions_drawn() {
        let s = vec![
            ("a".to_owned(), vec![0.0, 0.0, 1.0, 2.0]),
            ("b,c".to_owned(), vec![2.0]),
        ];
        let p = histogram("t", "x [us]", &s, 2).unwrap();
        assert_eq!(p.csv, "bin_low,bin_high,a,\"b,c\"\n0,1,0.5,0\n1,2,0.5,1\n");
        assert!(p.svg.starts_with("<svg"), "{}", &p.svg[..40]);
        // The legend names every series, the axes carry their titles.
        let t = texts(&p.svg);
        for want in ["a", "b,c", "x [us]", "fraction of samples", "t"] {
            assert!(t.iter().any(|x| x == want), "no text `{want}` in {t:?}");
        }
    }

    #[test]
    fn empty_and_single_value_series_still_plot() {
        let p = histogram("t", "x", &[], 10).unwrap();
        assert_eq!(p.csv.lines().count(), 11);
        let one = vec![("a".to_owned(), vec![3.0, 3.0])];
        let p = histogram("t", "x", &one, 4).unwrap();
        assert_eq!(
            p.csv,
            "bin_low,bin_high,a\n2.5,2.75,0\n2.75,3,0\n3,3.25,1\n3.25,3.5,0\n"
        );
        let l = lines("t", "x", "y", &[("a".to_owned(), vec![])]).unwrap();
        assert_eq!(l.csv, "series,x,y\n");
    }

    #[test]
    fn calendar_names_modules_and_lists_the_mask() {
        let rows = vec![
            ("gateway".to_owned(), vec![(0, "sync".to_owned())]),
            (
                "motor1".to_owned(),
                vec![(1, "encoder1".to_owned()), (2, "encoder1".to_owned())],
            ),
        ];
        let p = calendar(4, 0b0111, &rows).unwrap();
        assert_eq!(
            p.csv,
            "row,slot,topic\ngateway,0,sync\nmotor1,1,encoder1\nmotor1,2,encoder1\n\
             mask,0,1\nmask,1,1\nmask,2,1\nmask,3,0\n"
        );
        let t = texts(&p.svg);
        for want in ["gateway", "motor1", "mask", "sync", "encoder1", "slot"] {
            assert!(t.iter().any(|x| x == want), "no text `{want}` in {t:?}");
        }
    }

    #[test]
    fn eleven_series_get_eleven_colours() {
        let c: Vec<RGBColor> = (0..11).map(colour).collect();
        for (i, a) in c.iter().enumerate() {
            for b in c.iter().skip(i + 1) {
                assert_ne!(a, b);
            }
        }
    }
}
