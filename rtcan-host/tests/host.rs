//! rtcan-host against the simulated Triskar2 and candump logs: JSON both ways with the
//! bad values refused, the host driving the robot through `teleop`, replay, monitor.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan_host::monitor::Monitor;
use rtcan_host::replay::ReplayLink;
use rtcan_host::sim::SimLink;
use rtcan_host::value::{from_json, to_json};
use rtcan_host::{Link, Stamped};
use rtcan_sim::candump::{self, Entry};
use rtcan_sim::decode::{plan_catalog, Catalog, Decoded, Decoder, TopicDesc};
use serde_json::json;

fn plan() -> rtcan_model::Plan {
    rtcan_model::Robot::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml"))
        .map_err(|d| d.render())
        .unwrap()
}

fn topic<'a>(cat: &'a Catalog, name: &str) -> &'a TopicDesc {
    cat.topics.iter().find(|t| t.name == name).unwrap()
}

fn entry(s: &Stamped) -> Entry {
    Entry {
        time_ns: s.time_ns,
        iface: "can0".into(),
        frame: s.frame,
        standard: false,
    }
}

/// Runs `link` for `ns` of bus time; every decoded message as (topic name, JSON).
fn run(
    link: &mut dyn Link,
    cat: &Catalog,
    ns: u64,
) -> (Vec<Stamped>, Vec<(String, serde_json::Value)>) {
    let mut dec = Decoder::new(cat);
    let (mut frames, mut msgs) = (Vec::new(), Vec::new());
    let end = link.now_ns() + ns;
    while link.now_ns() < end {
        let Some(batch) = link.recv().unwrap() else {
            break;
        };
        for s in batch {
            if let Some(Decoded::Message { topic, payload, .. }) = dec.push(&entry(&s)) {
                let t = &cat.topics[topic];
                msgs.push((t.name.clone(), to_json(t, &payload)));
            }
            frames.push(s);
        }
    }
    (frames, msgs)
}

#[test]
fn json_round_trips_exact_bytes_and_refuses_what_does_not_fit() {
    let cat = plan_catalog(&plan());
    let teleop = topic(&cat, "teleop");
    let bytes = from_json(teleop, &json!({"vx": 0.5, "vy": -0.25, "wz": 1})).unwrap();
    let mut want = Vec::new();
    for v in [0.5f32, -0.25, 1.0] {
        want.extend_from_slice(&v.to_le_bytes());
    }
    assert_eq!(bytes, want);
    assert_eq!(
        to_json(teleop, &bytes),
        json!({"vx": 0.5, "vy": -0.25, "wz": 1.0})
    );

    let err = |t: &TopicDesc, v: serde_json::Value| from_json(t, &v).unwrap_err();
    assert!(err(teleop, json!({"vx": 0.5, "vy": 0})).contains("missing field `wz`"));
    assert!(err(teleop, json!({"vx": 0, "vy": 0, "wz": 0, "vz": 1})).contains("no field `vz`"));
    assert!(err(teleop, json!({"vx": "fast", "vy": 0, "wz": 0})).contains("field `vx`"));
    assert!(err(teleop, json!({"vx": 1e39, "vy": 0, "wz": 0})).contains("does not fit f32"));
    assert!(err(teleop, json!([1, 2, 3])).contains("JSON object"));

    // Integers and arrays: the log line's text is [u8; 32].
    let log = topic(&cat, "log");
    let fields: Vec<&str> = log.fields.iter().map(|f| f.name.as_str()).collect();
    let arr = log.fields.iter().find(|f| f.len.is_some()).unwrap();
    let mut ok = serde_json::Map::new();
    for f in &log.fields {
        let v = match f.len {
            Some(n) => json!(vec![65u8; usize::from(n)]),
            None => json!(7),
        };
        ok.insert(f.name.clone(), v);
    }
    let ok = serde_json::Value::Object(ok);
    let b = from_json(log, &ok).unwrap();
    assert_eq!(b.len(), usize::from(log.size));
    assert_eq!(to_json(log, &b), ok, "fields {fields:?}");
    let mut bad = ok.clone();
    bad[&arr.name] = json!([1, 2]);
    assert!(from_json(log, &bad)
        .unwrap_err()
        .contains(&format!("expected {} elements, got 2", arr.len.unwrap())));
    let mut bad = ok.clone();
    bad[&arr.name][0] = json!(256);
    assert!(from_json(log, &bad)
        .unwrap_err()
        .contains("256 does not fit u8"));
    let mut bad = ok;
    bad[&arr.name][0] = json!(1.5);
    assert!(from_json(log, &bad).unwrap_err().contains("not an integer"));
}

#[test]
fn the_host_drives_the_simulated_robot_through_teleop() {
    let plan = plan();
    let cat = plan_catalog(&plan);
    let mut link = SimLink::start(&plan, 0.0).unwrap();
    // No command: the gateway publishes zero and the robot stays put.
    let (_, msgs) = run(&mut link, &cat, 1_000_000_000);
    assert!(link.pose_m().0.abs() < 0.01, "{:?}", link.pose_m());
    assert!(msgs
        .iter()
        .any(|(n, v)| n == "teleop" && v["vx"] == json!(0.0)));

    let cmd = from_json(
        topic(&cat, "teleop"),
        &json!({"vx": 0.25, "vy": 0, "wz": 0}),
    )
    .unwrap();
    link.publish("teleop", &cmd).unwrap();
    let (_, msgs) = run(&mut link, &cat, 3_000_000_000);
    // The command goes out on the bus as the gateway's teleop, bit for bit...
    assert!(msgs
        .iter()
        .any(|(n, v)| n == "teleop" && v["vx"] == json!(0.25)));
    // ...and odometry reports the robot moving forward.
    let x = msgs
        .iter()
        .filter(|(n, _)| n == "odometry")
        .filter_map(|(_, v)| v["x"].as_f64())
        .next_back()
        .unwrap();
    assert!(x > 0.3 && x < 0.8, "odometry x {x}");
    assert!(link.pose_m().0 > 0.3, "{:?}", link.pose_m());

    // Only teleop comes from the host.
    let err = link.publish("velocity", &cmd).unwrap_err();
    assert!(err.contains("only teleop"), "{err}");
}

#[test]
fn replay_gives_back_the_recorded_frames_and_counts_what_it_skips() {
    let plan = plan();
    let cat = plan_catalog(&plan);
    let frames = {
        let mut link = SimLink::start(&plan, 0.0).unwrap();
        run(&mut link, &cat, 300_000_000).0
    };
    assert!(frames.len() > 100);
    let mut text = String::new();
    for (i, s) in frames.iter().enumerate() {
        text.push_str(&candump::line(s.time_ns, "can0", &s.frame));
        text.push('\n');
        if i == 3 {
            text.push_str("(0.5) can0 20000080#0000080000000000\n"); // error frame
            text.push_str("garbage line\n");
            text.push_str("(0.5) can0 00000123#R\n"); // remote frame
        }
    }
    let mut r = ReplayLink::from_reader(Box::new(std::io::Cursor::new(text)), 0.0);
    let mut back = Vec::new();
    while let Some(b) = r.recv().unwrap() {
        back.extend(b);
    }
    assert_eq!(back.len(), frames.len());
    for (a, b) in back.iter().zip(&frames) {
        // candump stamps in microseconds.
        assert_eq!(a.time_ns, b.time_ns / 1000 * 1000);
        assert_eq!(a.frame, b.frame);
    }
    assert_eq!((r.skipped, r.malformed), (2, 1));
    assert!(r
        .publish("teleop", &[0; 12])
        .unwrap_err()
        .contains("read-only"));
}

#[test]
fn monitor_sees_every_module_and_the_periodic_topics() {
    let plan = plan();
    let cat = plan_catalog(&plan);
    let names: Vec<String> = plan.modules.iter().map(|m| m.name.clone()).collect();
    let mut mon = Monitor::new(&cat, names.clone(), plan.bus.bitrate);
    let mut link = SimLink::start(&plan, 0.0).unwrap();
    let mut dec = Decoder::new(&cat);
    while link.now_ns() < 2_000_000_000 {
        for s in link.recv().unwrap().unwrap() {
            mon.frame(&s, &cat);
            if let Some(d) = dec.push(&entry(&s)) {
                mon.record(&d, s.time_ns);
            }
        }
    }
    assert_eq!(mon.heartbeats().len(), names.len());
    let table = mon.render(&cat);
    for n in &names {
        let row = table.lines().find(|l| l.starts_with(n.as_str())).unwrap();
        assert!(row.ends_with("yes"), "{row}");
    }
    let odo = cat
        .topics
        .iter()
        .position(|t| t.name == "odometry")
        .unwrap();
    // Odometry's declared rate over 2 s, give or take the start-up.
    let tp = plan.topics.iter().find(|t| t.name == "odometry").unwrap();
    let rate = tp
        .rate_hz
        .or(tp.requested_period_ns.map(|p| 1e9 / p))
        .unwrap();
    assert_eq!(rate, 50.0);
    let n = mon.topic_count(odo) as f64;
    assert!(
        n > 1.5 * rate && n <= 2.0 * rate + 1.0,
        "{n} odometry at {rate} Hz"
    );
    let load = mon.load_pct();
    assert!(load[0] > 0.0 && load[1] > 0.0, "{load:?}");
    assert!(load.iter().sum::<f64>() < 100.0);
    assert!(table.contains("odometry"));
}
