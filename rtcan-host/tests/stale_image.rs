//! An incompatible image named at run time (issue 14): Triskar2 with a robot.lock, then the
//! `Encoder` type changes (`speed` f32 → i32, same size), so encoder1 and encoder3 are
//! re-laid out under new IDs and their old IDs retired. motor3 keeps its old image. Its
//! heartbeat carries the same compatibility fingerprint (same lineage), so only its frames
//! under the retired ID show it: `rtcan monitor` and `rtcan decode` must name the topic,
//! its layout then and now, and the module to reflash. With every image new, nothing is
//! reported (the check can fail both ways).
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use rtcan_core::engine::Policy;
use rtcan_host::monitor::Monitor;
use rtcan_host::Stamped;
use rtcan_model::{analyze, analyze_locked, lock, Plan};
use rtcan_sim::candump::Entry;
use rtcan_sim::decode::{plan_catalog, Decoded, Decoder};
use rtcan_sim::policy::PolicyKind;
use rtcan_sim::run::{run_engine, SimConfig};

const TRISKAR: &str = include_str!("../../robot.toml");

/// The old plan, the lock written from it, the new plan (Encoder re-laid out) with it.
fn plans() -> (Plan, Plan) {
    let a = analyze("robot.toml", TRISKAR);
    let lock = lock::render(a.model.as_ref().unwrap(), a.plan.as_ref().unwrap(), None);
    let new_toml = TRISKAR.replacen(
        "[types.Encoder]         # one motor's encoder (8 B: 1 frame)\nticks = \"i32\"\nspeed = \"f32\"",
        "[types.Encoder]\nticks = \"i32\"\nspeed = \"i32\"",
        1,
    );
    assert_ne!(
        new_toml, TRISKAR,
        "robot.toml's Encoder type moved: update the test"
    );
    let locked = |s: &str| {
        analyze_locked("robot.toml", s, Some(("robot.lock", &lock)))
            .plan
            .unwrap()
    };
    (locked(TRISKAR), locked(&new_toml))
}

fn id_of(plan: &Plan, topic: &str) -> u16 {
    plan.topics
        .iter()
        .find(|t| t.name == topic)
        .unwrap()
        .msg_id
        .0
}

/// 0.3 s of the new plan with `old_images` on the old plan's tables: every frame on the
/// wire, as a host sees them.
fn wire(old: &Plan, new: &Plan, old_images: &[&str]) -> Vec<Stamped> {
    let sc = rtcan_sim::robot::mixed_scenario(old, new, old_images).unwrap();
    let cfg = SimConfig {
        seconds: 0.3,
        ..SimConfig::default()
    };
    let run = run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS).unwrap();
    run.wire
        .iter()
        .filter(|w| w.ok)
        .map(|w| Stamped {
            time_ns: w.sof,
            frame: w.frame,
        })
        .collect()
}

#[test]
fn the_plan_knows_what_each_retired_id_carried() {
    let (old, new) = plans();
    let (e1, e3) = (id_of(&old, "encoder1"), id_of(&old, "encoder3"));
    assert_ne!(
        id_of(&new, "encoder3"),
        e3,
        "a re-laid-out topic gets a new ID"
    );
    let retired: Vec<(u16, &str, &str)> = new
        .retired
        .iter()
        .map(|r| (r.msg_id, r.name.as_str(), r.layout.as_str()))
        .collect();
    // encoder2 is local to motor2 (never on the bus) but locked with its ID all the same.
    let e2 = id_of(&old, "encoder2");
    let then = "Encoder{ticks:i32,speed:f32}/8/hrt/1";
    let mut want = vec![
        (e1, "encoder1", then),
        (e2, "encoder2", then),
        (e3, "encoder3", then),
    ];
    want.sort();
    assert_eq!(retired, want);
    let now = new
        .retired
        .iter()
        .find(|r| r.msg_id == e3)
        .unwrap()
        .now
        .clone();
    assert_eq!(
        now,
        Some((
            id_of(&new, "encoder3"),
            "Encoder{ticks:i32,speed:i32}/8/hrt/1".to_string()
        ))
    );
    // The unchanged plan retires nothing.
    assert!(old.retired.is_empty());
}

#[test]
fn the_lock_records_and_reads_back_the_retired_topics() {
    let (old, new) = plans();
    let a = analyze("robot.toml", TRISKAR);
    let first = lock::render(a.model.as_ref().unwrap(), &old, None);
    let prev = lock::parse("robot.lock", &first).unwrap();
    let new_toml = TRISKAR.replacen("speed = \"f32\"", "speed = \"i32\"", 1);
    let b = analyze_locked("robot.toml", &new_toml, Some(("robot.lock", &first)));
    let second = lock::render(b.model.as_ref().unwrap(), &new, Some(&prev));
    let e3 = id_of(&old, "encoder3");
    let line = format!("retired {e3:#06x} encoder3 Encoder{{ticks:i32,speed:f32}}/8/hrt/1");
    assert!(second.lines().any(|l| l == line), "{second}");
    let back = lock::parse("robot.lock", &second).unwrap();
    assert_eq!(
        back.retired_topics.get(&e3),
        Some(&(
            "encoder3".to_string(),
            "Encoder{ticks:i32,speed:f32}/8/hrt/1".to_string()
        ))
    );
    // A bare ID (locks written before round 7) still reads; a doubled one does not.
    let bare = format!("{first}retired 0x7000\n");
    assert!(lock::parse("robot.lock", &bare)
        .unwrap()
        .retired
        .contains(&0x7000));
    let twice = format!("{first}retired 0x7000\nretired 0x7000 x T{{}}/0/nrt/1\n");
    let e = lock::parse("robot.lock", &twice).unwrap_err();
    assert!(e.message.contains("robot.lock:"), "{}", e.message);
    assert!(e.message.contains("ID retired twice"), "{}", e.message);
}

#[test]
fn a_stale_image_is_named_with_its_topic_and_module() {
    let (old, new) = plans();
    let cat = plan_catalog(&new);
    let frames = wire(&old, &new, &["motor3"]);
    let mut mon = Monitor::new(
        &cat,
        new.modules.iter().map(|m| m.name.clone()).collect(),
        new.bus.bitrate,
    );
    let mut dec = Decoder::new(&cat);
    let mut reasons = Vec::new();
    for s in &frames {
        mon.frame(s, &cat);
        let e = Entry {
            time_ns: s.time_ns,
            iface: "can0".into(),
            frame: s.frame,
            standard: false,
        };
        if let Some(Decoded::Unattributed { why, .. }) = dec.push(&e) {
            reasons.push(why);
        }
    }
    let e3_old = id_of(&old, "encoder3");
    let e3_new = id_of(&new, "encoder3");
    let motor3 = new.modules.iter().position(|m| m.name == "motor3").unwrap();
    let want = format!(
        "retired ID of topic `encoder3` (then Encoder{{ticks:i32,speed:f32}}/8/hrt/1; now {e3_new:#06x} Encoder{{ticks:i32,speed:i32}}/8/hrt/1): an image built before that change is on the bus (its publisher is module {motor3}); rebuild and flash it"
    );
    let v = mon.view(&cat);
    assert_eq!(v.stale.len(), 1, "{:?}", v.stale);
    let row = &v.stale[0];
    assert_eq!(row.msg_id, e3_old);
    assert_eq!(row.reason, want);
    // encoder3 at 200 Hz for 0.3 s, from motor3's first synchronised cycle on.
    assert!((50..=60).contains(&row.frames), "{}", row.frames);
    assert_eq!(dec.counts.stale, row.frames);
    // Every frame the decoder cannot attribute is a stale one, named.
    assert_eq!(reasons.len() as u64, row.frames);
    assert!(reasons.iter().all(|r| *r == want), "{reasons:?}");
    assert!(mon.render(&cat).contains(&format!(
        "STALE IMAGES (frames under IDs robot.lock retired)\n{e3_old:#06x} {:>6}  {want}\n",
        row.frames
    )));
    // Its heartbeat matches: the compatibility fingerprint cannot tell.
    assert!(v.modules.iter().all(|m| m.matches == Some(true)));
}

#[test]
fn with_every_image_new_nothing_is_stale() {
    let (old, new) = plans();
    let cat = plan_catalog(&new);
    let mut mon = Monitor::new(
        &cat,
        new.modules.iter().map(|m| m.name.clone()).collect(),
        new.bus.bitrate,
    );
    for s in &wire(&old, &new, &[]) {
        mon.frame(s, &cat);
    }
    assert!(mon.view(&cat).stale.is_empty());
    assert!(!mon.render(&cat).contains("STALE"));
}
