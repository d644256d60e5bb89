#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! `rtcan check --update-lock` writes robot.lock; later checks keep its allocation and
//! report moves; `--against` lists only the images that change; `--json` has `chains`.
use std::path::PathBuf;
use std::process::Command;

fn rtcan(dir: &std::path::Path, args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_rtcan"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

const IMU: &str = "\n[modules.imu]\nboard = \"stm32f103c8\"\n\n[nodes.imu_driver]\nmodule = \"imu\"\npriority = 2\n\n\
[topics.imu_rate]\ntype = \"Encoder\"\npublisher = \"imu_driver\"\nclass = \"hrt\"\nrate = \"100Hz\"\n\
subscribers = [{ node = \"ros_bridge\", queue = 2 }]\n";

#[test]
fn update_lock_then_add_a_module() {
    let dir = std::env::temp_dir().join(format!("rtcan-lock-test-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("old")).unwrap();
    let src =
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../robot.toml"))
            .unwrap();
    std::fs::write(dir.join("robot.toml"), &src).unwrap();
    std::fs::write(dir.join("old/robot.toml"), &src).unwrap();
    let (code, _, err) = rtcan(&dir, &["check", "robot.toml", "--update-lock"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("wrote robot.lock"), "{err}");
    let lock = std::fs::read_to_string(dir.join("robot.lock")).unwrap();
    assert!(lock.starts_with("# Allocation of robot.toml"), "{lock}");
    // The edit: the old copy has no lock of its own, so the new robot's lock (still the
    // old allocation) is used for it.
    std::fs::write(dir.join("robot.toml"), format!("{src}{IMU}")).unwrap();
    let (code, out, err) = rtcan(
        &dir,
        &[
            "check",
            "robot.toml",
            "--against",
            "old/robot.toml",
            "--json",
        ],
    );
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let changed: Vec<&str> = v["images_to_change"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["module"].as_str().unwrap())
        .collect();
    // Triskar2 is supervised (`on_missing`): the sync-capable gateway and motor1 also
    // receive the new module's health, and the module tables get a row more (their
    // layout changes, so their IDs move).
    assert_eq!(changed, ["gateway", "motor1", "imu"]);
    let moves: Vec<(&str, &str, &str)> = v["moves"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            (
                m["subject"].as_str().unwrap(),
                m["what"].as_str().unwrap(),
                m["to"].as_str().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        moves,
        [
            ("module_state_gateway", "msg_id", "0x0156"),
            ("module_state_motor1", "msg_id", "0x0157"),
            ("gateway", "filters", "7 banks"),
            ("motor1", "filters", "5 banks"),
        ],
        "{}",
        v["moves"]
    );
    assert_eq!(v["moves"][2]["reason"], "now receives `imu_rate`");
    assert_eq!(v["moves"][3]["reason"], "now receives `health_imu`");
    assert_eq!(v["chains"][0]["name"], "odometry_feedback");
    assert_eq!(v["chains"][0]["budget_ns"], 50_000_000);
    // Recording the edit keeps every other locked line and retires the module tables'
    // old IDs (moved with their layout).
    let (code, _, _) = rtcan(&dir, &["check", "robot.toml", "--update-lock"]);
    assert_eq!(code, 0);
    let relock = std::fs::read_to_string(dir.join("robot.lock")).unwrap();
    for l in lock
        .lines()
        .filter(|l| l.starts_with("topic") || l.starts_with("lineage"))
        .filter(|l| !l.starts_with("topic module_state_"))
    {
        assert!(relock.contains(l), "{l}");
    }
    assert!(relock.contains("topic imu_rate "));
    assert!(relock.contains("topic module_state_gateway 0x0156 "));
    let retired: Vec<&str> = relock
        .lines()
        .filter(|l| l.starts_with("retired"))
        .collect();
    // Each with the topic it carried and its layout then (the old lock's line), so the
    // host tools can name a stale image's frames.
    let was = |name: &str| {
        let l = lock
            .lines()
            .find(|l| l.starts_with(&format!("topic {name} ")))
            .unwrap();
        let w: Vec<&str> = l.split_whitespace().collect();
        format!("retired {} {name} {}", w[2], w[3])
    };
    assert_eq!(
        retired,
        [was("module_state_gateway"), was("module_state_motor1")]
    );
    assert!(retired[0].starts_with("retired 0x0150 module_state_gateway ModuleState{"));
    assert!(retired[1].starts_with("retired 0x0151 module_state_motor1 ModuleState{"));
    // A damaged lock is refused with its line.
    std::fs::write(
        dir.join("robot.lock"),
        relock.replacen("version 1", "version 9", 1),
    )
    .unwrap();
    let (code, _, err) = rtcan(&dir, &["check", "robot.toml"]);
    assert_eq!(code, 2);
    assert!(err.contains("error[lock-invalid]"), "{err}");
    assert!(
        err.contains("robot.lock:3:1: unsupported lock version"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
