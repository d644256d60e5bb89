//! `rtcan check robot.toml [--json]`: the same analysis as the build (rtcan-model), printed
//! for a person (plan, load, filters, calendar) or as JSON (docs/ROBOT_TOML.md).
//! `--against old.toml` also lists the modules whose image changes (`images_to_change`).
use crate::out;
use rtcan_model::{analyze, compat, read_source, report, Analysis, Robot, Status};
use std::path::Path;

/// Exit code: 0 admissible, 1 not admissible, 2 invalid input or usage, 3 undecided.
pub fn run(args: &[String]) -> i32 {
    let mut json = false;
    let mut path: Option<&str> = None;
    let mut against: Option<&str> = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--json" => json = true,
            "--against" => match it.next() {
                Some(old) => against = Some(old),
                None => {
                    eprintln!("error: `--against` needs the old robot.toml");
                    return 2;
                }
            },
            "-h" | "--help" => {
                println!("usage: rtcan check <robot.toml> [--json] [--against <old.toml>]");
                return 0;
            }
            s if s.starts_with('-') => {
                eprintln!("error: unknown option `{s}` (usage: rtcan check <robot.toml> [--json] [--against <old.toml>])");
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
        eprintln!("error: missing robot.toml (usage: rtcan check <robot.toml> [--json] [--against <old.toml>])");
        return 2;
    };
    let analysis = match read_source(Path::new(path), path) {
        Ok(source) => analyze(path, &source),
        Err(diagnostics) => Analysis {
            model: None,
            plan: None,
            diagnostics,
        },
    };
    let status = analysis.status();
    // A reader that stops early (`| head -1`) ends the output, not the command.
    if !analysis.diagnostics.is_empty() {
        out::eprint(&analysis.diagnostics.render());
    }
    let changes = match (against, &analysis.plan) {
        (Some(old_path), Some(plan)) => {
            match Robot::load(old_path) {
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
    if json {
        out::println(&compat::json_text(&analysis, changes.as_deref()));
    } else if let Some(plan) = &analysis.plan {
        out::print(&report::text(plan));
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
