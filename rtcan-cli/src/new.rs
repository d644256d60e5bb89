//! `rtcan new DIR --robot robot.toml [--rtcan PATH]`: writes (or updates) the firmware
//! workspace of a robot (rtcan-codegen `scaffold`: images, nodes, simulator entry,
//! probe-rs runner, budgets). Generated files are rewritten; the user's files (node
//! sources) are written only when absent; budgets.toml gets only new modules' sections.
use rtcan_codegen::scaffold::{scaffold, Owner};
use rtcan_model::read_analysis;
use std::path::{Path, PathBuf};

/// `rtcan new`: a firmware workspace for a robot.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The workspace to write or update
    #[arg(value_name = "DIR")]
    dir: PathBuf,
    /// The robot (default: DIR/robot.toml; copied to DIR/robot.toml otherwise)
    #[arg(long, value_name = "robot.toml")]
    robot: Option<PathBuf>,
    /// The rtcan repository its crates come from (default: the one this binary was
    /// built from)
    #[arg(long, value_name = "repository")]
    rtcan: Option<PathBuf>,
}

/// Exit code: 0 written, 2 invalid robot.toml, usage or I/O error.
pub fn run(a: Args) -> i32 {
    let dir = a.dir;
    let rtcan = a.rtcan;
    let dest_robot = dir.join("robot.toml");
    let robot = a.robot.unwrap_or_else(|| dest_robot.clone());
    let shown = robot.display().to_string();
    let analysis = read_analysis(&robot, &shown);
    let plan = match analysis.plan {
        Some(p) if analysis.diagnostics.is_empty() => p,
        _ => {
            crate::out::eprint(&analysis.diagnostics.render());
            eprintln!("error: {shown} is not a valid, admissible robot: nothing written");
            return 2;
        }
    };
    let repo = match rtcan.map_or_else(default_repo, Ok) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let repo = match repo.canonicalize() {
        Ok(r) if r.join("boards/app/Cargo.toml").is_file() => r,
        _ => {
            eprintln!(
                "error: `{}` is not the rtcan repository (no boards/app/Cargo.toml); give it with --rtcan",
                repo.display()
            );
            return 2;
        }
    };
    match write_all(&dir, &robot, &dest_robot, &repo, &plan) {
        Ok(log) => {
            crate::out::print(&log);
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            2
        }
    }
}

/// The repository this binary was built from (rtcan-cli is one of its crates).
fn default_repo() -> Result<PathBuf, String> {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .ok_or_else(|| "no rtcan repository; give it with --rtcan".to_string())
}

fn io_err(p: &Path, e: std::io::Error) -> String {
    format!("`{}`: {e}", p.display())
}

fn write(p: &Path, text: &str) -> Result<(), String> {
    if let Some(d) = p.parent() {
        std::fs::create_dir_all(d).map_err(|e| io_err(d, e))?;
    }
    std::fs::write(p, text).map_err(|e| io_err(p, e))
}

/// Writes the workspace; returns one line per file: `created`, `updated` (generated,
/// changed), `appended` (budget sections) or `kept` (the user's, or unchanged).
fn write_all(
    dir: &Path,
    robot: &Path,
    dest_robot: &Path,
    repo: &Path,
    plan: &rtcan_model::Plan,
) -> Result<String, String> {
    let mut log = String::new();
    let mut note = |what: &str, p: &str| log.push_str(&format!("{what:<9} {p}\n"));
    // The robot itself: the workspace's copy is what every crate reads.
    let text = std::fs::read_to_string(robot).map_err(|e| io_err(robot, e))?;
    match std::fs::read_to_string(dest_robot) {
        Ok(old) if old == text => note("kept", "robot.toml"),
        Ok(_) => {
            write(dest_robot, &text)?;
            note("updated", "robot.toml");
        }
        Err(_) => {
            write(dest_robot, &text)?;
            note("created", "robot.toml");
        }
    }
    // Lock files seeded from the repository's: the same dependency versions it builds
    // and tests with, and no registry resolution on the first build.
    for (seed, to) in [
        ("Cargo.lock", "Cargo.lock"),
        ("examples/triskar2/Cargo.lock", "firmware/Cargo.lock"),
    ] {
        let dst = dir.join(to);
        if !dst.exists() {
            if let Ok(t) = std::fs::read_to_string(repo.join(seed)) {
                write(&dst, &t)?;
                note("created", to);
            }
        }
    }
    let repo_str = repo.display().to_string();
    for f in scaffold(plan, &repo_str) {
        let p = dir.join(&f.path);
        let old = std::fs::read_to_string(&p).ok();
        match (&f.owner, old) {
            (_, None) => {
                write(&p, &f.text)?;
                note("created", &f.path);
            }
            (Owner::Generated, Some(o)) if o != f.text => {
                write(&p, &f.text)?;
                note("updated", &f.path);
            }
            (Owner::UserSections(sections), Some(o)) => {
                let missing: Vec<&(String, String)> = sections
                    .iter()
                    .filter(|(name, _)| !o.lines().any(|l| l.trim() == format!("[{name}]")))
                    .collect();
                if missing.is_empty() {
                    note("kept", &f.path);
                } else {
                    let mut t = o;
                    for (_, s) in missing {
                        if !t.ends_with("\n\n") {
                            t.push('\n');
                        }
                        t.push_str(s);
                    }
                    write(&p, &t)?;
                    note("appended", &f.path);
                }
            }
            (_, Some(_)) => note("kept", &f.path),
        }
    }
    Ok(log)
}
