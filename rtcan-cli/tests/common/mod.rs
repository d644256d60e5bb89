//! What the CLI's integration tests share: the workspace root and a runner of the
//! `rtcan` binary (each test binary uses some of it).
#![allow(dead_code, clippy::unwrap_used)]

use std::path::PathBuf;
use std::process::Command;

/// The workspace root (robot.toml, robots/).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Runs `rtcan ARGS` in the workspace root: (exit code, or -1 when killed by a signal;
/// stdout; stderr). Output that is not UTF-8 fails the test: every command prints text.
pub fn rtcan(args: &[&str]) -> (i32, String, String) {
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
