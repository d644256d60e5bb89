//! HRT admission through `rtcan_core::admission`, and its failures turned into
//! diagnostics that name the topics and suggest admissible periods.
use crate::diag::{Code, Diagnostic, Span};
use crate::model::Model;
use crate::units;
use rtcan_core::admission::{
    self, AdmissionError, AdmitStats, HrtRequest, Placement, MAX_CONFLICT, MAX_HRT,
    MAX_HYPERPERIOD_SLOTS,
};

/// Step budget of one admission (the 200-topic benchmark needs far less).
pub const ADMISSION_BUDGET: u64 = 20_000_000;

/// An admitted HRT set.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Admitted {
    /// Phase of each request.
    pub placements: Vec<Placement>,
    /// Search statistics (hyperperiod, reserved slots, steps).
    pub stats: AdmitStats,
    /// Reservation mask of every cycle of the hyperperiod.
    pub masks: Vec<u64>,
}

/// One HRT topic to place.
#[derive(Clone, Copy, Debug)]
pub struct HrtTopic {
    /// Index into `model.topics`.
    pub topic: usize,
    /// The request.
    pub request: HrtRequest,
}

fn topic_name(model: &Model, t: usize) -> &str {
    model.topics.get(t).map_or("?", |x| x.name.as_str())
}

fn timing_span(model: &Model, t: usize) -> Option<Span> {
    model
        .topics
        .get(t)
        .and_then(|x| x.spans.timing.clone().or_else(|| x.spans.name.clone()))
}

fn fmt_period(model: &Model, slots: u32) -> String {
    let ns = f64::from(slots) * model.bus.slot_ns as f64;
    format!("{slots} slots ({})", units::fmt_hz(1e9 / ns))
}

/// "admissible periods for `x`: ..." from `suggest_periods`, or a fallback hint.
fn suggestion(model: &Model, hrt: &[HrtTopic], index: usize) -> String {
    let requests: Vec<HrtRequest> = hrt.iter().map(|h| h.request).collect();
    let name = hrt.get(index).map_or("?", |h| topic_name(model, h.topic));
    // A period longer than the hyperperiod bound can never be admitted, and searching
    // 1..=2*period candidates for it would take seconds.
    if hrt
        .get(index)
        .is_some_and(|h| u64::from(h.request.period_slots) > MAX_HYPERPERIOD_SLOTS)
    {
        return format!(
            "an HRT period must be at most {MAX_HYPERPERIOD_SLOTS} slots; make `{name}` SRT or NRT with a `rate` instead"
        );
    }
    let mut out = [0u32; 4];
    let n = admission::suggest_periods(u32::from(model.bus.slots), &requests, index, &mut out);
    let list: Vec<String> = out.iter().take(n).map(|p| fmt_period(model, *p)).collect();
    if list.is_empty() {
        format!("no period near the requested one makes `{name}` admissible: move other HRT topics or lengthen their periods")
    } else {
        format!("admissible periods for `{name}`: {}", list.join(", "))
    }
}

/// Runs admission and builds the master masks; errors become diagnostics.
pub fn admit(model: &Model, hrt: &[HrtTopic]) -> Result<Admitted, Diagnostic> {
    let slots = u32::from(model.bus.slots);
    let requests: Vec<HrtRequest> = hrt.iter().map(|h| h.request).collect();
    let mut placements = vec![Placement::default(); requests.len()];
    let result =
        admission::admit(slots, &requests, &mut placements, ADMISSION_BUDGET).and_then(|stats| {
            let cycles = usize::try_from(stats.hyperperiod_slots / u64::from(slots)).unwrap_or(0);
            let mut masks = vec![0u64; cycles];
            let n = admission::build_masks(slots, &requests, &placements, &mut masks)?;
            masks.truncate(n);
            Ok(Admitted {
                placements: placements.clone(),
                stats,
                masks,
            })
        });
    result.map_err(|e| diagnose(model, hrt, e))
}

fn diagnose(model: &Model, hrt: &[HrtTopic], e: AdmissionError) -> Diagnostic {
    let slots = u64::from(model.bus.slots);
    let name_of = |i: usize| hrt.get(i).map_or("?", |h| topic_name(model, h.topic));
    let span_of = |i: usize| hrt.get(i).and_then(|h| timing_span(model, h.topic));
    let period_of = |i: usize| hrt.get(i).map_or(0, |h| h.request.period_slots);
    match e {
        AdmissionError::TooMany { count } => Diagnostic::new(
            Code::TooManyHrt,
            span_of(MAX_HRT),
            format!("{count} HRT topics on the bus; admission handles at most {MAX_HRT}"),
        )
        .help("make some topics SRT, or merge them into larger messages"),
        AdmissionError::InvalidRequest { index } => {
            let r = hrt.get(index).map(|h| h.request).unwrap_or(HrtRequest {
                period_slots: 0,
                fragments: 0,
            });
            let g = admission::gcd(u64::from(r.period_slots), slots);
            let why = if u32::from(r.fragments) > r.period_slots {
                format!(
                    "its {} fragments need more consecutive slots than its period",
                    r.fragments
                )
            } else if g == 1 {
                "its period is relatively prime to the cycle, so it hits the sync slot at every phase".to_string()
            } else {
                format!(
                    "its {} consecutive slots hit the sync slot at every phase (gcd(period, {} slots per cycle) = {g})",
                    r.fragments, slots
                )
            };
            Diagnostic::new(
                Code::InadmissibleHrt,
                span_of(index),
                format!(
                    "HRT topic `{}` with period {} is not admissible: {why}",
                    name_of(index),
                    fmt_period(model, r.period_slots)
                ),
            )
            .help(suggestion(model, hrt, index))
        }
        AdmissionError::HyperperiodTooLong { slots: h } => {
            // The topic whose period first pushes the lcm past the limit.
            let mut acc = slots;
            let mut culprit = 0;
            for (i, x) in hrt.iter().enumerate() {
                acc = admission::lcm(acc, u64::from(x.request.period_slots)).unwrap_or(u64::MAX);
                if acc > MAX_HYPERPERIOD_SLOTS {
                    culprit = i;
                    break;
                }
            }
            Diagnostic::new(
                Code::HyperperiodTooLong,
                span_of(culprit),
                format!(
                    "the HRT hyperperiod reaches {h} slots with topic `{}` (period {}); the limit is {MAX_HYPERPERIOD_SLOTS} slots",
                    name_of(culprit),
                    fmt_period(model, period_of(culprit))
                ),
            )
            .help(suggestion(model, hrt, culprit))
            .note("the master keeps one reservation mask per cycle of the hyperperiod; periods dividing each other keep it short")
        }
        AdmissionError::OverCapacity {
            reserved,
            available,
        } => {
            // Point at the topic using the largest share of slots.
            let (culprit, _) = hrt.iter().enumerate().fold((0, 0.0f64), |best, (i, x)| {
                let share =
                    f64::from(x.request.fragments) / f64::from(x.request.period_slots.max(1));
                if share > best.1 {
                    (i, share)
                } else {
                    best
                }
            });
            let mut uses: Vec<String> = hrt
                .iter()
                .map(|x| {
                    format!(
                        "`{}` {}/{}",
                        topic_name(model, x.topic),
                        x.request.fragments,
                        x.request.period_slots
                    )
                })
                .collect();
            // Eight are enough to see the pattern; the count says the list is cut.
            let listed = 8;
            let more = uses.len().saturating_sub(listed);
            uses.truncate(listed);
            if more > 0 {
                uses.push(format!("and {more} more"));
            }
            Diagnostic::new(
                Code::HrtOverCapacity,
                span_of(culprit),
                format!(
                    "HRT topics need {reserved} slots per hyperperiod but only {available} are free (more reservations than slots)"
                ),
            )
            .help(suggestion(model, hrt, culprit))
            .note(format!("slots per period: {}", uses.join(", ")))
        }
        AdmissionError::Infeasible {
            conflict,
            len,
            size,
        } => {
            let idx: Vec<usize> = conflict
                .iter()
                .take(usize::from(len).min(MAX_CONFLICT))
                .map(|c| usize::from(*c))
                .collect();
            // A pair: the later one. A capacity core: its most demanding topic (the one
            // whose period is worth changing).
            let demand = |i: usize| {
                hrt.get(i).map_or(0.0, |h| {
                    f64::from(h.request.fragments) / f64::from(h.request.period_slots.max(1))
                })
            };
            let culprit = if usize::from(size) > idx.len() {
                idx.iter()
                    .copied()
                    .fold(None::<usize>, |best, i| match best {
                        Some(b) if demand(b) >= demand(i) => Some(b),
                        _ => Some(i),
                    })
                    .unwrap_or(0)
            } else {
                idx.last().copied().unwrap_or(0)
            };
            let others: Vec<String> = idx
                .iter()
                .filter(|i| **i != culprit)
                .map(|i| {
                    format!(
                        "`{}` (period {})",
                        name_of(*i),
                        fmt_period(model, period_of(*i))
                    )
                })
                .collect();
            let subset: Vec<HrtRequest> = idx
                .iter()
                .filter_map(|i| hrt.get(*i).map(|h| h.request))
                .collect();
            let shown = idx.len();
            let size = usize::from(size).max(shown);
            let (with, why) = if size > shown {
                // A capacity argument over many topics: name a few, count the rest.
                (
                    format!("{} and {} more HRT topics", others.join(", "), size - shown),
                    "together they need more slots than the phases their periods leave free",
                )
            } else if others.is_empty() {
                ("the sync slot".to_string(), "every phase collides")
            } else if admission::paper_rule(&subset).is_err() {
                (others.join(", "), "periods relatively prime")
            } else {
                (others.join(", "), "every phase collides")
            };
            Diagnostic::new(
                Code::InadmissibleHrt,
                span_of(culprit),
                format!(
                    "topic `{}` has period {}, not admissible with {with}: {why}",
                    name_of(culprit),
                    fmt_period(model, period_of(culprit))
                ),
            )
            .help(suggestion(model, hrt, culprit))
        }
        AdmissionError::TooHard { steps, stuck, len } => {
            let idx: Vec<usize> = stuck
                .iter()
                .take(usize::from(len).min(MAX_CONFLICT))
                .map(|c| usize::from(*c))
                .collect();
            let culprit = idx.first().copied();
            let named: Vec<String> = idx
                .iter()
                .map(|i| {
                    format!(
                        "`{}` (period {})",
                        name_of(*i),
                        fmt_period(model, period_of(*i))
                    )
                })
                .collect();
            let mut d = Diagnostic::new(
                Code::AdmissionUndecided,
                culprit
                    .and_then(span_of)
                    .or_else(|| model.bus.spans.table.clone()),
                format!(
                    "HRT admission is undecided: no placement and no proof that none exists after {steps} search steps"
                ),
            )
            .help("use harmonic periods (each dividing the next) to make the search easy");
            if let Some((first, rest)) = named.split_first() {
                d = d.note(if rest.is_empty() {
                    format!("the search was placing {first} when it stopped")
                } else {
                    format!(
                        "the search was placing {first} when it stopped; its phases collided with {}",
                        rest.join(", ")
                    )
                });
            }
            d.note("an undecided robot is refused like an inadmissible one (`rtcan check` exits 3)")
        }
    }
}
