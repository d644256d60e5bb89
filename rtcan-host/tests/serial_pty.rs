//! The gateway serial link end to end over a real pty pair: the simulated robot with the
//! gateway's link code (`triskar2_link`, as the firmware uses it) on the master side,
//! `rtcan_host::serial::SerialLink` (what `--serial PORT` opens) on the slave side. The
//! line loses bytes in both directions; both ends resynchronise, the host drives the
//! robot and reads its odometry.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use rtcan_host::gateway::SimGateway;
use rtcan_host::serial::SerialLink;
use rtcan_host::sim::SimLink;
use rtcan_host::value::{from_json, to_json};
use rtcan_host::Link;
use rtcan_sim::candump::Entry;
use rtcan_sim::decode::{plan_catalog, Decoded, Decoder};
use serde_json::json;

fn plan() -> rtcan_model::Plan {
    rtcan_model::Robot::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml"))
        .map_err(|d| d.render())
        .unwrap()
}

#[test]
fn host_drives_the_simulated_robot_over_a_lossy_pty_link() {
    let (master, _slave, path) = rtcan_host::serial::open_pty().unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let stop2 = stop.clone();
    let gateway = std::thread::spawn(move || {
        let plan = plan();
        let cat = plan_catalog(&plan);
        // Five times real time, so the test is short; the link keeps up.
        let robot = SimLink::start(&plan, 5.0).unwrap();
        let mut gw = SimGateway::new(robot, master, &cat, &plan.bridge.link);
        let mut dropped = 0u32;
        let mut delimiters = 0u64;
        // Every 40th frame of the robot loses its 7th-last byte on the line.
        let mut lose = |out: &mut Vec<u8>| {
            let mut i = 0;
            while i < out.len() {
                if out[i] == 0 {
                    delimiters += 1;
                    if delimiters.is_multiple_of(40) && i >= 7 {
                        out.remove(i - 7);
                        dropped += 1;
                        i -= 1;
                    }
                }
                i += 1;
            }
        };
        while !stop2.load(Ordering::Relaxed) {
            gw.step(&mut lose).unwrap();
        }
        (gw.stats(), gw.sent, dropped, gw.pose_m())
    });

    let plan = plan();
    let cat = plan_catalog(&plan);
    let mut host = SerialLink::open(&path, &cat, &plan.bridge.link).unwrap();
    // Garbage on the line before the first command (a half frame, a bad frame): the
    // gateway drops it and resynchronises on the delimiters.
    {
        let mut raw = std::fs::OpenOptions::new().write(true).open(&path).unwrap();
        raw.write_all(&[0x13, 0x37, 0xA5, 0x00, 0x05, 0xFF, 0xFF, 0x00])
            .unwrap();
    }
    let teleop = cat.topics.iter().find(|t| t.name == "teleop").unwrap();
    let cmd = from_json(teleop, &json!({"vx": 0.25, "vy": 0, "wz": 0})).unwrap();
    host.publish("teleop", &cmd).unwrap();
    assert!(host
        .publish("odometry", &[0; 24])
        .unwrap_err()
        .contains("only teleop from the host, not `odometry`"));

    let mut dec = Decoder::new(&cat);
    let (mut odometry, mut proximity, mut last_x) = (0, 0, 0.0);
    let t0 = Instant::now();
    // Until the robot has driven 0.3 m by its own odometry (the time limit only guards
    // against a hang; it is not what the test measures).
    while last_x < 0.3 && t0.elapsed() < Duration::from_secs(60) {
        for s in host.recv().unwrap().unwrap() {
            let e = Entry {
                time_ns: s.time_ns,
                iface: "serial".into(),
                frame: s.frame,
                standard: false,
            };
            if let Some(Decoded::Message { topic, payload, .. }) = dec.push(&e) {
                let t = &cat.topics[topic];
                match t.name.as_str() {
                    "odometry" => {
                        odometry += 1;
                        last_x = to_json(t, &payload)["x"].as_f64().unwrap();
                    }
                    "proximity" => proximity += 1,
                    _ => {}
                }
            }
        }
    }
    stop.store(true, Ordering::Relaxed);
    let (gw_stats, sent, dropped, pose) = gateway.join().unwrap();
    let host_stats = host.stats();
    eprintln!("gateway {gw_stats:?} sent {sent} damaged {dropped}; host {host_stats:?}; odometry {odometry} x {last_x}");
    assert!(
        last_x >= 0.3,
        "odometry x {last_x} after {odometry} messages"
    );
    assert!(pose.0 >= 0.3, "robot at {pose:?}");
    assert!(
        odometry > 50 && proximity > 25,
        "{odometry} odometry, {proximity} proximity"
    );
    // Host → robot: the two garbage pieces were dropped, the command arrived.
    assert_eq!(gw_stats.frames, 1, "{gw_stats:?}");
    assert_eq!(gw_stats.malformed + gw_stats.bad_check, 2, "{gw_stats:?}");
    // Robot → host: every damaged frame was dropped, never delivered wrong, and the
    // frames after it arrived.
    assert!(dropped > 0);
    assert!(
        host_stats.bad_check + host_stats.malformed <= dropped,
        "{host_stats:?}, {dropped} damaged"
    );
    assert!(
        host_stats.bad_check + host_stats.malformed > 0,
        "{host_stats:?}"
    );
    assert!(u64::from(host_stats.frames) + u64::from(dropped) <= sent);
}

/// An in-memory serial line: what the gateway writes is kept, reads return nothing.
#[derive(Default)]
struct Line(Vec<u8>);

impl std::io::Read for Line {
    fn read(&mut self, _: &mut [u8]) -> std::io::Result<usize> {
        Ok(0)
    }
}

impl std::io::Write for Line {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[test]
fn the_link_carries_exactly_the_topics_robot_toml_declares() {
    // The model's limit for link topics is the link's frame size.
    assert_eq!(
        rtcan_model::bridge_keys::LINK_MAX_PAYLOAD,
        triskar2_link::MAX_PAYLOAD
    );
    let src =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml")).unwrap();
    // Triskar2 as declared, and with encoder1 on the link instead of proximity.
    let changed = src
        .replace(
            "link = \"out\"\nros2 = \"sensor_msgs/msg/Range\"",
            "ros2 = \"sensor_msgs/msg/Range\"",
        )
        .replace(
            "subscribers = [{ node = \"odometry\", queue = 2 }]\n\n[topics.encoder2]",
            "subscribers = [{ node = \"odometry\", queue = 2 }]\nlink = \"out\"\n\n[topics.encoder2]",
        );
    assert_ne!(src, changed);
    for (text, want) in [
        (
            &src,
            vec![
                (2u8, "odometry"),
                (3, "proximity"),
                (4, "battery"),
                (5, "log"),
            ],
        ),
        (
            &changed,
            vec![(2, "encoder1"), (3, "odometry"), (4, "battery"), (5, "log")],
        ),
    ] {
        let plan = rtcan_model::Robot::parse("robot.toml", text)
            .map_err(|d| d.render())
            .unwrap();
        let cat = plan_catalog(&plan);
        let robot = SimLink::start(&plan, 0.0).unwrap();
        let mut line = Line::default();
        {
            let mut gw = SimGateway::new(robot, &mut line, &cat, &plan.bridge.link);
            // 1.1 s of bus time: every periodic topic and the 1 Hz battery at least once.
            for _ in 0..110 {
                gw.step(&mut |_| {}).unwrap();
            }
        }
        // Decode what went down the line with the link's own decoder.
        let mut d = triskar2_link::Decoder::new();
        let mut seen = std::collections::BTreeMap::new();
        for &b in &line.0 {
            if let Some((n, p)) = d.push(b) {
                let size = plan
                    .bridge
                    .link
                    .iter()
                    .find(|l| l.number == n)
                    .unwrap()
                    .size;
                assert_eq!(p.len(), size, "link topic {n}");
                *seen.entry(n).or_insert(0u32) += 1;
            }
        }
        let got: Vec<(u8, &str)> = seen
            .keys()
            .map(|n| {
                let l = plan.bridge.link.iter().find(|l| l.number == *n).unwrap();
                (*n, l.name.as_str())
            })
            .collect();
        assert_eq!(got, want, "{seen:?}");
        assert_eq!(d.stats().bad_check + d.stats().malformed, 0);
    }
}
