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

/// `--json` is the simulator's triskar2 report (`rtcan sim --json`, docs/SIM.md) plus
/// the emulator's own `emulation` member.
#[test]
fn json_report_of_a_short_run() {
    let (code, out, err) = emu(&["--seconds", "0.3", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    // The simulator's fields.
    assert_eq!(v["scenario"], "triskar2");
    assert_eq!(v["seconds"], 0.3);
    assert_eq!(v["wall_x"], 1.5);
    for key in [
        "max_x",
        "min_gap",
        "final_gap",
        "stopped_short",
        "overrides",
        "path",
    ] {
        assert!(!v["robot"][key].is_null(), "robot.{key}");
    }
    assert!(v["robot"]["path"].as_array().unwrap().len() >= 6);
    let hrt = v["run"]["hrt"].as_array().unwrap();
    let names: Vec<&str> = hrt.iter().map(|h| h["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "encoder1@n1",
            "wheel_setpoints@n1",
            "odometry@n2",
            "encoder3@n3",
            "proximity@n4"
        ]
    );
    // encoder1 at 200 Hz: 5 ms mean period, no miss.
    assert!((hrt[0]["mean_period_us"].as_f64().unwrap() - 5000.0).abs() < 5.0);
    assert_eq!(hrt[0]["misses"], 0);
    let srt: Vec<&str> = v["run"]["srt"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["class"].as_str().unwrap())
        .collect();
    // The plan's SRT topics, `proximity_read`'s request and reply included (robot.toml's
    // `[services]`; the images make no calls, so they stay silent).
    assert_eq!(
        srt,
        [
            "teleop",
            "proximity_read_request",
            "velocity",
            "proximity_read_reply"
        ]
    );
    let load = &v["run"]["load"];
    let total: f64 = ["sync", "hrt", "srt", "nrt"]
        .iter()
        .map(|k| load[k].as_f64().unwrap())
        .sum();
    assert!(total > 0.05 && total < 0.5, "bus load {total}");
    assert_eq!(v["run"]["cpu"]["design"], "emulated");
    assert_eq!(v["run"]["cpu"]["modules"].as_array().unwrap().len(), 6);
    assert_eq!(v["modules"].as_array().unwrap().len(), 6);
    assert!(v["speed_x_real_time"].as_f64().unwrap() > 0.0);
    // The emulator's own.
    let modules = v["emulation"]["modules"].as_array().unwrap();
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
        // Unicorn runs by what ended them: the parts add up, the module slept (WFI / `b .`
        // end runs), and nothing ended one unexpectedly.
        let runs = &m["runs"];
        let parts: u64 = [
            "event",
            "until",
            "chunk",
            "unmask",
            "replan",
            "sleep",
            "exc_return",
            "other",
        ]
        .iter()
        .map(|k| runs[k].as_u64().unwrap())
        .sum();
        assert_eq!(runs["total"].as_u64().unwrap(), parts, "{name}: {runs}");
        assert!(runs["sleep"].as_u64().unwrap() > 0, "{name}: {runs}");
        assert_eq!(runs["other"], 0, "{name}: {runs}");
        // Instructions are counted per translation block (docs/EMULATOR.md "Time", round
        // 8): a run ends at the first block boundary at or past its planned point. The
        // lateness is the emulator's own event latency: a few instructions on average
        // (3.7-5.6 measured), bounded by the longest straight-line block (47-73).
        let late = &runs["late"];
        let mean = late["mean_instructions"].as_f64().unwrap();
        let max = late["max_instructions"].as_u64().unwrap();
        assert!(late["runs"].as_u64().unwrap() > 0, "{name}: {late}");
        assert!(mean > 0.0 && mean < 10.0, "{name}: {late}");
        assert!(max < 200, "{name}: {late}");
        // QEMU ends a block after every unmask, so a pending exception is entered inside
        // the run: no run ends at an unmask (the loop is needed only for a transmit
        // request the bus waits for, a reset, the watchdog).
        assert!(
            runs["unmask"].as_u64().unwrap() * 100 <= runs["total"].as_u64().unwrap(),
            "{name}: {runs}"
        );
    }
    // RTIC's idle (`b .`) sleeps: the busy fraction is the handlers' and the app's time
    // only (0.22-0.34 in 0.3 s). While the idle loop spun until the end of each run
    // (round 5, docs/EMULATOR.md "Time") every module read 0.47-0.58.
    for m in v["run"]["cpu"]["modules"].as_array().unwrap() {
        let load = m["load"].as_f64().unwrap();
        assert!(load > 0.1 && load < 0.42, "{}: busy {load}", m["name"]);
    }
}

#[test]
fn bad_arguments() {
    let (code, _, err) = emu(&["--seconds", "0"]);
    assert_eq!(code, 2);
    assert!(err.contains("--seconds must be in (0, 3600]"), "{err}");
    let (code, _, err) = emu(&["--cpi", "0.1"]);
    assert_eq!(code, 2);
    assert!(err.contains("--cpi must be in [0.5, 10]"), "{err}");
    let (code, _, err) = emu(&["--seed"]);
    assert_eq!(code, 2);
    assert!(err.contains("--seed needs a value"), "{err}");
    let (code, _, err) = emu(&["--robot", "/nonexistent.toml"]);
    assert_eq!(code, 1, "{err}");
    let (code, _, err) = emu(&["--frobnicate"]);
    assert_eq!(code, 2, "{err}");
    let (code, _, err) = emu(&["--images", "/nonexistent-dir"]);
    assert_eq!(code, 1);
    assert!(err.contains("/nonexistent-dir/gateway"), "{err}");
    let (code, _, err) = emu(&["--ber", "1.5"]);
    assert_eq!(code, 2);
    assert!(err.contains("--ber must be in [0, 1), got 1.5"), "{err}");
    // rtcan-sim's fault syntax; the faults the emulated MCU cannot model are refused
    // before the run.
    let (code, _, err) = emu(&["--fault", "motor9:stuck@1s"]);
    assert_eq!(code, 2);
    assert!(err.contains("no module `motor9`"), "{err}");
    let (code, _, err) = emu(&["--fault", "motor1:stall=5ms@1s"]);
    assert_eq!(code, 2);
    assert!(
        err.contains(
            "--fault `motor1:stall=5ms@1s`: fault Stall(5000000) is not modelled under emulation"
        ),
        "{err}"
    );
}
