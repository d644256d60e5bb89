//! `rtcan flash` against the simulated Triskar2 (issue 15, docs/SERVICES.md §4).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
mod common;
use common::rtcan;

#[test]
fn flash_motor1_with_the_default_test_image() {
    let (code, out, err) = rtcan(&["flash", "robot.toml", "--module", "motor1"]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 3, "{out}");
    assert!(
        lines[0].contains("1000000 bit/s; image: deterministic 28 KiB test image"),
        "{out}"
    );
    // Begin, 115 Data, End of 32 frames each; the bus time is simulated, deterministic.
    assert!(
        lines[1].starts_with("motor1     28672 bytes, 3744 frames, "),
        "{out}"
    );
    assert!(
        lines[1].ends_with(" s bus time, 0 retries: ok (committed to slot 1, seq 2)"),
        "{out}"
    );
    assert_eq!(
        lines[2],
        "robot traffic meanwhile (10.5 s): 0 HRT misses, 0 SRT misses"
    );
}

#[test]
fn flash_json_fields_and_a_refused_image() {
    let (code, out, err) = rtcan(&["flash", "--module", "psu", "--json", "--seconds", "8"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["module"], "psu");
    assert_eq!(v["bytes"], 28672);
    assert_eq!(v["frames"], 3744);
    assert_eq!(v["retries"], 0);
    assert_eq!(v["ok"], true);
    let ms = v["bus_time_ms"].as_f64().unwrap();
    assert!(ms > 1000.0 && ms <= 10_000.0, "{ms}");
    // An image without this robot's fingerprint at 0x1D0: refused at End (Begin, 9
    // Data, End: 352 frames), exit 1.
    let dir = std::env::temp_dir().join(format!("rtcan-flash-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let img = dir.join("zeros.bin");
    std::fs::write(&img, vec![0u8; 2048]).unwrap();
    let (code, out, _) = rtcan(&[
        "flash",
        "--module",
        "motor2",
        "--image",
        img.to_str().unwrap(),
        "--seconds",
        "3",
    ]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("motor2     2048 bytes, 352 frames, ")
            && out.contains("FAILED: refused by the module (Fingerprint)"),
        "{out}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn flash_usage_errors() {
    for (args, msg) in [
        (&["flash"][..], "required arguments were not provided"),
        (
            &["flash", "--module", "gateway"],
            "updated over its host link",
        ),
        (&["flash", "--module", "wheel9"], "no module `wheel9`"),
        (
            &["flash", "--all", "--module", "psu"],
            "cannot be used with",
        ),
        (
            &["flash", "--all", "--can", "can0"],
            "(--serial PORT) only so far",
        ),
        (
            &["flash", "--module", "psu", "--serial", "/nonexistent-tty"],
            "--serial /nonexistent-tty",
        ),
        (
            &["flash", "--module", "psu", "--image", "/nonexistent"],
            "/nonexistent",
        ),
    ] {
        let (code, _, err) = rtcan(args);
        assert_eq!(code, 2, "{args:?}");
        assert!(err.contains(msg), "{args:?}: {err}");
    }
}

/// The gateway thread's result: what motor1 and motor2 would boot, host-channel frames
/// put on the bus and refused.
type GatewayDone = std::thread::JoinHandle<(
    Option<(usize, u32, u32)>,
    Option<(usize, u32, u32)>,
    u64,
    u64,
)>;

/// A pty pair with the simulated robot's gateway on the master side (five times real
/// time; every module with its update port, the gateway relaying the host channels)
/// until `stop`; the slave's path.
fn gateway_on_pty(stop: std::sync::Arc<std::sync::atomic::AtomicBool>) -> (String, GatewayDone) {
    let (master, slave, path) = rtcan_host::serial::open_pty().unwrap();
    let h = std::thread::spawn(move || {
        let _slave = slave;
        let plan = rtcan_model::Robot::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml"))
            .map_err(|d| d.render())
            .unwrap();
        let cat = rtcan_sim::decode::plan_catalog(&plan);
        let robot = rtcan_host::sim::SimLink::start_with_updates(&plan, 5.0).unwrap();
        let mut gw = rtcan_host::gateway::SimGateway::new(robot, master, &cat, &plan.bridge.link);
        while !stop.load(std::sync::atomic::Ordering::Relaxed) {
            gw.step(&mut |_| {}).unwrap();
        }
        (gw.booted(1), gw.booted(2), gw.relayed, gw.refused)
    });
    (path, h)
}

#[test]
fn flash_through_the_gateway_serial_link_over_a_pty() {
    use std::sync::atomic::{AtomicBool, Ordering};
    let plan = rtcan_model::Robot::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml"))
        .map_err(|d| d.render())
        .unwrap();
    let img = rtcan_sim::update::test_image(2000, plan.fingerprint, 0x33);
    let dir = std::env::temp_dir().join(format!("rtcan-flash-serial-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = dir.join("good.bin");
    std::fs::write(&good, &img).unwrap();
    let zeros = dir.join("zeros.bin");
    std::fs::write(&zeros, vec![0u8; 2000]).unwrap();
    let stop = std::sync::Arc::new(AtomicBool::new(false));
    let (pty, gw) = gateway_on_pty(stop.clone());
    let (code, out, err) = rtcan(&[
        "flash",
        "robot.toml",
        "--module",
        "motor1",
        "--serial",
        &pty,
        "--image",
        good.to_str().unwrap(),
        "--json",
        "--seconds",
        "30",
    ]);
    // The wrong image to motor2: refused by the module at End, nothing committed.
    let (code2, out2, err2) = rtcan(&[
        "flash",
        "robot.toml",
        "--module",
        "motor2",
        "--serial",
        &pty,
        "--image",
        zeros.to_str().unwrap(),
        "--seconds",
        "30",
    ]);
    stop.store(true, Ordering::Relaxed);
    let (motor1, motor2, relayed, refused) = gw.join().unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    eprintln!("{out}{out2}");
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["module"], "motor1");
    assert_eq!(v["bytes"], 2000);
    // Begin, 8 Data of 250 bytes, End: 10 requests of 32 frames.
    assert_eq!(v["frames"], 320);
    assert_eq!(v["retries"], 0);
    assert_eq!(v["ok"], true);
    // Committed to the other slot: what motor1 boots now is the image sent.
    assert_eq!(motor1, Some((1, 2000, rtcan_sim::update::crc(&img))));
    assert_eq!(code2, 1, "{err2}");
    assert!(
        out2.contains("through the gateway link")
            && out2.contains("motor2     2000 bytes, 320 frames, ")
            && out2.contains("FAILED: refused by the module (Fingerprint)"),
        "{out2}"
    );
    // motor2 still boots its factory image (slot 0, 4096 bytes).
    assert_eq!(motor2.map(|(s, len, _)| (s, len)), Some((0, 4096)));
    // Every request frame of both updates went onto the bus; none refused.
    assert_eq!((relayed, refused), (640, 0));
}
