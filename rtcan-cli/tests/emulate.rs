#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! `rtcan sim --emulate` (issue 12): what the command checks before starting `rtcan-emu`
//! (the emulator itself is tested in rtcan-emu/tests).
use std::path::PathBuf;
use std::process::Command;

fn rtcan(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_rtcan"))
        .args(args)
        .current_dir(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(".."))
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn emulate_runs_only_the_workspace_robot() {
    let other = std::fs::read_dir(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../robots"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "toml"))
        .unwrap();
    let (code, err) = rtcan(&["sim", other.to_str().unwrap(), "--emulate"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("workspace robot"), "{err}");
}

#[test]
fn emulate_rejects_simulator_only_options() {
    let (code, err) = rtcan(&["sim", "--emulate", "--load", "2"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("`--load` does not apply with --emulate"),
        "{err}"
    );
    let (code, err) = rtcan(&["sim", "robot.toml", "--emulate", "--seconds"]);
    assert_eq!(code, 2);
    // clap's report of a missing value.
    assert!(
        err.contains("a value is required for '--seconds <N>'"),
        "{err}"
    );
}

#[test]
fn emulate_refuses_faults_the_emulator_cannot_model() {
    // Checked before rtcan-emu starts: exit 2 and the reason, whether or not the
    // emulator is built.
    let (code, err) = rtcan(&["sim", "--emulate", "--fault", "motor1:dies@1s"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--fault `motor1:dies@1s`: `dies` cannot be emulated"),
        "{err}"
    );
    let (code, err) = rtcan(&["sim", "--emulate", "--ber", "1.5"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--ber must be in [0, 1)"), "{err}");
}
