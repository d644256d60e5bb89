#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! `rtcan monitor|echo|pub|record` (issue 13) on the simulated robot and on logs:
//! real output, the refused values, usage errors (exit 2), unavailable buses (exit 1).
mod common;
use common::{root, rtcan};

#[test]
fn monitor_once_shows_every_module_topic_and_the_load() {
    let (code, out, err) = rtcan(&[
        "monitor",
        "--once",
        "--sim",
        "robot.toml",
        "--seconds",
        "1",
        "--speed",
        "0",
    ]);
    assert_eq!(code, 0, "{err}");
    for m in ["gateway", "motor1", "motor2", "motor3", "proximity", "psu"] {
        let row = out
            .lines()
            .find(|l| l.starts_with(m))
            .unwrap_or_else(|| panic!("{m}: {out}"));
        assert!(row.ends_with("yes"), "{row}");
    }
    // 100 Hz wheel set points over 1 s: 99 intervals measured at 100.0 Hz.
    let row = out
        .lines()
        .find(|l| l.starts_with("wheel_setpoints"))
        .unwrap();
    let cols: Vec<&str> = row.split_whitespace().collect();
    assert_eq!(cols[1], "HRT");
    assert_eq!(cols[3], "100.0", "{row}");
    assert!(row.ends_with(r#"{"w":[0.0,0.0,0.0]}"#), "{row}");
    assert!(out.contains("LOAD %   sync "), "{out}");
}

#[test]
fn echo_json_prints_odometry_objects_with_the_type_field_names() {
    let (code, out, err) = rtcan(&["echo", "odometry", "--json", "--count", "3", "--speed", "0"]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 3);
    for (k, v) in lines.iter().enumerate() {
        assert_eq!(v["topic"], "odometry");
        let keys: Vec<&String> = v["value"].as_object().unwrap().keys().collect();
        assert_eq!(keys, ["x", "y", "theta", "vx", "vy", "wz"]);
        // 50 Hz: one every 20 ms, from 41 ms: Triskar2 is supervised (`on_missing`), and
        // a module not heard yet counts as missing, so the odometry's module stays in its
        // safe state until every module's first heartbeat (the 21 ms instance is not
        // published).
        let t = v["time"].as_f64().unwrap();
        assert!((t - 0.041 - 0.02 * k as f64).abs() < 0.001, "{t}");
    }
}

#[test]
fn pub_puts_the_command_on_the_bus_and_refuses_what_does_not_fit() {
    let (code, out, err) = rtcan(&[
        "pub",
        "teleop",
        r#"{"vx":0.3,"vy":0,"wz":0}"#,
        "--speed",
        "0",
    ]);
    assert_eq!(code, 0, "{err}");
    // teleop is 20 Hz: the gateway publishes the command 19 or 20 times in 1 s.
    assert!(
        out.contains("the bus carried it 20 times (0 other")
            || out.contains("the bus carried it 19 times (1 other"),
        "{out}"
    );
    for (bad, why) in [
        (r#"{"vx":1e40,"vy":0,"wz":0}"#, "does not fit f32"),
        (r#"{"vx":0.3}"#, "missing field `vy`"),
        (r#"{"vx":0.3,"vy":0,"wz":0,"up":1}"#, "no field `up`"),
        ("vx=0.3", "is not JSON"),
    ] {
        let (code, _, err) = rtcan(&["pub", "teleop", bad, "--speed", "0"]);
        assert_eq!(code, 2, "{bad}");
        assert!(err.contains(why), "{bad}: {err}");
    }
    let (code, _, err) = rtcan(&[
        "pub",
        "velocity",
        r#"{"vx":0,"vy":0,"wz":0}"#,
        "--speed",
        "0",
    ]);
    assert_eq!(code, 1);
    assert!(err.contains("takes only teleop"), "{err}");
}

#[test]
fn record_writes_candump_from_the_epoch_that_decode_and_replay_read_back() {
    let dir = std::env::temp_dir().join(format!("rtcan-record-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("bus.log");
    let log_s = log.to_str().unwrap();
    let (code, _, err) = rtcan(&[
        "record",
        log_s,
        "--seconds",
        "1.2",
        "--speed",
        "0",
        "--log-epoch",
        "1700000000",
    ]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&log).unwrap();
    let first = text.lines().next().unwrap();
    // The first sync frame, stamped from the epoch, in candump -l format.
    assert!(first.starts_with("(1700000000.000"), "{first}");
    assert!(first.contains(" can0 00000000#"), "{first}");
    assert!(
        err.contains(&format!("recorded {} frames", text.lines().count())),
        "{err}"
    );
    // decode reads it back: the 1 Hz battery message is in the first 1.2 s.
    let (code, out, err) = rtcan(&["decode", log_s, "--robot", "robot.toml"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("NRT battery"), "{out}");
    // echo over the replayed log gives the same odometry as the simulator.
    let (_, live, _) = rtcan(&["echo", "odometry", "--json", "--count", "5", "--speed", "0"]);
    let (code, replay, err) = rtcan(&[
        "echo", "odometry", "--json", "--count", "5", "--speed", "0", "--replay", log_s,
    ]);
    assert_eq!(code, 0, "{err}");
    let values = |s: &str| -> Vec<serde_json::Value> {
        s.lines()
            .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()["value"].clone())
            .collect()
    };
    assert_eq!(values(&replay), values(&live));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn usage_errors_exit_2_and_unavailable_buses_exit_1() {
    for args in [
        vec!["echo"],
        vec!["echo", "odometry", "--seconds", "x"],
        vec!["echo", "odometry", "--bogus"],
        vec!["pub", "teleop"],
        vec!["record"],
        vec!["monitor", "--every", "0"],
    ] {
        let (code, _, err) = rtcan(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        // clap's report: what was wrong, then where to look.
        assert!(err.starts_with("error: "), "{err}");
        assert!(err.contains("try '--help'"), "{err}");
    }
    let (code, _, err) = rtcan(&["echo", "nosuch", "--speed", "0"]);
    assert_eq!(code, 1);
    assert!(
        err.contains("no topic `nosuch`") && err.contains("odometry"),
        "{err}"
    );
    // This machine's kernel has no CAN interface: the error names it and says how to
    // bring one up (or, built without SocketCAN, says so).
    let (code, _, err) = rtcan(&["echo", "odometry", "--can", "can0"]);
    assert_eq!(code, 1);
    if cfg!(feature = "socketcan") {
        assert!(
            err.starts_with("error: --can can0: no usable CAN interface `can0` ("),
            "{err}"
        );
        assert!(
            err.contains("ip link set can0 up type can bitrate 1000000"),
            "{err}"
        );
    } else {
        assert!(
            err.contains("--can can0: SocketCAN is not built in"),
            "{err}"
        );
    }
    let (code, _, err) = rtcan(&["echo", "odometry", "--replay", "/nonexistent.log"]);
    assert_eq!(code, 1);
    assert!(err.contains("/nonexistent.log"), "{err}");
    let (code, out, _) = rtcan(&["--version"]);
    assert_eq!(
        (code, out.as_str()),
        (0, concat!("rtcan ", env!("CARGO_PKG_VERSION"), "\n"))
    );
    for c in ["echo", "pub", "record", "monitor", "bridge"] {
        let (code, out, _) = rtcan(&[c, "--help"]);
        assert_eq!(code, 0);
        assert!(out.contains(&format!("usage: rtcan {c}")), "{out}");
    }
}

/// The gateway thread's result: its link counters and the robot's final pose.
type GatewayDone = std::thread::JoinHandle<(triskar2_link::LinkStats, (f64, f64))>;

/// A pty pair with the simulated robot's gateway on the master side (five times real
/// time) until `stop`; the slave's path.
fn gateway_on_pty(stop: std::sync::Arc<std::sync::atomic::AtomicBool>) -> (String, GatewayDone) {
    let (master, slave, path) = rtcan_host::serial::open_pty().unwrap();
    let h = std::thread::spawn(move || {
        let _slave = slave;
        let plan = rtcan_model::Robot::load(root().join("robot.toml"))
            .map_err(|d| d.render())
            .unwrap();
        let cat = rtcan_sim::decode::plan_catalog(&plan);
        let robot = rtcan_host::sim::SimLink::start(&plan, 5.0).unwrap();
        let mut gw = rtcan_host::gateway::SimGateway::new(robot, master, &cat, &plan.bridge.link);
        while !stop.load(std::sync::atomic::Ordering::Relaxed) {
            gw.step(&mut |_| {}).unwrap();
        }
        (gw.stats(), gw.pose_m())
    });
    (path, h)
}

#[test]
fn echo_and_pub_over_the_gateway_serial_link() {
    use std::sync::atomic::{AtomicBool, Ordering};
    let stop = std::sync::Arc::new(AtomicBool::new(false));
    let (pty, gw) = gateway_on_pty(stop.clone());
    let (code, out, err) = rtcan(&[
        "echo", "odometry", "--json", "--count", "3", "--serial", &pty,
    ]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 3, "{out}");
    assert_eq!(lines[0]["value"]["x"], 0.0);
    let (code, out, err) = rtcan(&[
        "pub",
        "teleop",
        r#"{"vx":0.4,"vy":0,"wz":0}"#,
        "--serial",
        &pty,
        "--seconds",
        "0.2",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("published teleop"), "{out}");
    let (code, out, err) = rtcan(&["monitor", "--once", "--serial", &pty, "--seconds", "0.5"]);
    assert_eq!(code, 0, "{err}");
    // The link carries odometry and proximity (no heartbeats: the gateway forwards topics).
    let row = out.lines().find(|l| l.starts_with("odometry")).unwrap();
    assert!(
        row.split_whitespace()
            .nth(2)
            .unwrap()
            .parse::<u64>()
            .unwrap()
            > 0,
        "{row}"
    );
    stop.store(true, Ordering::Relaxed);
    let (stats, pose) = gw.join().unwrap();
    assert_eq!(stats.frames, 1, "{stats:?}");
    assert_eq!(stats.malformed + stats.bad_check, 0, "{stats:?}");
    // The command reached the robot: it moved forward.
    assert!(pose.0 > 0.01, "{pose:?}");
}
