//! Supervision rules (docs/SERVICES.md §1, docs/ROBOT_TOML.md "Supervision"):
//! `[modules.<m>] on_missing = "safe_all" | "safe_dependents" | "warn"` with an optional
//! `dependents = ["module", ...]`, and the heartbeat period that follows from them.
//!
//! A robot that declares any `on_missing` is *supervised*: its modules beat faster
//! (`heartbeat_cycles`, chosen so that every module's heartbeat together takes at most
//! [`HEARTBEAT_SHARE`] of a cycle) so that a dead module is shown missing within
//! `heartbeat_cycles + MISSING_SLACK_CYCLES + 1` cycles. A robot without rules keeps the
//! engine's default period (`HEARTBEAT_PERIOD_CYCLES`), bit for bit as before.
use crate::diag::{Code, Diagnostic};
use crate::model::Model;
use crate::syntax::{Entry, Kind, Node};
use rtcan_core::heartbeat::{HEARTBEAT_DLC, HEARTBEAT_PERIOD_CYCLES};

/// What a missing module means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OnMissing {
    /// Every module enters its safe state.
    SafeAll,
    /// Its dependents enter their safe state.
    SafeDependents,
    /// Shown in the module table only.
    Warn,
}

impl OnMissing {
    /// Name as written in robot.toml.
    pub const fn name(self) -> &'static str {
        match self {
            OnMissing::SafeAll => "safe_all",
            OnMissing::SafeDependents => "safe_dependents",
            OnMissing::Warn => "warn",
        }
    }
    fn parse(s: &str) -> Option<OnMissing> {
        [
            OnMissing::SafeAll,
            OnMissing::SafeDependents,
            OnMissing::Warn,
        ]
        .into_iter()
        .find(|o| o.name() == s)
    }
}

/// One module's rule.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rule {
    /// Module index.
    pub module: usize,
    pub on_missing: OnMissing,
    /// Module indices that enter their safe state under `SafeDependents` (sorted): the
    /// `dependents` list, or by default the modules subscribing to its topics.
    pub dependents: Vec<usize>,
}

/// The robot's supervision.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Supervision {
    /// Rules in module order (modules without `on_missing` have none: warn).
    pub rules: Vec<Rule>,
    /// Heartbeat period of every module, in cycles.
    pub heartbeat_cycles: u32,
}

impl Default for Supervision {
    fn default() -> Self {
        Supervision {
            rules: Vec::new(),
            heartbeat_cycles: HEARTBEAT_PERIOD_CYCLES,
        }
    }
}

/// Most of a cycle the heartbeats of a supervised robot may take together: with 6
/// modules at 1 Mbit/s and a 10 ms cycle, 6 worst-case heartbeat frames (~0.8 ms) fit
/// every cycle; a robot with 64 modules beats every 7 cycles instead.
pub const HEARTBEAT_SHARE: f64 = 0.1;

/// The heartbeat period of a supervised robot: the shortest in `1..=HEARTBEAT_PERIOD_CYCLES`
/// whose heartbeats take at most `HEARTBEAT_SHARE` of a cycle.
pub fn fast_heartbeat_cycles(modules: usize, bitrate: u32, cycle_ns: u64) -> u32 {
    let frame = rtcan_core::timing::worst_case_ns(HEARTBEAT_DLC, bitrate.max(1));
    let per_cycle = modules as f64 * frame as f64;
    let budget = HEARTBEAT_SHARE * cycle_ns as f64;
    (1..HEARTBEAT_PERIOD_CYCLES)
        .find(|p| per_cycle / f64::from(*p) <= budget)
        .unwrap_or(HEARTBEAT_PERIOD_CYCLES)
}

fn err(code: Code, n: &Node, msg: String, help: &str) -> Diagnostic {
    Diagnostic::new(code, n.span.clone(), msg).help(help)
}

/// Modules that subscribe to a topic published on module `m` (other than `m`), sorted.
pub fn subscribers_of(model: &Model, m: usize) -> Vec<usize> {
    // The module-state topics go to the sync-capable modules whatever the rules say.
    let mut out: Vec<usize> = model
        .topics
        .iter()
        .enumerate()
        .filter(|(i, _)| !model.is_module_state_topic(*i))
        .map(|(_, t)| t)
        .filter(|t| model.node_module(t.publisher) == m)
        .flat_map(|t| t.subscribers.iter().map(|s| model.node_module(s.node)))
        .filter(|&d| d != m)
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// Reads `on_missing` / `dependents` of every `[modules.<m>]` in `root`; errors to `items`.
/// `bitrate` and `cycle_ns` (the planned bus) set the heartbeat period.
pub fn validate(
    root: &[Entry],
    model: &Model,
    bitrate: u32,
    cycle_ns: u64,
    items: &mut Vec<Diagnostic>,
) -> Supervision {
    let mut rules = Vec::new();
    let modules = root.iter().find(|e| e.key == "modules");
    let Some(Kind::Table(modules)) = modules.map(|e| &e.value.kind) else {
        return Supervision::default();
    };
    for e in modules {
        let (Some(mi), Kind::Table(keys)) = (
            model.modules.iter().position(|m| m.name == e.key),
            &e.value.kind,
        ) else {
            continue; // reported by validate
        };
        let get = |k: &str| keys.iter().find(|x| x.key == k).map(|x| &x.value);
        let what = format!("module `{}`", e.key);
        let on_missing = match get("on_missing") {
            None => None,
            Some(n) => match &n.kind {
                Kind::Str(s) => match OnMissing::parse(s) {
                    Some(o) => Some(o),
                    None => {
                        items.push(err(
                            Code::BadValue,
                            n,
                            format!("{what}: `on_missing` is `{s}`"),
                            "expected \"safe_all\", \"safe_dependents\" or \"warn\"",
                        ));
                        continue;
                    }
                },
                other => {
                    items.push(err(
                        Code::WrongType,
                        n,
                        format!(
                            "{what}: `on_missing` must be a string, found {}",
                            other.type_name()
                        ),
                        "e.g. `on_missing = \"safe_dependents\"`",
                    ));
                    continue;
                }
            },
        };
        let dependents = match get("dependents") {
            None => None,
            Some(n) => match dependents(n, &what, mi, model, items) {
                Some(d) => Some((n, d)),
                None => continue,
            },
        };
        let on_missing = match (on_missing, dependents) {
            (None, None) => continue,
            (Some(o @ OnMissing::SafeDependents), d) => {
                let deps = d.map_or_else(|| subscribers_of(model, mi), |(_, d)| d);
                Rule {
                    module: mi,
                    on_missing: o,
                    dependents: deps,
                }
            }
            (Some(o), None) => Rule {
                module: mi,
                on_missing: o,
                dependents: Vec::new(),
            },
            (o, Some((n, _))) => {
                items.push(err(
                    Code::BadValue,
                    n,
                    format!(
                        "{what}: `dependents` without `on_missing = \"safe_dependents\"`{}",
                        o.map_or(String::new(), |o| format!(" (it is `{}`)", o.name()))
                    ),
                    "`dependents` names the modules that enter their safe state when this one is missing; add `on_missing = \"safe_dependents\"` or remove it",
                ));
                continue;
            }
        };
        rules.push(on_missing);
    }
    let heartbeat_cycles = if rules.is_empty() {
        HEARTBEAT_PERIOD_CYCLES
    } else {
        fast_heartbeat_cycles(model.modules.len(), bitrate, cycle_ns)
    };
    Supervision {
        rules,
        heartbeat_cycles,
    }
}

/// `dependents = ["m", ...]`: module names, not the module itself, no repeats; sorted
/// indices, `None` after an error.
fn dependents(
    n: &Node,
    what: &str,
    me: usize,
    model: &Model,
    items: &mut Vec<Diagnostic>,
) -> Option<Vec<usize>> {
    let Kind::Array(list) = &n.kind else {
        items.push(err(
            Code::WrongType,
            n,
            format!(
                "{what}: `dependents` must be an array of module names, found {}",
                n.kind.type_name()
            ),
            "e.g. `dependents = [\"motor1\", \"motor2\"]`",
        ));
        return None;
    };
    let before = items.len();
    let mut out = Vec::new();
    for d in list {
        let Kind::Str(name) = &d.kind else {
            items.push(err(
                Code::WrongType,
                d,
                format!(
                    "{what}: a dependent must be a module name, found {}",
                    d.kind.type_name()
                ),
                "e.g. `dependents = [\"motor1\"]`",
            ));
            continue;
        };
        match model.modules.iter().position(|m| &m.name == name) {
            None => {
                let names: Vec<&str> = model.modules.iter().map(|m| m.name.as_str()).collect();
                items.push(err(
                    Code::UnknownModule,
                    d,
                    format!("{what}: unknown dependent module `{name}`"),
                    &format!("modules: {}", names.join(", ")),
                ));
            }
            Some(i) if i == me => items.push(err(
                Code::BadValue,
                d,
                format!("{what} lists itself as a dependent"),
                "a missing module cannot act on its own absence; list the modules that depend on it",
            )),
            Some(i) if out.contains(&i) => items.push(err(
                Code::DuplicateName,
                d,
                format!("{what}: dependent `{name}` listed twice"),
                "list each dependent module once",
            )),
            Some(i) => out.push(i),
        }
    }
    out.sort_unstable();
    (items.len() == before).then_some(out)
}

#[cfg(test)]
mod tests {
    use crate::diag::Code;

    const BASE: &str = r#"
[bus]
bitrate = "1Mbit/s"
cycle = "10ms"
slots = 20
master = "a"
[types.T]
x = "u32"
[modules.a]
board = "stm32f103c8"
[modules.b]
board = "stm32f103c8"
[modules.c]
board = "stm32f103c8"
[nodes.na]
module = "a"
[nodes.nb]
module = "b"
[nodes.nc]
module = "c"
[topics.t]
type = "T"
publisher = "nb"
class = "nrt"
rate = "10Hz"
subscribers = ["nc"]
"#;

    fn with(extra_b: &str) -> crate::Analysis {
        let src = BASE.replace(
            "[modules.b]\nboard = \"stm32f103c8\"",
            &format!("[modules.b]\nboard = \"stm32f103c8\"\n{extra_b}"),
        );
        crate::analyze("r.toml", &src)
    }

    #[test]
    fn no_rule_keeps_the_default_heartbeat() {
        let a = with("");
        let p = a.plan.unwrap();
        assert!(p.supervision.rules.is_empty());
        assert_eq!(p.supervision.heartbeat_cycles, 10);
    }

    #[test]
    fn rules_parsed_with_default_and_explicit_dependents() {
        let p = with("on_missing = \"safe_dependents\"").plan.unwrap();
        let r = &p.supervision.rules;
        assert_eq!(r.len(), 1);
        assert_eq!(
            (r[0].module, r[0].on_missing),
            (1, super::OnMissing::SafeDependents)
        );
        // b publishes t, subscribed on c.
        assert_eq!(r[0].dependents, vec![2]);
        // 3 modules × 135 µs ≤ 1 ms: every cycle.
        assert_eq!(p.supervision.heartbeat_cycles, 1);
        let p = with("on_missing = \"safe_dependents\"\ndependents = [\"c\", \"a\"]")
            .plan
            .unwrap();
        assert_eq!(p.supervision.rules[0].dependents, vec![0, 2]);
        let p = with("on_missing = \"safe_all\"").plan.unwrap();
        assert_eq!(p.supervision.rules[0].on_missing, super::OnMissing::SafeAll);
        assert!(p.supervision.rules[0].dependents.is_empty());
        let p = with("on_missing = \"warn\"").plan.unwrap();
        assert_eq!(p.supervision.rules[0].on_missing, super::OnMissing::Warn);
    }

    fn one_error(extra: &str) -> (Code, String) {
        let a = with(extra);
        assert!(a.plan.is_none(), "{extra}");
        assert_eq!(a.diagnostics.items.len(), 1, "{}", a.diagnostics.render());
        let d = &a.diagnostics.items[0];
        let text = a.diagnostics.render();
        // rustc-style: file:line:col and a hint.
        assert!(text.contains("r.toml:"), "{text}");
        assert!(text.contains("help:"), "{text}");
        (d.code, text)
    }

    #[test]
    fn bad_rules_are_refused_with_a_location_and_a_hint() {
        let (c, t) = one_error("on_missing = \"panic\"");
        assert_eq!(c, Code::BadValue);
        assert!(
            t.contains("`on_missing` is `panic`") && t.contains("safe_dependents"),
            "{t}"
        );
        let (c, _) = one_error("on_missing = 3");
        assert_eq!(c, Code::WrongType);
        let (c, t) = one_error("on_missing = \"safe_dependents\"\ndependents = [\"zz\"]");
        assert_eq!(c, Code::UnknownModule);
        assert!(t.contains("modules: a, b, c"), "{t}");
        let (c, _) = one_error("on_missing = \"safe_dependents\"\ndependents = [\"b\"]");
        assert_eq!(c, Code::BadValue);
        let (c, _) = one_error("on_missing = \"safe_dependents\"\ndependents = [\"a\", \"a\"]");
        assert_eq!(c, Code::DuplicateName);
        let (c, _) = one_error("on_missing = \"safe_dependents\"\ndependents = \"a\"");
        assert_eq!(c, Code::WrongType);
        let (c, _) = one_error("on_missing = \"safe_dependents\"\ndependents = [1]");
        assert_eq!(c, Code::WrongType);
        let (c, t) = one_error("on_missing = \"warn\"\ndependents = [\"a\"]");
        assert_eq!(c, Code::BadValue);
        assert!(t.contains("(it is `warn`)"), "{t}");
        let (c, _) = one_error("dependents = [\"a\"]");
        assert_eq!(c, Code::BadValue);
        // The column points at the value.
        let a = with("on_missing = \"panic\"");
        let text = a.diagnostics.render();
        assert!(text.contains("r.toml:13:14"), "{text}");
    }

    #[test]
    fn heartbeat_period_grows_with_the_module_count() {
        // 1 Mbit/s, 10 ms: a 5-byte extended frame is at most 135 bits.
        assert_eq!(super::fast_heartbeat_cycles(6, 1_000_000, 10_000_000), 1);
        assert_eq!(super::fast_heartbeat_cycles(8, 1_000_000, 10_000_000), 2);
        assert_eq!(super::fast_heartbeat_cycles(64, 1_000_000, 10_000_000), 9);
        // 125 kbit/s: 64 heartbeats take 69 ms: no period up to 9 fits, the default.
        assert_eq!(super::fast_heartbeat_cycles(64, 125_000, 10_000_000), 10);
    }
}
