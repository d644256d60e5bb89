#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! The module table of the supervised Triskar2 on the host tools (issue 15,
//! docs/SERVICES.md §1): `rtcan echo module_state` and `rtcan monitor --once`.
use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn rtcan(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_rtcan"))
        .args(args)
        .current_dir(root())
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

fn fingerprint() -> u64 {
    let plan = rtcan_model::Robot::load(root().join("robot.toml"))
        .unwrap_or_else(|d| panic!("{}", d.render()));
    u64::from(plan.fingerprint)
}

#[test]
fn echo_module_state_prints_the_masters_table_every_10_cycles() {
    let (code, out, err) = rtcan(&[
        "echo",
        "module_state",
        "--json",
        "--seconds",
        "0.8",
        "--speed",
        "0",
    ]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    // The first table, in the first cycle, has heard nobody but the gateway itself.
    assert_eq!(
        lines[0]["value"]["flags"],
        serde_json::json!([3, 0, 0, 0, 0, 0])
    );
    // After the start-up (tables at once on every change): every 10 cycles.
    let steady: Vec<&serde_json::Value> = lines
        .iter()
        .filter(|v| v["time"].as_f64().unwrap() > 0.3)
        .collect();
    // 0.5 s of 0.1 s periods: 4 or 5 by the phase of the last start-up change.
    assert!((4..=5).contains(&steady.len()), "{out}");
    let fp = fingerprint();
    let mut times = Vec::new();
    for v in steady {
        assert_eq!(v["topic"], "module_state_gateway", "{v}");
        let t = &v["value"];
        assert_eq!(t["reporter"], 0);
        assert_eq!(t["sync_master"], 0);
        // Every module alive and heard, with the robot's fingerprint.
        assert_eq!(t["flags"], serde_json::json!([3, 3, 3, 3, 3, 3]), "{v}");
        for f in t["fingerprint"].as_array().unwrap() {
            assert_eq!(f.as_u64(), Some(fp));
        }
        for col in [
            "state",
            "age",
            "tec",
            "rec",
            "bus_off",
            "rx_overrun",
            "deadline_missed",
        ] {
            assert_eq!(t[col].as_array().unwrap().len(), 6, "{col}");
        }
        times.push(v["time"].as_f64().unwrap());
    }
    // Once every 10 cycles of 10 ms when nothing changes.
    for w in times.windows(2) {
        assert!((w[1] - w[0] - 0.1).abs() < 0.002, "{times:?}");
    }
}

#[test]
fn monitor_once_screen_shows_the_module_table() {
    let (code, out, err) = rtcan(&[
        "monitor",
        "--once",
        "--screen",
        "--sim",
        "robot.toml",
        "--seconds",
        "1",
        "--speed",
        "0",
    ]);
    assert_eq!(code, 0, "{err}");
    let at = out
        .find("MODULE TABLE from gateway (sync master gateway)")
        .unwrap_or_else(|| panic!("{out}"));
    let section = &out[at..];
    let fp = format!("{:#010x}", fingerprint());
    for m in ["gateway", "motor1", "motor2", "motor3", "proximity", "psu"] {
        let row = section
            .lines()
            .find(|l| l.starts_with(m))
            .unwrap_or_else(|| panic!("{m}: {section}"));
        let cols: Vec<&str> = row.split_whitespace().collect();
        assert_eq!(cols[1], "yes", "{row}");
        assert_eq!(cols[4], fp, "{row}");
        // A clean bus: no bus-off, no overrun.
        assert_eq!(cols[7], "0", "{row}");
        assert_eq!(cols[8], "0", "{row}");
    }
    // The plain table (without --screen) carries the same section.
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
    assert!(out.contains("\nMODULE TABLE from gateway"), "{out}");
    assert!(out.contains("module_state_gateway"), "{out}");
}

#[test]
fn echo_of_an_unknown_topic_lists_the_module_state_topics() {
    let (code, _, err) = rtcan(&["echo", "module_states", "--speed", "0"]);
    assert_eq!(code, 1);
    assert!(
        err.contains("module_state_gateway, module_state_motor1"),
        "{err}"
    );
}
