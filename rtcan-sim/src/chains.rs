//! Measured end-to-end chain latency (issue 14), beside the build-time bound
//! (`rtcan_model::chains`). From the wire log of a run: every message of a chain's first
//! topic is followed, hop by hop, to the first message of the next topic published after
//! it was delivered (the node reads its latest input when it next runs) — the reaction
//! the bound covers. The latency is the last hop's delivery (end of its last frame) minus
//! the first message's publication.
//!
//! Publication time: an HRT message is sampled at its slot (first frame's start of
//! frame); an SRT message's release is recovered from its first frame's laxity field:
//! `sof + lower_bound(code) - deadline` (within one laxity unit plus the mailbox wait).
//! Chains through topics that never reach the wire, or NRT topics, are not measured.
use crate::bus::WireFrame;
use rtcan_core::{Class, Nanos};
use rtcan_model::Plan;
use std::fmt::Write as _;

/// One chain: bound and measured worst case.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChainMeasure {
    /// Chain name.
    pub name: String,
    /// Build-time bound, ns.
    pub bound_ns: Option<u64>,
    /// Budget, ns.
    pub budget_ns: u64,
    /// Worst measured latency, ns (`None`: nothing traced).
    pub worst_ns: Option<u64>,
    /// Messages of the first topic followed to a delivery of the last.
    pub samples: u64,
}

#[derive(Clone, Copy)]
struct Msg {
    published: i128,
    delivered: Nanos,
}

/// Complete messages of topic `t` in wire order.
fn messages(plan: &Plan, t: usize, wire: &[WireFrame]) -> Vec<Msg> {
    let Some(tp) = plan.topics.get(t) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut first: Option<&WireFrame> = None;
    for w in wire
        .iter()
        .filter(|w| w.ok && w.frame.id().msg_id() == tp.msg_id)
    {
        // Count-down counter in the low bits; the transfer ID above it (PROTOCOL.md §7).
        let bits = rtcan_core::fragment::counter_bits(tp.fragments);
        let frag = w.frame.id().fragment() & ((1u8 << bits) - 1);
        if frag + 1 == tp.fragments {
            first = Some(w);
        }
        if frag != 0 {
            continue;
        }
        let Some(f) = first.take() else { continue };
        let published = match tp.class {
            Class::Hrt => i128::from(f.sof),
            _ => {
                let lb = plan
                    .bus
                    .laxity
                    .lower_bound_ns(f.frame.id().laxity())
                    .unwrap_or(0);
                i128::from(f.sof) + i128::from(lb) - i128::from(tp.deadline_ns.unwrap_or(0))
            }
        };
        out.push(Msg {
            published,
            delivered: w.end,
        });
    }
    out
}

/// Measures every chain of `plan` on `wire`.
pub fn measure(plan: &Plan, wire: &[WireFrame]) -> Vec<ChainMeasure> {
    plan.chains
        .iter()
        .map(|c| {
            let on_wire = c.path.iter().all(|t| {
                plan.topics
                    .get(*t)
                    .is_some_and(|x| x.on_bus && x.class != Class::Nrt)
            });
            let msgs: Vec<Vec<Msg>> = if on_wire {
                c.path.iter().map(|t| messages(plan, *t, wire)).collect()
            } else {
                Vec::new()
            };
            let mut worst: Option<u64> = None;
            let mut samples = 0;
            if let Some((first, after)) = msgs.split_first() {
                for m in first {
                    let mut at = m.delivered;
                    let mut traced = true;
                    for hop in after {
                        // First message of the next topic published once this one is in.
                        let k = hop.partition_point(|x| x.published < i128::from(at));
                        match hop.get(k) {
                            Some(x) => at = x.delivered,
                            None => {
                                traced = false;
                                break;
                            }
                        }
                    }
                    if traced {
                        samples += 1;
                        let lat = u64::try_from(i128::from(at) - m.published).unwrap_or(0);
                        worst = Some(worst.map_or(lat, |w| w.max(lat)));
                    }
                }
            }
            ChainMeasure {
                name: c.name.clone(),
                bound_ns: c.bound_ns,
                budget_ns: c.budget_ns,
                worst_ns: worst,
                samples,
            }
        })
        .collect()
}

/// Message IDs of every topic on a chain of `plan`: what a run must keep of its wire for
/// `measure` (`SimConfig::keep_msg_ids`).
pub fn msg_ids(plan: &Plan) -> Vec<u16> {
    let mut ids: Vec<u16> = plan
        .chains
        .iter()
        .flat_map(|c| c.path.iter())
        .filter_map(|t| plan.topics.get(*t).map(|x| x.msg_id.0))
        .collect();
    ids.sort_unstable();
    ids.dedup();
    ids
}

/// Complete messages of topic `t` on the wire (for reports and tests).
pub fn message_count(plan: &Plan, t: usize, wire: &[WireFrame]) -> usize {
    messages(plan, t, wire).len()
}

fn ms(ns: u64) -> String {
    rtcan_model::units::fmt_ns(ns as f64)
}

/// The chains as `rtcan sim` prints them: one line each, bound and budget from the build
/// (`rtcan check`), the worst measured on this run's wire beside them. Empty without chains.
pub fn text(chains: &[ChainMeasure]) -> String {
    if chains.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "end-to-end chains (bound from robot.toml at build time; worst measured on the wire):\n",
    );
    for c in chains {
        let bound = c.bound_ns.map_or("none".to_string(), ms);
        let worst = match c.worst_ns {
            Some(w) => format!("{} over {} samples", ms(w), c.samples),
            None => "not traced (a hop off the bus, NRT, or no message)".into(),
        };
        let _ = writeln!(
            s,
            "  {:<20} bound {bound}, budget {}, measured worst {worst}",
            c.name,
            ms(c.budget_ns)
        );
    }
    s
}

/// The chains as JSON (`rtcan sim --json` field `chains`): times in ns, `null` when
/// unbounded or not traced.
pub fn json(chains: &[ChainMeasure]) -> serde_json::Value {
    serde_json::Value::Array(
        chains
            .iter()
            .map(|c| {
                serde_json::json!({
                    "name": c.name,
                    "bound_ns": c.bound_ns,
                    "budget_ns": c.budget_ns,
                    "worst_ns": c.worst_ns,
                    "samples": c.samples,
                })
            })
            .collect(),
    )
}
