#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! `rtcan check` exit codes and outputs on the reference robots.
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
        out.status.code().unwrap(),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

#[test]
fn admissible_robot_exits_0_with_plan() {
    let (code, out, err) = rtcan(&["check", "robot.toml"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.is_empty());
    assert!(out.starts_with("robot.toml: admissible, fingerprint 0x"));
    assert!(out.contains("  wheel_setpoints  motor1     0x0147  100 Hz (10 ms)"));
    assert!(out.contains("filter banks:"));
    assert!(out.contains("calendar (60 slots per cycle, 4 cycle(s) per hyperperiod"));
}

#[test]
fn paper_calendar_has_40_of_60_slots() {
    let (code, out, _) = rtcan(&["check", "robots/rtcan-paper.toml"]);
    assert_eq!(code, 0);
    assert!(out.contains("  mask     111111111111111100011100011100011111111100011100011100011100   40/60 reserved"), "{out}");
}

#[test]
fn not_admissible_exits_1() {
    let (code, out, err) = rtcan(&["check", "robots/broken/inadmissible-hrt.toml"]);
    assert_eq!(code, 1);
    assert!(
        err.starts_with("error[inadmissible-hrt]: topic `speed` has period 3 slots"),
        "{err}"
    );
    assert!(err.contains("--> robots/broken/inadmissible-hrt.toml:35:8"));
    assert_eq!(out, "robots/broken/inadmissible-hrt.toml: not admissible\n");
}

#[test]
fn invalid_input_exits_2() {
    for f in [
        "robots/broken/unknown-key.toml",
        "robots/broken/toml-syntax.toml",
        "robots/does-not-exist.toml",
    ] {
        let (code, out, err) = rtcan(&["check", f]);
        assert_eq!(code, 2, "{f}");
        assert!(out.is_empty(), "{f}");
        assert!(err.starts_with("error["), "{f}: {err}");
    }
    assert_eq!(rtcan(&["check"]).0, 2);
    assert_eq!(rtcan(&["check", "robot.toml", "--frobnicate"]).0, 2);
    assert_eq!(rtcan(&["frobnicate"]).0, 2);
    assert_eq!(rtcan(&["help"]).0, 0);
}

#[test]
fn json_output_and_exit_codes() {
    let (code, out, _) = rtcan(&["check", "robot.toml", "--json"]);
    assert_eq!(code, 0);
    for needle in [
        "\"admissible\": true",
        "\"slots_per_cycle\": 60",
        "\"slot_ns\": 166666",
        "\"phase_slot\": 3",
    ] {
        assert!(out.contains(needle), "{needle}");
    }
    let (code, out, _) = rtcan(&["check", "--json", "robots/broken/hrt-over-capacity.toml"]);
    assert_eq!(code, 1);
    assert!(
        out.contains("\"admissible\": false") && out.contains("\"code\": \"hrt-over-capacity\"")
    );
    let (code, out, _) = rtcan(&["check", "--json", "robots/broken/no-master.toml"]);
    assert_eq!(code, 2);
    assert!(out.contains("\"status\": \"invalid\""));
}
