//! `rtcan sim [robot.toml] --emulate [--seconds N] [--seed N] [--cpi X] [--json] [--images DIR]`: runs the
//! workspace robot's Triskar2 release images on emulated STM32F103s by starting the
//! `rtcan-emu` program (docs/EMULATOR.md). A separate process on purpose: rtcan-emu links
//! the GPL-2.0 Unicorn, which the `rtcan` command (MIT OR Apache-2.0) must not.
use std::path::{Path, PathBuf};
use std::process::Command;

/// Whether `args` ask for the emulator.
pub fn wanted(args: &[String]) -> bool {
    args.iter().any(|a| a == "--emulate")
}

/// Runs `rtcan-emu` with the options that apply to it; returns the exit code.
pub fn run(args: &[String]) -> i32 {
    let mut forward = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--emulate" => {}
            "--json" => forward.push(a.clone()),
            "--seconds" | "--images" | "--seed" | "--cpi" => {
                let Some(v) = it.next() else {
                    eprintln!("error: {a} needs a value");
                    return 2;
                };
                forward.push(a.clone());
                forward.push(v.clone());
            }
            s if s.starts_with('-') => {
                eprintln!("error: `{s}` does not apply with --emulate (options: --seconds, --seed, --cpi, --json, --images)");
                return 2;
            }
            robot => {
                // The images are built from the workspace robot: another file cannot run.
                if !same_file(Path::new(robot), Path::new("robot.toml")) {
                    eprintln!(
                        "error: --emulate runs the images of the workspace robot (./robot.toml), not `{robot}`"
                    );
                    return 2;
                }
            }
        }
    }
    let exe = emulator();
    match Command::new(&exe).args(&forward).status() {
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

fn same_file(a: &Path, b: &Path) -> bool {
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
