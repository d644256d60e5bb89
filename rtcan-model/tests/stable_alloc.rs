//! Stable allocation through robot.lock (issue 14): adding a topic, a module or an HRT
//! topic to Triskar2 keeps every existing topic's ID and phase and every other module's
//! filter banks; forced moves are reported with their reason.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]
use rtcan_model::filters::FilterBank;
use rtcan_model::{analyze, analyze_locked, lock, Plan};

const TRISKAR: &str = include_str!("../../robot.toml");

fn base() -> (Plan, String) {
    let a = analyze("robot.toml", TRISKAR);
    let plan = a.plan.clone().expect("triskar2 admissible");
    let text = lock::render(a.model.as_ref().unwrap(), &plan, None);
    (plan, text)
}

fn locked(source: &str, lock_text: &str) -> Plan {
    let a = analyze_locked("robot.toml", source, Some(("robot.lock", lock_text)));
    assert!(a.diagnostics.is_empty(), "{}", a.diagnostics.render());
    a.plan.unwrap()
}

fn banks(p: &Plan, module: &str) -> Vec<FilterBank> {
    p.module(module)
        .unwrap()
        .banks
        .iter()
        .map(|b| b.filter)
        .collect()
}

/// Every topic of `old` keeps its ID and phase in `new`; every module of `old` except
/// `receivers` keeps its banks.
fn assert_stable(old: &Plan, new: &Plan, receivers: &[&str]) {
    assert_stable_but(old, new, receivers, &[]);
}

/// As `assert_stable`, the topics `moved` excepted.
fn assert_stable_but(old: &Plan, new: &Plan, receivers: &[&str], moved: &[&str]) {
    for t in old
        .topics
        .iter()
        .filter(|t| !moved.contains(&t.name.as_str()))
    {
        let n = new.topic(&t.name).unwrap();
        assert_eq!(n.msg_id, t.msg_id, "ID of {}", t.name);
        assert_eq!(n.phase_slot, t.phase_slot, "phase of {}", t.name);
        assert_eq!(n.period_slots, t.period_slots, "period of {}", t.name);
    }
    for m in &old.modules {
        let nm = new.module(&m.name).unwrap();
        assert_eq!(nm.index, m.index, "index of {}", m.name);
        if !receivers.contains(&m.name.as_str()) {
            assert_eq!(
                banks(new, &m.name),
                banks(old, &m.name),
                "banks of {}",
                m.name
            );
            assert_eq!(nm.calendar, m.calendar, "calendar of {}", m.name);
        }
    }
}

#[test]
fn lock_reproduces_the_plan_it_records() {
    let (plan, text) = base();
    let again = locked(TRISKAR, &text);
    assert!(again.moves.is_empty(), "{:?}", again.moves);
    assert_stable(&plan, &again, &[]);
    for m in &plan.modules {
        assert_eq!(
            again.tables(m.index.into()).unwrap().tx,
            plan.tables(m.index.into()).unwrap().tx
        );
    }
    // The lineage, not the whole plan, goes into the fingerprint.
    assert_eq!(again.lineage, Some(plan.fingerprint));
    assert_ne!(again.fingerprint, plan.fingerprint);
    // Writing the lock again gives the same text.
    let a = analyze_locked("robot.toml", TRISKAR, Some(("robot.lock", &text)));
    let l = lock::parse("robot.lock", &text).unwrap();
    assert_eq!(
        lock::render(a.model.as_ref().unwrap(), &again, Some(&l)),
        text
    );
}

const NEW_SRT: &str = r#"
[topics.motor_temp]
type = "Battery"
publisher = "battery_monitor"
class = "srt"
deadline = "50ms"
rate = "5Hz"
subscribers = ["kinematics"]
"#;

#[test]
fn adding_a_topic_keeps_every_existing_allocation() {
    let (plan, text) = base();
    let new = locked(&format!("{TRISKAR}{NEW_SRT}"), &text);
    assert_stable(&plan, &new, &["motor1"]);
    let t = new.topic("motor_temp").unwrap();
    // Not an ID any existing topic uses, nor one another module's filters pass.
    assert!(plan.topics.iter().all(|o| o.msg_id != t.msg_id));
    // motor1 receives it: its banks change, and only that is reported.
    assert_eq!(new.moves.len(), 1, "{:?}", new.moves);
    assert_eq!(new.moves[0].subject, "motor1");
    assert_eq!(new.moves[0].what, "filters");
    assert_eq!(new.moves[0].reason, "now receives `motor_temp`");
    // Without the lock the same edit regroups IDs (what the lock prevents).
    let fresh = analyze("robot.toml", &format!("{TRISKAR}{NEW_SRT}"))
        .plan
        .unwrap();
    assert!(plan
        .topics
        .iter()
        .any(|o| fresh.topic(&o.name).unwrap().msg_id != o.msg_id));
}

const NEW_MODULE_HRT: &str = r#"
[modules.imu]
board = "stm32f103c8"

[nodes.imu_reader]
module = "imu"
priority = 2

[topics.imu]
type = "Encoder"
publisher = "imu_reader"
class = "hrt"
rate = "100Hz"
subscribers = ["odometry"]
"#;

#[test]
fn adding_a_module_with_an_hrt_topic_keeps_every_existing_allocation() {
    let (plan, text) = base();
    let new = locked(&format!("{TRISKAR}{NEW_MODULE_HRT}"), &text);
    // Triskar2 is supervised (`on_missing`): the module tables get a row more (their
    // layout, so their IDs, change) and the sync-capable modules receive the new
    // module's health.
    let tables = ["module_state_gateway", "module_state_motor1"];
    assert_stable_but(&plan, &new, &["motor2", "gateway", "motor1"], &tables);
    let imu = new.topic("imu").unwrap();
    assert_eq!(imu.period_slots, Some(60));
    let phase = imu.phase_slot.unwrap();
    // Its slot is one no existing module transmits in.
    for m in &plan.modules {
        for c in &m.calendar {
            assert_ne!(
                u64::from(c.slot) % 60,
                u64::from(phase),
                "{} slot {}",
                m.name,
                c.slot
            );
        }
    }
    assert_eq!(new.module("imu").unwrap().index, 6);
    // Only motor2, which receives it, and the sync-capable modules, which receive its
    // health, change their filters; every move says why.
    let moves: Vec<(&str, &str, String)> = new
        .moves
        .iter()
        .map(|m| {
            let reason = m.reason.split(':').next().unwrap_or("").to_string();
            (m.subject.as_str(), m.what, reason)
        })
        .collect();
    assert_eq!(
        moves,
        [
            ("module_state_gateway", "msg_id", "layout changed".into()),
            ("module_state_motor1", "msg_id", "layout changed".into()),
            ("gateway", "filters", "now receives `health_imu`".into()),
            ("motor1", "filters", "now receives `health_imu`".into()),
            ("motor2", "filters", "now receives `imu`".into()),
        ]
    );
    assert!(new.moves[0].reason.ends_with("/107/nrt/14"));
}

#[test]
fn a_changed_layout_moves_the_id_and_reports_why() {
    let (plan, text) = base();
    let src = TRISKAR.replacen(
        "[types.Encoder]         # one motor's encoder (8 B: 1 frame)\nticks = \"i32\"",
        "[types.Encoder]\nticks = \"i16\"",
        1,
    );
    assert_ne!(src, TRISKAR);
    let new = locked(&src, &text);
    let ids: Vec<_> = new.moves.iter().filter(|m| m.what == "msg_id").collect();
    assert_eq!(ids.len(), 3, "{:?}", new.moves);
    let e1 = ids.iter().find(|m| m.subject == "encoder1").unwrap();
    assert_eq!(
        e1.from,
        format!("{:#06x}", plan.topic("encoder1").unwrap().msg_id.0)
    );
    assert!(e1.reason.starts_with("layout changed: Encoder{ticks:i32,speed:f32}/8/hrt/1 -> Encoder{ticks:i16,speed:f32}/6/hrt/1"), "{}", e1.reason);
    // The old IDs are never handed out again.
    for t in &new.topics {
        if ["encoder1", "encoder2", "encoder3"].contains(&t.name.as_str()) {
            assert!(
                plan.topics.iter().all(|o| o.msg_id != t.msg_id),
                "{}",
                t.name
            );
        }
    }
    let relock = lock::render(
        analyze_locked("robot.toml", &src, Some(("robot.lock", &text)))
            .model
            .as_ref()
            .unwrap(),
        &new,
        lock::parse("robot.lock", &text).ok().as_ref(),
    );
    let old_e1 = plan.topic("encoder1").unwrap().msg_id.0;
    // With the topic it carried and its layout then, for the host tools (stale images).
    let then = lock::parse("robot.lock", &text).unwrap().topics["encoder1"]
        .layout
        .clone();
    assert!(
        relock.contains(&format!("retired {old_e1:#06x} encoder1 {then}\n")),
        "{relock}"
    );
}

#[test]
fn a_changed_period_keeps_a_free_phase() {
    let (plan, text) = base();
    // odometry 50 Hz -> 100 Hz (120 -> 60 slots): its locked phase is still free.
    let src = TRISKAR.replacen(
        "rate = \"50Hz\"\nsubscribers = [\"ros_bridge\"]",
        "rate = \"100Hz\"\nsubscribers = [\"ros_bridge\"]",
        1,
    );
    assert_ne!(src, TRISKAR);
    let new = locked(&src, &text);
    assert!(new.moves.is_empty(), "{:?}", new.moves);
    assert_eq!(new.topic("odometry").unwrap().period_slots, Some(60));
    assert_eq!(
        new.topic("odometry").unwrap().phase_slot,
        plan.topic("odometry").unwrap().phase_slot
    );
}

#[test]
fn colliding_locked_phases_force_a_reported_move() {
    let (plan, text) = base();
    // A lock whose proximity phase collides with encoder1 (slot 1): the locked phases
    // cannot all be kept, admission runs afresh and every phase that moved is reported.
    let e1 = plan.topic("encoder1").unwrap().phase_slot.unwrap();
    let bad = text.replacen("period=240 phase=8", &format!("period=240 phase={e1}"), 1);
    assert_ne!(bad, text);
    let new = locked(TRISKAR, &bad);
    let moved: Vec<_> = new.moves.iter().filter(|m| m.what == "phase").collect();
    assert!(!moved.is_empty());
    for m in &moved {
        assert_eq!(
            m.reason,
            "the HRT set does not fit around the locked phases: full re-admission"
        );
        let t = new.topic(&m.subject).unwrap();
        assert_eq!(m.to, t.phase_slot.unwrap().to_string());
    }
    // Every phase that differs from the lock is in the report.
    let l = lock::parse("robot.lock", &bad).unwrap();
    for t in &new.topics {
        if let (Some(lt), Some(p)) = (l.topics.get(&t.name), t.phase_slot) {
            assert_eq!(
                lt.phase != Some(p),
                moved.iter().any(|m| m.subject == t.name),
                "{}",
                t.name
            );
        }
    }
}

#[test]
fn a_module_inserted_before_others_is_reported() {
    let (_, text) = base();
    let src = TRISKAR.replacen(
        "[modules.motor1]",
        "[modules.aux]\nboard = \"stm32f103c8\"\n\n[modules.motor1]",
        1,
    );
    let new = locked(&src, &text);
    let m: Vec<_> = new
        .moves
        .iter()
        .filter(|m| m.what == "module-index")
        .collect();
    assert_eq!(m.len(), 5, "{:?}", new.moves);
    assert_eq!(
        (m[0].subject.as_str(), m[0].from.as_str(), m[0].to.as_str()),
        ("motor1", "1", "2")
    );
    assert!(m[0]
        .reason
        .contains("add new modules after the existing ones"));
}

#[test]
fn a_bad_lock_is_an_error_with_file_line_col() {
    let (_, text) = base();
    let bad = text.replacen("topic teleop", "topik teleop", 1);
    let a = analyze_locked("robot.toml", TRISKAR, Some(("robot.lock", &bad)));
    assert!(a.plan.is_none());
    let d = &a.diagnostics.items[0];
    assert_eq!(d.code.name(), "lock-invalid");
    let line = bad.lines().position(|l| l.starts_with("topik")).unwrap() + 1;
    assert!(
        d.message
            .starts_with(&format!("robot.lock:{line}:1: unknown line")),
        "{}",
        d.message
    );
    assert!(!d.help.is_empty());
    // A topic ID in the sync/heartbeat range is refused (found by damaged_locks_never_panic).
    let low = text.replacen("topic teleop 0x0148", "topic teleop 0x0048", 1);
    let a = analyze_locked("robot.toml", TRISKAR, Some(("robot.lock", &low)));
    assert!(a.diagnostics.items[0]
        .message
        .contains("bad message ID (topics use 0x0140..=0xffff)"));
    for junk in [
        "",
        "version 2\n",
        "version 1\ntopic a 0x10000 x\n",
        "version 1\nbank m mask 1\n",
    ] {
        let a = analyze_locked("robot.toml", TRISKAR, Some(("robot.lock", junk)));
        assert_eq!(
            a.diagnostics.items[0].code.name(),
            "lock-invalid",
            "{junk:?}"
        );
    }
}

/// Every single-line deletion or number change of a valid lock either plans (keeping what
/// still fits, reporting the rest) or is refused with a diagnostic; it never panics, and a
/// plan made with a damaged lock is still a valid robot (same checks as without a lock).
#[test]
fn damaged_locks_never_panic() {
    let (_, text) = base();
    let lines: Vec<&str> = text.lines().collect();
    let mut variants = Vec::new();
    for i in 0..lines.len() {
        let mut v = lines.clone();
        v.remove(i);
        variants.push(v.join("\n"));
        for (from, to) in [
            ("0x01", "0x00"),
            ("phase=", "phase=9"),
            ("period=", "period=1"),
            ("0x0000", "0xffff"),
        ] {
            let mut v = lines.clone();
            let changed = v[i].replacen(from, to, 1);
            v[i] = &changed;
            variants.push(v.join("\n"));
        }
    }
    variants.push("version 1\nbank gateway mask 0 0\nbank motor1 mask 0 0\n".into());
    variants.push("version 1\ntopic teleop 0x0140 x\ntopic velocity 0x0140 y\n".into());
    let mut planned = 0;
    for v in &variants {
        let a = analyze_locked("robot.toml", TRISKAR, Some(("robot.lock", v)));
        match &a.plan {
            Some(p) => {
                planned += 1;
                // IDs stay unique and every module's banks pass exactly what it receives.
                let mut ids: Vec<u16> = p.topics.iter().map(|t| t.msg_id.0).collect();
                ids.sort_unstable();
                ids.dedup();
                assert_eq!(ids.len(), p.topics.len(), "{v}");
                assert_filters_exact(p);
            }
            None => assert!(!a.diagnostics.is_empty(), "{v}"),
        }
    }
    assert!(
        planned > variants.len() / 2,
        "{planned} of {}",
        variants.len()
    );
}

fn assert_filters_exact(p: &Plan) {
    use rtcan_core::Class;
    use rtcan_model::filters::{fixed_id, WireTopic};
    for (mi, m) in p.modules.iter().enumerate() {
        for (ti, t) in p.topics.iter().enumerate().filter(|(_, t)| t.on_bus) {
            let w = WireTopic {
                topic: ti,
                msg_id: t.msg_id.0,
                fixed_id: match (t.class, t.fragments) {
                    (Class::Hrt, 1) => Some(fixed_id(rtcan_core::id::LAXITY_HRT, t.msg_id.0)),
                    (Class::Nrt, 1) => Some(fixed_id(rtcan_core::id::LAXITY_NRT, t.msg_id.0)),
                    _ => None,
                },
            };
            if m.rx.contains(&ti) {
                assert!(
                    m.banks.iter().any(|b| lock::always_passes(&b.filter, &w)),
                    "{} {}",
                    m.name,
                    t.name
                );
            } else if t.module != mi {
                assert!(
                    !m.banks.iter().any(|b| lock::may_pass(&b.filter, &w)),
                    "{} {}",
                    m.name,
                    t.name
                );
            }
        }
    }
}
