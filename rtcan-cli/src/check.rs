//! `rtcan check robot.toml [--json]`: the same analysis as the build (rtcan-model), printed
//! for a person (plan, load, filters, calendar) or as JSON (docs/ROBOT_TOML.md).
//! `--against old.toml` also lists the modules whose image changes (`images_to_change`).
use crate::out;
use rtcan_model::{compat, lock, read_analysis, report, Robot, Status};
use std::path::Path;

/// Exit code: 0 admissible, 1 not admissible, 2 invalid input or usage, 3 undecided.
pub fn run(args: &[String]) -> i32 {
    let mut json = false;
    let mut path: Option<&str> = None;
    let mut against: Option<&str> = None;
    let mut update_lock = false;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--json" => json = true,
            "--update-lock" => update_lock = true,
            "--against" => match it.next() {
                Some(old) => against = Some(old),
                None => {
                    eprintln!("error: `--against` needs the old robot.toml");
                    return 2;
                }
            },
            "-h" | "--help" => {
                println!("usage: rtcan check <robot.toml> [--json] [--against <old.toml>] [--update-lock]");
                return 0;
            }
            s if s.starts_with('-') => {
                eprintln!("error: unknown option `{s}` (usage: rtcan check <robot.toml> [--json] [--against <old.toml>] [--update-lock])");
                return 2;
            }
            s if path.is_none() => path = Some(s),
            s => {
                eprintln!("error: unexpected argument `{s}` (one robot.toml at a time)");
                return 2;
            }
        }
    }
    let Some(path) = path else {
        eprintln!("error: missing robot.toml (usage: rtcan check <robot.toml> [--json] [--against <old.toml>] [--update-lock])");
        return 2;
    };
    let analysis = read_analysis(Path::new(path), path);
    let status = analysis.status();
    // A reader that stops early (`| head -1`) ends the output, not the command.
    if !analysis.diagnostics.is_empty() {
        out::eprint(&analysis.diagnostics.render());
    }
    let changes = match (against, &analysis.plan) {
        (Some(old_path), Some(plan)) => {
            match load_old(old_path, path) {
                Ok(old) => Some(compat::images_to_change(&old, plan)),
                Err(d) => {
                    out::eprint(&d.render());
                    eprintln!("error: `--against {old_path}`: the old robot.toml must itself be admissible");
                    return 2;
                }
            }
        }
        _ => None,
    };
    if let (true, Some(plan), Some(model)) = (update_lock, &analysis.plan, &analysis.model) {
        let lp = lock::path_for(Path::new(path));
        let prev = std::fs::read_to_string(&lp)
            .ok()
            .and_then(|t| lock::parse(&lp.display().to_string(), &t).ok());
        if let Err(e) = std::fs::write(&lp, lock::render(model, plan, prev.as_ref())) {
            eprintln!("error: cannot write `{}`: {e}", lp.display());
            return 2;
        }
        eprintln!("wrote {}", lp.display());
    }
    if json {
        out::println(&compat::json_text(&analysis, changes.as_deref()));
    } else if let Some(plan) = &analysis.plan {
        out::print(&report::text(plan));
        for c in &plan.chains {
            out::println(&format!(
                "chain {}: bound {} budget {}",
                c.name,
                c.bound_ns.map_or("unbounded".to_string(), |b| format!(
                    "{:.3} ms",
                    b as f64 / 1e6
                )),
                format_args!("{:.3} ms", c.budget_ns as f64 / 1e6)
            ));
        }
        if !plan.moves.is_empty() {
            out::print(&lock::text(&plan.moves));
        }
        if let Some(c) = &changes {
            out::print(&compat::text(c));
        }
    } else if status == Status::NotAdmissible {
        out::println(&format!("{path}: not admissible"));
    } else if status == Status::Undecided {
        out::println(&format!(
            "{path}: undecided (admission search budget exhausted)"
        ));
    }
    status.exit_code()
}

/// The old robot with its own lock, or else with the new robot's lock (which, before
/// `--update-lock`, still records the old allocation).
fn load_old(old: &str, new: &str) -> Result<rtcan_model::Plan, rtcan_model::Diagnostics> {
    let own = lock::path_for(Path::new(old));
    let theirs = lock::path_for(Path::new(new));
    if own.exists() || !theirs.exists() {
        return Robot::load(old);
    }
    let source = rtcan_model::read_source(Path::new(old), old)?;
    let shown = theirs.display().to_string();
    let text = rtcan_model::read_source(&theirs, &shown)?;
    let a = rtcan_model::analyze_locked(old, &source, Some((&shown, &text)));
    match a.plan {
        Some(p) if a.diagnostics.is_empty() => Ok(p),
        _ => Err(a.diagnostics),
    }
}
