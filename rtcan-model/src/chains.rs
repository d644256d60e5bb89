//! End-to-end chains (`[chains.NAME] path = ["encoder1", "odometry"], budget = "50ms"`):
//! a worst-case latency bound from the calendar, checked against the budget.
//!
//! The bound is the sum over the path of (docs/ROBOT_TOML.md "Chains"):
//! - every topic after the first: the period of its publishing node's loop (its publication
//!   period: HRT period, or 1/rate for SRT/NRT), the worst wait between the input's arrival
//!   and the next run that reads it;
//! - every topic's transit: HRT on the bus a full period (the sample just missed its slot)
//!   plus its fragments' slots; SRT on the bus its deadline (admission guarantees it); a
//!   local topic 0. An NRT topic on the bus has no bound, nor has an SRT/NRT publisher
//!   without a rate.
//!
//! Node compute time is not modelled (no per-node WCET in robot.toml).
use crate::diag::{Code, Diagnostic, Span};
use crate::model::Model;
use crate::plan::Plan;
use crate::syntax::{Entry, Kind};
use crate::units;
use rtcan_core::Class;

/// A chain with its bound.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChainBound {
    /// Name.
    pub name: String,
    /// Topic indices in path order.
    pub path: Vec<usize>,
    /// Worst-case latency bound, ns (`None`: unbounded).
    pub bound_ns: Option<u64>,
    /// Declared budget, ns.
    pub budget_ns: u64,
}

fn bad(code: Code, span: Option<Span>, msg: String, help: &str) -> Diagnostic {
    Diagnostic::new(code, span, msg).help(help)
}

/// Publication period of topic `t`, ns.
fn pub_period(plan: &Plan, t: usize) -> Option<u64> {
    let tp = plan.topics.get(t)?;
    match tp.class {
        Class::Hrt => tp.actual_period_ns(&plan.bus),
        _ => tp
            .rate_hz
            .filter(|r| *r > 0.0)
            .map(|r| (1e9 / r).ceil() as u64),
    }
}

/// Transit bound of topic `t`, ns.
fn transit(plan: &Plan, t: usize) -> Option<u64> {
    let tp = plan.topics.get(t)?;
    if !tp.on_bus {
        return Some(0);
    }
    match tp.class {
        Class::Hrt => tp
            .actual_period_ns(&plan.bus)
            .map(|p| p + u64::from(tp.fragments) * plan.bus.slot_ns),
        Class::Srt => tp.deadline_ns,
        Class::Nrt => None,
    }
}

/// The bound of a path: see the module documentation.
pub fn bound(plan: &Plan, path: &[usize]) -> Option<u64> {
    let mut total = 0u64;
    for (k, t) in path.iter().enumerate() {
        if k > 0 {
            total = total.checked_add(pub_period(plan, *t)?)?;
        }
        total = total.checked_add(transit(plan, *t)?)?;
    }
    Some(total)
}

/// Parses `[chains]`, bounds every chain and reports `chain-over-budget`.
pub fn check(
    root: &[Entry],
    model: &Model,
    plan: &Plan,
    items: &mut Vec<Diagnostic>,
) -> Vec<ChainBound> {
    let mut out = Vec::new();
    let Some(top) = root.iter().find(|e| e.key == "chains") else {
        return out;
    };
    let Kind::Table(chains) = &top.value.kind else {
        items.push(bad(
            Code::WrongType,
            top.value.span.clone(),
            "`chains` must be a table".into(),
            "write `[chains.NAME]` tables with `path` and `budget`",
        ));
        return out;
    };
    for c in chains {
        let Kind::Table(keys) = &c.value.kind else {
            items.push(bad(
                Code::WrongType,
                c.value.span.clone(),
                format!("`chains.{}` must be a table", c.key),
                "write `path = [\"topic\", ...]` and `budget = \"20ms\"`",
            ));
            continue;
        };
        let mut path: Option<Vec<usize>> = None;
        let mut budget: Option<u64> = None;
        let mut budget_span = c.key_span.clone();
        let mut ok = true;
        for e in keys {
            match (e.key.as_str(), &e.value.kind) {
                ("path", Kind::Array(xs)) if !xs.is_empty() => {
                    let mut p = Vec::new();
                    for x in xs {
                        let found = match &x.kind {
                            Kind::Str(s) => model.topics.iter().position(|t| &t.name == s),
                            _ => None,
                        };
                        match found {
                            Some(t) => p.push(t),
                            None => {
                                ok = false;
                                items.push(bad(
                                    Code::BadValue,
                                    x.span.clone(),
                                    format!("chain `{}`: not a topic name", c.key),
                                    "a chain's `path` lists topic names in data-flow order",
                                ));
                            }
                        }
                    }
                    path = Some(p);
                }
                ("budget", Kind::Str(s)) => match units::duration_ns(s) {
                    Ok(ns) if ns > 0 => {
                        budget = Some(ns);
                        budget_span = e.value.span.clone();
                    }
                    Ok(_) | Err(_) => {
                        ok = false;
                        items.push(bad(
                            Code::BadValue,
                            e.value.span.clone(),
                            format!("chain `{}`: bad budget `{s}`", c.key),
                            "a positive duration such as \"20ms\"",
                        ));
                    }
                },
                ("path" | "budget", _) => {
                    ok = false;
                    items.push(bad(
                        Code::WrongType,
                        e.value.span.clone(),
                        format!("chain `{}`: wrong type for `{}`", c.key, e.key),
                        "`path = [\"topic\", ...]` (at least one), `budget = \"20ms\"`",
                    ));
                }
                _ => {
                    ok = false;
                    items.push(bad(
                        Code::UnknownKey,
                        e.key_span.clone(),
                        format!("unknown key `{}` in `chains.{}`", e.key, c.key),
                        "a chain has `path` and `budget`",
                    ));
                }
            }
        }
        let (Some(path), Some(budget_ns), true) = (path, budget, ok) else {
            if ok {
                items.push(bad(
                    Code::MissingKey,
                    c.key_span.clone(),
                    format!("chain `{}` needs `path` and `budget`", c.key),
                    "`path = [\"topic\", ...]`, `budget = \"20ms\"`",
                ));
            }
            continue;
        };
        // Consecutive topics must be connected: the publisher of the next subscribes the previous.
        let name = |t: usize| model.topics.get(t).map_or("?", |x| x.name.as_str());
        let mut linked = true;
        for w in path.windows(2) {
            let (Some(a), Some(b)) = (
                w.first().and_then(|t| model.topics.get(*t)),
                w.get(1).and_then(|t| model.topics.get(*t)),
            ) else {
                continue;
            };
            if !a.subscribers.iter().any(|s| s.node == b.publisher) {
                linked = false;
                let node = model
                    .nodes
                    .get(b.publisher)
                    .map_or("?", |n| n.name.as_str());
                items.push(bad(
                    Code::BadValue,
                    c.key_span.clone(),
                    format!(
                        "chain `{}`: `{}` is published by `{node}`, which does not subscribe `{}`",
                        c.key, b.name, a.name
                    ),
                    "each topic of a path must be published by a subscriber of the one before",
                ));
            }
        }
        if !linked {
            continue;
        }
        let b = bound(plan, &path);
        match b {
            None => items.push(
                bad(
                    Code::ChainOverBudget,
                    budget_span,
                    format!("chain `{}` has no latency bound", c.key),
                    "make its NRT topics SRT with a deadline, and give SRT/NRT publishers a `rate`",
                )
                .note(format!(
                    "path: {}",
                    path.iter()
                        .map(|t| name(*t))
                        .collect::<Vec<_>>()
                        .join(" -> ")
                )),
            ),
            Some(ns) if ns > budget_ns => {
                let worst = path
                    .iter()
                    .enumerate()
                    .max_by_key(|(k, t)| {
                        transit(plan, **t).unwrap_or(0)
                            + if *k > 0 {
                                pub_period(plan, **t).unwrap_or(0)
                            } else {
                                0
                            }
                    })
                    .map_or("?", |(_, t)| name(*t));
                items.push(
                    bad(
                        Code::ChainOverBudget,
                        budget_span,
                        format!(
                            "chain `{}`: worst-case latency {} exceeds its budget {}",
                            c.key,
                            units::fmt_ns(ns as f64),
                            units::fmt_ns(budget_ns as f64)
                        ),
                        &format!("the largest term is `{worst}`: shorten its period or deadline, or raise the budget"),
                    )
                    .note("bound = publisher loop periods + HRT period and slots / SRT deadline of each topic on the bus"),
                );
            }
            Some(_) => {}
        }
        out.push(ChainBound {
            name: c.key.clone(),
            path,
            bound_ns: b,
            budget_ns,
        });
    }
    out
}

/// JSON for `rtcan check --json`: `[{name, bound_ns, budget_ns}]`.
pub fn json(chains: &[ChainBound]) -> serde_json::Value {
    serde_json::Value::Array(
        chains
            .iter()
            .map(|c| serde_json::json!({"name": c.name, "bound_ns": c.bound_ns, "budget_ns": c.budget_ns}))
            .collect(),
    )
}
