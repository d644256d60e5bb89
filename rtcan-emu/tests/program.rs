#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! The `rtcan-emu` program (what `rtcan sim --emulate` starts): report and bad arguments.
use std::path::PathBuf;
use std::process::Command;

fn emu(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_rtcan-emu"))
        .args(args)
        .current_dir(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(".."))
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn json_report_of_a_short_run() {
    let (code, out, err) = emu(&["--seconds", "0.2", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["seconds"], 0.2);
    let modules = v["modules"].as_array().unwrap();
    assert_eq!(modules.len(), 6);
    for m in modules {
        let name = m["module"].as_str().unwrap();
        assert_eq!(m["unknown_accesses"].as_array().unwrap().len(), 0, "{name}");
        let log: Vec<&str> = m["log"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| l.as_str().unwrap())
            .collect();
        assert!(
            log.contains(&format!("INFO {name} up").as_str()),
            "{name}: {log:?}"
        );
        assert!(m["frames_sent"].as_u64().unwrap() > 0, "{name}");
    }
    let load = v["bus_load"].as_f64().unwrap();
    assert!(load > 0.05 && load < 0.5, "bus load {load}");
    // encoder1 at 200 Hz: 5 ms mean period.
    let enc = v["ids"]
        .as_array()
        .unwrap()
        .iter()
        .find(|i| i["id"] == "0xa200")
        .unwrap();
    assert!((enc["mean_period_us"].as_f64().unwrap() - 5000.0).abs() < 5.0);
}

#[test]
fn bad_arguments() {
    let (code, _, err) = emu(&["--seconds", "0"]);
    assert_eq!(code, 2);
    assert!(err.contains("--seconds must be in (0, 3600]"), "{err}");
    let (code, _, err) = emu(&["--frobnicate"]);
    assert_eq!(code, 2, "{err}");
    let (code, _, err) = emu(&["--images", "/nonexistent-dir"]);
    assert_eq!(code, 1);
    assert!(err.contains("/nonexistent-dir/gateway"), "{err}");
}
