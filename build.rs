//! Build script of the `rtcan` facade: checks and generates the workspace robot.
//!
//! Reads the robot named by `RTCAN_ROBOT` (relative paths are taken from this package's
//! directory, the workspace root) or, when unset, `robot.toml` next to Cargo.toml if it
//! exists. It runs the same model and code generator as `rtcan::robot!`; on success it
//! writes `OUT_DIR/robot.rs` (exposed as `rtcan::robot_toml` under `cfg(rtcan_robot)`),
//! on any diagnostic it prints them all, rustc-style, and fails the build.
use std::path::PathBuf;
use std::process::{exit, Command};

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-env-changed=RTCAN_ROBOT");
    println!("cargo::rustc-check-cfg=cfg(rtcan_robot)");
    let root = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    let (path, shown) = match std::env::var_os("RTCAN_ROBOT") {
        Some(p) => {
            let p = PathBuf::from(p);
            let shown = p.display().to_string();
            (if p.is_relative() { root.join(p) } else { p }, shown)
        }
        None => {
            let p = root.join("robot.toml");
            if !p.exists() {
                return; // no workspace robot: `rtcan::robot_toml` is absent
            }
            (p, "robot.toml".to_string())
        }
    };
    println!("cargo::rerun-if-changed={}", path.display());
    // The same reading rules as `rtcan check` and `rtcan::robot!` (UTF-8, 16 MiB cap).
    // With its robot.lock when there is one (stable allocation, docs/ROBOT_TOML.md).
    println!(
        "cargo::rerun-if-changed={}",
        rtcan_model::lock::path_for(&path).display()
    );
    let analysis = rtcan_model::read_analysis(&path, &shown);
    let plan = match analysis.plan {
        Some(p) if analysis.diagnostics.is_empty() => p,
        _ => {
            // Every diagnostic at once, as `rtcan check` prints them.
            eprint!("{}", analysis.diagnostics.render());
            println!(
                "cargo::error={} has {} error(s), shown rustc-style in the build script stderr below",
                shown,
                analysis.diagnostics.items.len()
            );
            exit(1);
        }
    };
    let code = rtcan_codegen::generate_source(&plan, &rtcan_codegen::Options::default());
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default()).join("robot.rs");
    if let Err(e) = std::fs::write(&out, code) {
        eprintln!("error: cannot write `{}`: {e}", out.display());
        exit(1);
    }
    // Best effort: readable generated code for people who open it; the build does not
    // depend on rustfmt being installed.
    let rustfmt = std::env::var_os("RUSTFMT").unwrap_or_else(|| "rustfmt".into());
    let _ = Command::new(rustfmt)
        .args(["--edition", "2021"])
        .arg(&out)
        .status();
    println!("cargo::rustc-cfg=rtcan_robot");
}
