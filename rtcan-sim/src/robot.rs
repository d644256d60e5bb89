//! A scenario from any robot.toml: the plan's per-module tables, HRT topics always
//! sampled, SRT/NRT topics driven by generators (declared rates by default, or a user
//! traffic file, docs/SIM.md).
use rtcan_core::{Class, Nanos};
use rtcan_model::Plan;

use crate::run::{topic_infos, Scenario};
use crate::tables::OwnedTables;
use crate::traffic::{tier, Gen, GenKind, TIERS, WARMUP_NS};

/// A traffic override for one topic (by name).
#[derive(Clone, Debug, PartialEq)]
pub struct Traffic {
    /// Topic name.
    pub topic: String,
    /// Arrival process.
    pub kind: GenKind,
}

/// The scenario of `new` with the modules named in `old_images` running the tables of
/// `old` (images built from an older robot.toml of the same robot.lock), for the
/// incremental-change tests: what an old image does on a bus of new ones.
pub fn mixed_scenario(old: &Plan, new: &Plan, old_images: &[&str]) -> Result<Scenario, String> {
    let mut sc = scenario(new, &[])?;
    for (i, m) in new.modules.iter().enumerate() {
        if old_images.contains(&m.name.as_str()) {
            let oi = old
                .modules
                .iter()
                .position(|o| o.name == m.name)
                .ok_or_else(|| format!("module `{}` is not in the old plan", m.name))?;
            let (Some(slot), Some(t)) = (sc.tables.get_mut(i), old.tables(oi)) else {
                return Err(format!("no tables for module `{}`", m.name));
            };
            *slot = t;
        }
    }
    Ok(sc)
}

/// Builds the scenario of `plan`; `traffic` overrides declared rates per topic. Topics
/// without a rate and without an override send nothing.
pub fn scenario(plan: &Plan, traffic: &[Traffic]) -> Result<Scenario, String> {
    let by_name: std::collections::HashMap<&str, &rtcan_model::TopicPlan> =
        plan.topics.iter().map(|t| (t.name.as_str(), t)).collect();
    let mut kinds: std::collections::HashMap<&str, GenKind> = std::collections::HashMap::new();
    for t in traffic {
        match by_name.get(t.topic.as_str()) {
            None => return Err(format!("traffic for unknown topic `{}`", t.topic)),
            Some(p) if p.class == Class::Hrt => {
                return Err(format!(
                    "traffic for HRT topic `{}`: HRT topics send a fresh sample in every calendar slot; traffic applies to SRT and NRT topics",
                    t.topic
                ))
            }
            Some(_) => {
                kinds.insert(t.topic.as_str(), t.kind);
            }
        }
    }
    let mut tables = Vec::new();
    let mut gens = Vec::new();
    for (i, m) in plan.modules.iter().enumerate() {
        let t = plan
            .tables(i)
            .ok_or_else(|| format!("no tables for module {}", m.name))?;
        let ot: OwnedTables = t;
        if tier(&ot).is_none() {
            return Err(format!(
                "module {} receives {} topics in {} arena bytes; the simulator holds at most {} topics and {} bytes",
                m.name,
                ot.rx.len(),
                ot.arena_bytes(),
                TIERS[2].0,
                TIERS[2].1
            ));
        }
        if m.tx.len() > usize::from(u8::MAX) + 1 {
            return Err(format!(
                "module {} sends {} topics; a module's transmit topics are numbered by a byte (at most 256)",
                m.name,
                m.tx.len()
            ));
        }
        let mut g = Vec::new();
        for (k, &ti) in m.tx.iter().enumerate() {
            let Some(topic) = plan.topics.get(ti) else {
                continue;
            };
            let tx = k as u8;
            if topic.class == Class::Hrt {
                // A fresh sample of the topic's full size in every slot (a multi-frame
                // HRT topic sends all its fragments, as a node's would).
                g.push(Gen {
                    size: usize::from(topic.size),
                    ..Gen::hrt(tx)
                });
                continue;
            }
            let kind = match kinds.get(topic.name.as_str()) {
                Some(k) => Some(*k),
                None => topic.rate_hz.filter(|r| *r > 0.0).map(|r| {
                    let mean = 1e9 / r;
                    GenKind::Random {
                        lo: (mean * 0.5) as Nanos,
                        hi: (mean * 1.5) as Nanos,
                    }
                }),
            };
            if let Some(kind) = kind {
                g.push(Gen {
                    tx,
                    kind,
                    size: usize::from(topic.size),
                    start_ns: WARMUP_NS,
                });
            }
        }
        tables.push(ot);
        gens.push(g);
    }
    let master = plan.bus.master;
    let name = |n: usize, k: usize| -> String {
        plan.modules
            .get(n)
            .and_then(|m| m.tx.get(k))
            .and_then(|&ti| plan.topics.get(ti))
            .map_or_else(|| "?".into(), |t| t.name.clone())
    };
    let period = |n: usize, k: usize| -> u64 {
        plan.modules
            .get(n)
            .and_then(|m| m.tx.get(k))
            .and_then(|&ti| plan.topics.get(ti))
            .and_then(|t| t.period_slots)
            .map_or(0, u64::from)
    };
    let topics = topic_infos(&tables, name, period);
    Ok(Scenario {
        tables,
        gens,
        topics,
        master,
        names: plan.modules.iter().map(|m| m.name.clone()).collect(),
    })
}

/// Scales every SRT/NRT event rate of `sc` by `load` (inter-arrival times divided by it;
/// 1.0 leaves them as they are). HRT topics are sampled by the calendar, not scaled.
pub fn scale_load(sc: &mut Scenario, load: f64) {
    let scale = |ns: Nanos| ((ns as f64 / load) as Nanos).max(1);
    for g in sc.gens.iter_mut().flatten() {
        g.kind = match g.kind {
            GenKind::Random { lo, hi } => GenKind::Random {
                lo: scale(lo),
                hi: scale(hi),
            },
            GenKind::Periodic { period } => GenKind::Periodic {
                period: scale(period),
            },
            GenKind::Hrt => GenKind::Hrt,
        };
    }
}

/// A user scenario file: the robot it runs and traffic per topic.
///
/// ```toml
/// robot = "../../robots/rtcan-paper.toml"   # relative to this file
/// [traffic]
/// "s_a*" = { every = ["10ms", "20ms"] }    # uniform inter-arrival; trailing * = prefix
/// s_c1_1 = { period = "50ms" }             # periodic
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct UserScenario {
    /// Path of the robot.toml (resolved against the scenario file's directory).
    pub robot: std::path::PathBuf,
    /// Patterns and processes in file order.
    pub traffic: Vec<(String, GenKind)>,
    /// Scripted faults (`fault::parse` syntax, the robot's module names), e.g.
    /// `faults = ["node3:stuck@1s", "node3:release@2s"]`.
    pub faults: Vec<String>,
}

fn duration(v: &toml_edit::Item, what: &str) -> Result<Nanos, String> {
    let s = v
        .as_str()
        .ok_or_else(|| format!("{what}: expected a duration string like \"10ms\""))?;
    rtcan_model::units::duration_ns(s).map_err(|e| format!("{what}: {e}"))
}

/// Parses a scenario file's text; `dir` resolves the robot path.
pub fn parse_user(text: &str, dir: &std::path::Path) -> Result<UserScenario, String> {
    let doc: toml_edit::DocumentMut = text
        .parse()
        .map_err(|e: toml_edit::TomlError| e.to_string())?;
    let robot = doc
        .get("robot")
        .and_then(|r| r.as_str())
        .ok_or("missing `robot = \"path/to/robot.toml\"`")?;
    let mut traffic = Vec::new();
    if let Some(t) = doc.get("traffic") {
        let t = t.as_table_like().ok_or("`traffic` must be a table")?;
        for (pattern, v) in t.iter() {
            let v = v.as_table_like().ok_or_else(|| {
                format!("traffic.{pattern}: expected {{ every = [..] }} or {{ period = .. }}")
            })?;
            let kind = if let Some(e) = v.get("every") {
                let arr = e
                    .as_array()
                    .ok_or_else(|| format!("traffic.{pattern}.every: expected [min, max]"))?;
                let vals: Vec<&str> = arr.iter().filter_map(|x| x.as_str()).collect();
                let [lo, hi] = vals.as_slice() else {
                    return Err(format!("traffic.{pattern}.every: expected two durations"));
                };
                let lo = rtcan_model::units::duration_ns(lo)
                    .map_err(|e| format!("traffic.{pattern}.every: {e}"))?;
                let hi = rtcan_model::units::duration_ns(hi)
                    .map_err(|e| format!("traffic.{pattern}.every: {e}"))?;
                if lo == 0 || hi < lo {
                    return Err(format!("traffic.{pattern}.every: need 0 < min <= max"));
                }
                GenKind::Random { lo, hi }
            } else if let Some(p) = v.get("period") {
                let period = duration(p, &format!("traffic.{pattern}.period"))?;
                if period == 0 {
                    return Err(format!("traffic.{pattern}.period: must be > 0"));
                }
                GenKind::Periodic { period }
            } else {
                return Err(format!("traffic.{pattern}: expected `every` or `period`"));
            };
            traffic.push((pattern.to_string(), kind));
        }
    }
    let mut faults = Vec::new();
    if let Some(f) = doc.get("faults") {
        let bad = "`faults` must be an array of strings like \"node3:stuck@1s\"";
        for v in f.as_array().ok_or(bad)?.iter() {
            faults.push(v.as_str().ok_or(bad)?.to_string());
        }
    }
    Ok(UserScenario {
        robot: dir.join(robot),
        traffic,
        faults,
    })
}

/// Expands the patterns of `user` over the topics of `plan` (first matching pattern wins).
pub fn expand(user: &UserScenario, plan: &Plan) -> Result<Vec<Traffic>, String> {
    let mut out: Vec<Traffic> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for (pattern, kind) in &user.traffic {
        let matching: Vec<&rtcan_model::TopicPlan> = plan
            .topics
            .iter()
            .filter(|t| match pattern.strip_suffix('*') {
                Some(prefix) => t.name.starts_with(prefix),
                None => t.name == *pattern,
            })
            .collect();
        if matching.is_empty() {
            return Err(format!(
                "traffic pattern `{pattern}` matches no topic of the robot"
            ));
        }
        if let Some(h) = matching.iter().find(|t| t.class == Class::Hrt) {
            return Err(format!(
                "traffic pattern `{pattern}` matches HRT topic `{}`: HRT topics send a fresh sample in every calendar slot; traffic applies to SRT and NRT topics",
                h.name
            ));
        }
        let matches = matching.iter().map(|t| t.name.as_str());
        for m in matches {
            if seen.insert(m) {
                out.push(Traffic {
                    topic: m.to_string(),
                    kind: *kind,
                });
            }
        }
    }
    Ok(out)
}
