#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! Issue 10 on the command line: `check` rejects a guard the slot timer path does not
//! fit (exit 1, `guard-too-short`); `sim` runs on the CPU model by default, reports it in
//! JSON, and takes `--cpu off`, `--cpu-design`, `--cpi` (bad values exit 2).
use std::path::PathBuf;
use std::process::Command;

fn rtcan(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_rtcan"))
        .args(args)
        .current_dir(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(".."))
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

#[test]
fn check_rejects_a_guard_shorter_than_the_timer_path() {
    let (code, out, err) = rtcan(&["check", "robots/broken/guard-too-short.toml"]);
    assert_eq!(code, 1, "{err}");
    assert!(out.contains("not admissible"));
    assert!(err.starts_with("error[guard-too-short]: module `main`: worst-case latency from a slot boundary to its TXRQ (2.945 us)"), "{err}");
    let (code, out, _) = rtcan(&["check", "robot.toml"]);
    assert_eq!(code, 0);
    assert!(out.contains("\ntiming (guard 5 us;"), "{out}");
}

#[test]
fn sim_reports_the_cpu_model() {
    let (code, out, err) = rtcan(&["sim", "robot.toml", "--seconds", "1", "--json"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains(r#","cpu":{"design":"prioritised","cpi":1.25,"clock_hz":72000000,"modules":[{"name":"gateway","load":"#),
        "{out}"
    );
    for name in ["gateway", "motor1", "motor2", "motor3", "proximity", "psu"] {
        let at = out.find(&format!(r#"{{"name":"{name}","load":"#)).unwrap();
        // (12 + 120 * 1.25) cycles at 72 MHz, every activation.
        let tail = &out[at..];
        let m = &tail[..tail.find("}}").unwrap()];
        assert!(
            m.contains(r#""slot_to_txrq_ns":{"max":2250,"p99":2250,"mean":2250.0,"#),
            "{m}"
        );
    }
    let (code, out, _) = rtcan(&[
        "sim",
        "robot.toml",
        "--seconds",
        "1",
        "--json",
        "--cpu",
        "off",
    ]);
    assert_eq!(code, 0);
    assert!(!out.contains(r#""cpu":"#), "no model, no cpu report");
    let (code, out, _) = rtcan(&[
        "sim",
        "robot.toml",
        "--seconds",
        "1",
        "--json",
        "--cpu-design",
        "old",
        "--cpi",
        "2",
    ]);
    assert_eq!(code, 0);
    assert!(
        out.contains(r#""cpu":{"design":"single-priority","cpi":2,"#),
        "{out}"
    );
    assert!(
        !out.contains(r#""slot_overlaps":0,"#),
        "the old design overlaps slots"
    );
}

#[test]
fn sim_rejects_bad_cpu_options() {
    for (args, msg) in [
        (&["--cpi", "abc"][..], "bad --cpi"),
        (&["--cpi", "0"][..], "--cpi must be in [0.5, 10]"),
        (&["--cpi", "NaN"][..], "--cpi must be in [0.5, 10]"),
        (&["--cpu-design", "fast"][..], "unknown --cpu-design `fast`"),
        (&["--cpu", "maybe"][..], "--cpu must be `on` or `off`"),
    ] {
        let mut a = vec!["sim", "robot.toml", "--seconds", "1"];
        a.extend_from_slice(args);
        let (code, _, err) = rtcan(&a);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(msg), "{args:?}: {err}");
    }
}
