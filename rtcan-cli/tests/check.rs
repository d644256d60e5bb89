#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! `rtcan check` exit codes and outputs on the reference robots.
mod common;
use common::{root, rtcan};
use std::process::Command;

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

/// `rtcan check ... | head -1`: the reader closes the pipe after one line; the command
/// must stop writing quietly, not panic with "failed printing to stdout" (exit 101).
#[test]
fn closed_stdout_pipe_is_not_a_panic() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    // The JSON plan of 200 HRT topics is ~150 KB, more than a pipe buffers.
    let mut child = Command::new(env!("CARGO_BIN_EXE_rtcan"))
        .args(["check", "robots/hrt200.toml", "--json"])
        .current_dir(root())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert_eq!(first, "{\n");
    // The reader is dropped here: the pipe is closed.
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(out.status.code(), Some(0), "{err}");
}

/// A device that never ends is refused at the size cap, quickly and clearly.
#[test]
fn endless_input_hits_the_size_cap() {
    let (code, out, err) = rtcan(&["check", "/dev/zero"]);
    assert_eq!(code, 2);
    assert!(out.is_empty());
    assert!(
        err.starts_with("error[file-too-large]: `/dev/zero` is larger than 16 MiB\n"),
        "{err}"
    );
}

/// Invalid UTF-8 is reported with its byte offset, line and column.
#[test]
fn invalid_utf8_names_the_byte() {
    let dir = std::env::temp_dir().join(format!("rtcan-utf8-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("robot.toml");
    std::fs::write(&file, b"[bus]\nmaster = \"m\xff\"\n").unwrap();
    let (code, _, err) = rtcan(&["check", file.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(
        err.contains("error[invalid-utf8]: invalid UTF-8 at byte 17 (line 2, column 12)"),
        "{err}"
    );
    assert!(err.contains(":2:12\n"), "{err}");
}

#[test]
fn against_lists_images_to_change() {
    let dir = std::env::temp_dir().join(format!("rtcan-against-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let src = std::fs::read_to_string(root().join("robot.toml")).unwrap();
    let new = dir.join("new.toml");
    std::fs::write(
        &new,
        src.replacen("period = \"40ms\"", "period = \"80ms\"", 1),
    )
    .unwrap();
    let newp = new.to_str().unwrap();
    // Same file: nothing to rebuild.
    let (code, out, _) = rtcan(&["check", "robot.toml", "--against", "robot.toml"]);
    assert_eq!(code, 0);
    assert!(out.contains("images to change: 0\n"), "{out}");
    let (code, out, _) = rtcan(&["check", newp, "--against", "robot.toml"]);
    assert_eq!(code, 0);
    assert!(out.contains("  proximity\n"), "{out}");
    assert!(out.contains("    - topic \"proximity\": "), "{out}");
    let (code, out, _) = rtcan(&["check", newp, "--json", "--against", "robot.toml"]);
    assert_eq!(code, 0);
    let at = out
        .find("\"images_to_change\": [")
        .expect("images_to_change field");
    assert!(out[at..].contains("\"module\": \"gateway\""), "{out}");
    assert!(out[at..].contains("\"module\": \"proximity\""), "{out}");
    // Missing argument and a bad old file are usage errors.
    assert_eq!(rtcan(&["check", "robot.toml", "--against"]).0, 2);
    assert_eq!(
        rtcan(&[
            "check",
            "robot.toml",
            "--against",
            "robots/broken/none.toml"
        ])
        .0,
        2
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
