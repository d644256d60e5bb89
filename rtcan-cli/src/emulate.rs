//! `rtcan sim [robot.toml] --emulate [--seconds N] [--seed N] [--cpi X] [--ber P] [--fault F]... [--json] [--images DIR]`: runs the
//! workspace robot's Triskar2 release images on emulated STM32F103s by starting the
//! `rtcan-emu` program (docs/EMULATOR.md). A separate process on purpose: rtcan-emu links
//! the GPL-2.0 Unicorn, which the `rtcan` command (MIT OR Apache-2.0) must not.
use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `rtcan-emu` with `forward`, the options that apply to it (checked by
/// `sim::emulate_args`); returns the exit code.
pub fn run(forward: &[String]) -> i32 {
    let exe = emulator();
    match Command::new(&exe).args(forward).status() {
        Ok(s) => s.code().unwrap_or(1),
        Err(e) => {
            eprintln!(
                "error: cannot start {}: {e} (build it: cargo build --release -p rtcan-emu)",
                exe.display()
            );
            1
        }
    }
}

pub fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// `rtcan-emu` beside this executable (same cargo target directory), else from PATH.
fn emulator() -> PathBuf {
    std::env::current_exe()
        .ok()
        .and_then(|p| p.parent().map(|d| d.join("rtcan-emu")))
        .filter(|p| p.exists())
        .unwrap_or_else(|| PathBuf::from("rtcan-emu"))
}
