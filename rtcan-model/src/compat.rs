//! Which module images must be rebuilt when robot.toml changes (`check --against`).
//! A module's image depends on its own tables (bus parameters, TX/RX topics with IDs and
//! sizes, HRT calendar, master masks) and its filter banks; the global fingerprint is left
//! out of the comparison because it changes with any edit anywhere on the robot.
use crate::plan::{ModuleTables, Plan, TopicPlan};

/// One module whose image must change, with the reasons (one line each).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageChange {
    /// Module name.
    pub module: String,
    /// Why, e.g. `topic "odometry": msg_id 0x0020 -> 0x0040`.
    pub reasons: Vec<String>,
}

/// What a topic looks like to a module that sends or receives it.
fn topic_view(t: &TopicPlan) -> String {
    format!(
        "msg_id {:#06x} class {:?} size {} phase {:?} period {:?} deadline {:?}",
        t.msg_id.0, t.class, t.size, t.phase_slot, t.period_slots, t.deadline_ns
    )
}

/// Topics a module sends or receives on the bus, by name.
fn bus_topics(plan: &Plan, module: usize) -> Vec<&TopicPlan> {
    let Some(m) = plan.modules.get(module) else {
        return Vec::new();
    };
    let mut v: Vec<&TopicPlan> =
        m.tx.iter()
            .chain(m.rx.iter())
            .filter_map(|i| plan.topics.get(*i))
            .collect();
    v.sort_by(|a, b| a.name.cmp(&b.name));
    v
}

/// The bus fields that differ, `name old -> new`, comma-separated.
fn bus_diff(o: &rtcan_core::tables::BusConfig, n: &rtcan_core::tables::BusConfig) -> String {
    let mut d = Vec::new();
    let mut f = |name: &str, a: String, b: String| {
        if a != b {
            d.push(format!("{name} {a} -> {b}"));
        }
    };
    f("bitrate", o.bitrate.to_string(), n.bitrate.to_string());
    f(
        "slots_per_cycle",
        o.slots_per_cycle.to_string(),
        n.slots_per_cycle.to_string(),
    );
    f("slot_ns", o.slot_ns.to_string(), n.slot_ns.to_string());
    f(
        "hyperperiod_cycles",
        o.hyperperiod_cycles.to_string(),
        n.hyperperiod_cycles.to_string(),
    );
    f(
        "cycle_counter_wrap",
        o.cycle_counter_wrap.to_string(),
        n.cycle_counter_wrap.to_string(),
    );
    f(
        "laxity",
        format!("{:?}", o.laxity),
        format!("{:?}", n.laxity),
    );
    f("guard_ns", o.guard_ns.to_string(), n.guard_ns.to_string());
    d.join(", ")
}

fn without_fingerprint(mut t: ModuleTables) -> ModuleTables {
    t.bus.fingerprint = 0;
    t
}

/// Modules of `new` whose image differs from the one built from `old`, in `new`'s module
/// order. Modules removed in `new` are not listed (they have no image to build).
pub fn images_to_change(old: &Plan, new: &Plan) -> Vec<ImageChange> {
    let mut out = Vec::new();
    for (ni, nm) in new.modules.iter().enumerate() {
        let Some(oi) = old.modules.iter().position(|m| m.name == nm.name) else {
            out.push(ImageChange {
                module: nm.name.clone(),
                reasons: vec!["new module".to_string()],
            });
            continue;
        };
        let mut reasons = Vec::new();
        let (ot, nt) = match (old.tables(oi), new.tables(ni)) {
            (Some(o), Some(n)) => (without_fingerprint(o), without_fingerprint(n)),
            _ => continue,
        };
        if ot.bus != nt.bus {
            reasons.push(format!("bus parameters: {}", bus_diff(&ot.bus, &nt.bus)));
        }
        if ot.module != nt.module {
            reasons.push(format!("module index {} -> {}", ot.module, nt.module));
        }
        let ov = bus_topics(old, oi);
        let nv = bus_topics(new, ni);
        for t in &nv {
            match ov.iter().find(|o| o.name == t.name) {
                None => reasons.push(format!("topic \"{}\": added", t.name)),
                Some(o) if topic_view(o) != topic_view(t) => reasons.push(format!(
                    "topic \"{}\": {} -> {}",
                    t.name,
                    topic_view(o),
                    topic_view(t)
                )),
                Some(_) => {}
            }
        }
        for o in &ov {
            if !nv.iter().any(|t| t.name == o.name) {
                reasons.push(format!("topic \"{}\": removed", o.name));
            }
        }
        if ot.calendar != nt.calendar {
            reasons.push("HRT calendar changed".to_string());
        }
        if ot.master_masks != nt.master_masks {
            reasons.push("master reservation masks changed".to_string());
        }
        // The hardware filters only: a bank's purpose names topics by plan index, which
        // shifts when a topic is added before others (e.g. before the service topics).
        let filters =
            |m: &crate::plan::ModulePlan| m.banks.iter().map(|b| b.filter).collect::<Vec<_>>();
        let ob = old.modules.get(oi).map(filters);
        if ob != Some(filters(nm)) {
            reasons.push("CAN filter banks changed".to_string());
        }
        if reasons.is_empty() && ot != nt {
            // Same topics and calendar but different layout (e.g. arena offsets).
            reasons.push("tables changed".to_string());
        }
        if !reasons.is_empty() {
            out.push(ImageChange {
                module: nm.name.clone(),
                reasons,
            });
        }
    }
    out
}

/// JSON form for `check --against`: `[{"module": .., "reasons": [..]}, ..]`.
pub fn json(changes: &[ImageChange]) -> serde_json::Value {
    serde_json::Value::Array(
        changes
            .iter()
            .map(|c| serde_json::json!({ "module": c.module, "reasons": c.reasons }))
            .collect(),
    )
}

/// Text form for `check --against`.
pub fn text(changes: &[ImageChange]) -> String {
    let mut s = format!("images to change: {}\n", changes.len());
    for c in changes {
        s.push_str(&format!("  {}\n", c.module));
        for r in &c.reasons {
            s.push_str(&format!("    - {r}\n"));
        }
    }
    s
}

/// `check --json` output with `images_to_change` added when `--against` was given.
pub fn json_text(a: &crate::Analysis, changes: Option<&[ImageChange]>) -> String {
    let mut v = crate::report::json(a);
    if let (Some(p), Some(obj)) = (&a.plan, v.as_object_mut()) {
        obj.insert("moves".to_string(), crate::lock::json(&p.moves));
        obj.insert("chains".to_string(), crate::chains::json(&p.chains));
    }
    if let (Some(c), Some(obj)) = (changes, v.as_object_mut()) {
        obj.insert("images_to_change".to_string(), json(c));
    }
    serde_json::to_string_pretty(&v).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}
