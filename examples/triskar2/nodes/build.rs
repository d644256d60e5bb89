//! Build script of the Triskar2 nodes: one app per module, composed of the nodes
//! robot.toml places on it (`rtcan_codegen::apps`), written to `OUT_DIR/apps.rs` and
//! included by `app`, with each module's RTIC app macro (`rtcan_codegen::rtic_app`: one
//! task per node at its priority, `triskar2_nodes::<module>_app!`). It reads the robot
//! the `rtcan` facade generates `rtcan::robot_toml` from, by the same rule (`RTCAN_ROBOT`, relative paths from the
//! repository root, else the root robot.toml), and the apps check at compile time that
//! both came from the same file. Moving a node in robot.toml therefore moves its task to
//! the other module's app; no node code names its module.
use std::path::PathBuf;
use std::process::exit;

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-env-changed=RTCAN_ROBOT");
    let here = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    let root = here.join("../../..");
    let (path, shown) = match std::env::var_os("RTCAN_ROBOT") {
        Some(p) => {
            let p = PathBuf::from(p);
            let shown = p.display().to_string();
            (if p.is_relative() { root.join(p) } else { p }, shown)
        }
        None => (root.join("robot.toml"), "robot.toml".to_string()),
    };
    println!("cargo::rerun-if-changed={}", path.display());
    println!(
        "cargo::rerun-if-changed={}",
        rtcan_model::lock::path_for(&path).display()
    );
    let analysis = rtcan_model::read_analysis(&path, &shown);
    let plan = match analysis.plan {
        Some(p) if analysis.diagnostics.is_empty() => p,
        _ => {
            eprint!("{}", analysis.diagnostics.render());
            println!(
                "cargo::error={shown}: not a valid robot (diagnostics in the build script stderr)"
            );
            exit(1);
        }
    };
    let spec = rtcan_codegen::apps::AppsSpec {
        robot: "rtcan::robot_toml",
        tasks: "crate::tasks",
    };
    // Each module's RTIC app (`triskar2_nodes::<module>_app!`, invoked by the firmware's
    // bins): one task per node placed there, at its robot.toml priority.
    let rtic = rtcan_codegen::rtic_app::RticSpec {
        tasks: "triskar2_nodes::tasks",
        skeleton: "rtcan_app_stm32f103::module_app",
    };
    let text = format!(
        "{}\n{}",
        rtcan_codegen::apps::module_apps(&plan, &spec),
        rtcan_codegen::rtic_app::rtic_app_macros(&plan, &rtic)
    );
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default()).join("apps.rs");
    if let Err(e) = std::fs::write(&out, text) {
        eprintln!("error: cannot write `{}`: {e}", out.display());
        exit(1);
    }
}
