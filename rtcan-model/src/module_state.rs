//! The module-state topics of a supervised robot (docs/SERVICES.md §1): every module's
//! engine health (`health_<module>`) and the module table (`module_state_<module>`, one
//! per module that may be the sync master). Like a service's topics they are appended
//! after the declared topics (and the services' ones), so they get message IDs after
//! theirs and no existing ID moves; their types `ModuleHealth` and `ModuleState` are
//! appended after the declared types.
//!
//! Why one table topic per sync-capable module rather than one topic: a topic has exactly
//! one transmitter (docs/PROTOCOL.md §2.3). The current sync master publishes its own;
//! `rtcan echo module_state` shows every topic of the family.
//!
//! The wire layouts are `rtcan_pubsub::supervision`'s (`EngineHealth::encode`,
//! `ModuleTable::encode`), written here as field tables so the generated structs, the
//! host's decoder and `--json` all read them like any topic.
use crate::diag::{Code, Diagnostic};
use crate::model::{Field, FieldType, Model, MsgType, Prim, Subscriber, Topic, TopicSpans};
use crate::names;
use crate::syntax::{Entry, Kind};
use rtcan_core::fragment::MAX_PAYLOAD;
use rtcan_core::Class;

/// Name shared by the table topics (`module_state_<module>`): `rtcan echo module_state`.
pub const FAMILY: &str = "module_state";
/// Prefix of the health topics (`health_<module>`).
pub const HEALTH_PREFIX: &str = "health";
/// Message type of a health topic.
pub const HEALTH_TYPE: &str = "ModuleHealth";
/// Message type of a table topic.
pub const STATE_TYPE: &str = "ModuleState";
/// How often a module publishes its health and the master its table, Hz (declared rate
/// for the bus-load check; the table is also published at once when a module's alive
/// flag or state changes: `rtcan_pubsub::supervision::Supervisor`).
pub const RATE_HZ: f64 = 10.0;

/// The appended topics (indices into the model's topics).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct StateTopics {
    /// (module, topic) of every module's health, in module order.
    pub health: Vec<(usize, usize)>,
    /// (module, topic) of every sync-capable module's table: the configured master,
    /// then the backups in rank order.
    pub tables: Vec<(usize, usize)>,
    /// The `ModuleHealth` and `ModuleState` types.
    pub health_ty: usize,
    pub state_ty: usize,
}

impl StateTopics {
    /// Whether topic `t` is one of these.
    pub fn contains(&self, t: usize) -> bool {
        self.health.iter().chain(&self.tables).any(|&(_, x)| x == t)
    }
}

fn prim(p: Prim, len: Option<u16>) -> FieldType {
    FieldType { prim: p, len }
}

/// Fields of `ModuleHealth` (`EngineHealth::encode`, 8 bytes).
pub fn health_fields() -> Vec<(&'static str, FieldType)> {
    vec![
        ("tec", prim(Prim::U8, None)),
        ("rec", prim(Prim::U8, None)),
        ("bus_off", prim(Prim::U16, None)),
        ("rx_overrun", prim(Prim::U16, None)),
        ("deadline_missed", prim(Prim::U16, None)),
    ]
}

/// Fields of `ModuleState` for `n` modules (`ModuleTable::encode`): the reporter and the
/// sync master it follows, then one array per column, indexed by module.
pub fn state_fields(n: u16) -> Vec<(&'static str, FieldType)> {
    let a = |p| prim(p, Some(n));
    vec![
        ("reporter", prim(Prim::U8, None)),
        ("sync_master", prim(Prim::U8, None)),
        ("flags", a(Prim::U8)),
        ("state", a(Prim::U8)),
        ("age", a(Prim::U8)),
        ("fingerprint", a(Prim::U32)),
        ("tec", a(Prim::U8)),
        ("rec", a(Prim::U8)),
        ("bus_off", a(Prim::U16)),
        ("rx_overrun", a(Prim::U16)),
        ("deadline_missed", a(Prim::U16)),
    ]
}

fn msg_type(name: &str, fields: Vec<(&'static str, FieldType)>) -> MsgType {
    let mut offset = 0;
    let fields: Vec<Field> = fields
        .into_iter()
        .map(|(n, ty)| {
            let f = Field {
                name: n.to_string(),
                ty,
                offset,
            };
            offset += ty.size();
            f
        })
        .collect();
    MsgType {
        name: name.to_string(),
        fields,
        size: offset,
        span: None,
    }
}

/// Whether some `[modules.<m>]` declares `on_missing` (the robot is supervised).
pub fn supervised(root: &[Entry]) -> bool {
    let Some(Kind::Table(modules)) = root
        .iter()
        .find(|e| e.key == "modules")
        .map(|e| &e.value.kind)
    else {
        return false;
    };
    modules
        .iter()
        .any(|m| matches!(&m.value.kind, Kind::Table(keys) if keys.iter().any(|k| k.key == "on_missing")))
}

/// Appends the module-state types and topics of a supervised robot to `model` (nothing
/// for a robot without `on_missing`); a name collision with a declared type or topic is
/// an error in `items`. A module without nodes has nothing to publish from: it gets no
/// health topic (its counters read 0 in the table) and, if sync-capable, no table.
pub fn append(
    root: &[Entry],
    model: &mut Model,
    items: &mut Vec<Diagnostic>,
) -> Option<StateTopics> {
    if !supervised(root) {
        return None;
    }
    let n = model.modules.len();
    let span = root
        .iter()
        .find(|e| e.key == "modules")
        .and_then(|e| e.key_span.clone());
    let before = items.len();
    let collide = |what: &str, name: &str, items: &mut Vec<Diagnostic>| {
        items.push(
            Diagnostic::new(
                Code::NameCollision,
                span.clone(),
                format!("the supervised robot (`on_missing`) needs the {what} `{name}`, which is already declared"),
            )
            .help("rename the declared one: the module-state topics and types are generated (docs/SERVICES.md §1)"),
        );
    };
    for t in [HEALTH_TYPE, STATE_TYPE] {
        if model.types.iter().any(|x| x.name == t) {
            collide("message type", t, items);
        }
    }
    let first_node = |m: usize| model.nodes.iter().position(|x| x.module == m);
    let mut masters = vec![model.bus.master];
    masters.extend(model.bus.backup_masters.iter().copied());
    masters.retain(|&m| m < n);
    masters.dedup();
    let name_of = |m: usize| model.modules.get(m).map_or("", |x| x.name.as_str());
    let health_names: Vec<(usize, String)> = (0..n)
        .filter(|&m| first_node(m).is_some())
        .map(|m| (m, format!("{HEALTH_PREFIX}_{}", name_of(m))))
        .collect();
    let table_names: Vec<(usize, String)> = masters
        .iter()
        .filter(|&&m| first_node(m).is_some())
        .map(|&m| (m, format!("{FAMILY}_{}", name_of(m))))
        .collect();
    for (_, t) in health_names.iter().chain(&table_names) {
        let alias = names::topic_alias(t);
        if model
            .topics
            .iter()
            .any(|x| &x.name == t || names::topic_alias(&x.name) == alias)
        {
            collide("topic", t, items);
        }
    }
    let state = msg_type(
        STATE_TYPE,
        state_fields(u16::try_from(n).unwrap_or(u16::MAX)),
    );
    if state.size > MAX_PAYLOAD {
        items.push(
            Diagnostic::new(
                Code::PayloadTooLarge,
                span.clone(),
                format!(
                    "the module table of {n} modules is {} bytes; a message carries at most {MAX_PAYLOAD}",
                    state.size
                ),
            )
            .help("a supervised robot has at most 16 modules"),
        );
    }
    if items.len() > before {
        return None;
    }
    model.types.push(msg_type(HEALTH_TYPE, health_fields()));
    let health_ty = model.types.len() - 1;
    model.types.push(state);
    let state_ty = model.types.len() - 1;
    let topic = |name: &str, ty: usize, publisher: usize, subs: Vec<usize>| Topic {
        name: name.to_string(),
        ty,
        publisher,
        class: Class::Nrt,
        period_slots: None,
        requested_period_ns: None,
        deadline_ns: None,
        rate_hz: Some(RATE_HZ),
        lead_ns: None,
        subscribers: subs
            .into_iter()
            .map(|node| Subscriber {
                node,
                queue: 1,
                span: None,
            })
            .collect(),
        spans: TopicSpans::default(),
    };
    let mut out = StateTopics {
        health_ty,
        state_ty,
        ..StateTopics::default()
    };
    // Health goes to every sync-capable module (the one that takes over needs the
    // counters too): adding a module changes only the sync-capable images besides its
    // own (robot.lock, tests/compat.rs).
    for (m, name) in health_names {
        let subs = masters
            .iter()
            .filter(|&&x| x != m)
            .filter_map(|&x| first_node(x))
            .collect();
        let Some(publisher) = first_node(m) else {
            continue;
        };
        model.topics.push(topic(&name, health_ty, publisher, subs));
        out.health.push((m, model.topics.len() - 1));
    }
    // The table has no subscriber on the bus: only the host reads it (`rtcan echo
    // module_state`, `rtcan monitor`), so no firmware image carries its 92-byte decoder
    // (examples/triskar2/budgets.toml) and adding a module changes no other image's
    // receive tables through it.
    for (m, name) in table_names {
        let Some(publisher) = first_node(m) else {
            continue;
        };
        model
            .topics
            .push(topic(&name, state_ty, publisher, Vec::new()));
        out.tables.push((m, model.topics.len() - 1));
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    const BASE: &str = r#"
[bus]
bitrate = "1Mbit/s"
cycle = "10ms"
slots = 20
master = "a"
backup_masters = ["c"]
[types.T]
x = "u32"
[modules.a]
board = "stm32f103c8"
[modules.b]
board = "stm32f103c8"
on_missing = "warn"
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

    #[test]
    fn topics_appended_after_the_declared_ones_with_their_ids() {
        let a = crate::analyze("r.toml", BASE);
        let p = a
            .plan
            .unwrap_or_else(|| panic!("{}", a.diagnostics.render()));
        let names: Vec<&str> = p.topics.iter().map(|t| t.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "t",
                "health_a",
                "health_b",
                "health_c",
                "module_state_a",
                "module_state_c"
            ]
        );
        let s = p.module_state.as_ref().unwrap();
        assert_eq!(s.health, vec![(0, 1), (1, 2), (2, 3)]);
        assert_eq!(s.tables, vec![(0, 4), (2, 5)]);
        // The declared topic keeps the first ID; the appended ones follow.
        let id = |i: usize| p.topics[i].msg_id.0;
        assert_eq!(id(0), 0x0140);
        assert!(
            (1..6).all(|i| id(i) > 0x0140),
            "{:?}",
            (1..6).map(id).collect::<Vec<_>>()
        );
        // Sizes: 8-byte health, 2 + 15 × 3 = 47-byte table; NRT at 10 Hz.
        assert_eq!(p.types[s.health_ty].size, 8);
        assert_eq!(p.types[s.state_ty].size, 47);
        assert_eq!(p.types[s.state_ty].name, "ModuleState");
        for i in 1..6 {
            assert_eq!(p.topics[i].class, rtcan_core::Class::Nrt);
        }
        // The same robot without `on_missing`: nothing appended, the same IDs.
        let plain = crate::analyze("r.toml", &BASE.replace("on_missing = \"warn\"\n", ""));
        let q = plain.plan.unwrap();
        assert_eq!(q.topics.len(), 1);
        assert_eq!(q.topics[0].msg_id.0, 0x0140);
        assert!(q.module_state.is_none());
    }

    #[test]
    fn column_offsets_match_the_table_wire_form() {
        let f = super::state_fields(6);
        let mut off = 0;
        let mut at = Vec::new();
        for (n, t) in &f {
            at.push((*n, off));
            off += t.size();
        }
        assert_eq!(off, 92);
        assert_eq!(
            at,
            [
                ("reporter", 0),
                ("sync_master", 1),
                ("flags", 2),
                ("state", 8),
                ("age", 14),
                ("fingerprint", 20),
                ("tec", 44),
                ("rec", 50),
                ("bus_off", 56),
                ("rx_overrun", 68),
                ("deadline_missed", 80),
            ]
        );
    }

    #[test]
    fn a_declared_name_in_the_way_is_an_error_with_a_hint() {
        let a = crate::analyze(
            "r.toml",
            &BASE.replace("[types.T]", "[types.ModuleState]\ny = \"u8\"\n[types.T]"),
        );
        assert!(a.plan.is_none());
        let text = a.diagnostics.render();
        assert!(text.contains("message type `ModuleState`"), "{text}");
        assert!(text.contains("r.toml:"), "{text}");
        assert!(text.contains("help:"), "{text}");
        let a = crate::analyze(
            "r.toml",
            &BASE.replace("[topics.t]", "[topics.health_b]\ntype = \"T\"\npublisher = \"nb\"\nclass = \"nrt\"\nrate = \"1Hz\"\nsubscribers = [\"nc\"]\n[topics.t]"),
        );
        assert!(a.plan.is_none());
        let text = a.diagnostics.render();
        assert!(text.contains("topic `health_b`"), "{text}");
    }
}
