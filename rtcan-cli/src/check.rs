//! `rtcan check robot.toml [--json]`: the same analysis as the build (rtcan-model), printed
//! for a person (plan, load, filters, calendar) or as JSON (docs/ROBOT_TOML.md).
//! `--against old.toml` also lists the modules whose image changes (`images_to_change`).
use crate::out;
use rtcan_model::{compat, lock, read_analysis, report, Robot, Status};
use std::path::Path;

/// `rtcan check`: the plan for a person, or JSON (docs/ROBOT_TOML.md).
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The robot
    #[arg(value_name = "robot.toml")]
    path: String,
    /// The analysis as JSON (plan, diagnostics, field layouts of every topic)
    #[arg(long)]
    json: bool,
    /// Also list the modules whose image changes from this older robot.toml
    #[arg(long, value_name = "old.toml")]
    against: Option<String>,
    /// Write robot.lock with this plan's allocation
    #[arg(long)]
    update_lock: bool,
    /// Write the bus as a DBC file (cantools, SavvyCAN): the single-frame HRT and NRT
    /// topics and the heartbeats, the messages whose CAN identifier is fixed
    #[arg(long, value_name = "FILE")]
    dbc: Option<String>,
}

/// Exit code: 0 admissible, 1 not admissible, 2 invalid input or usage, 3 undecided.
pub fn run(a: Args) -> i32 {
    let (path, json, update_lock) = (a.path.as_str(), a.json, a.update_lock);
    let against = a.against.as_deref();
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
    if let (Some(file), Some(plan)) = (&a.dbc, &analysis.plan) {
        if let Err(e) = std::fs::write(file, rtcan_host::dbc::dbc(plan)) {
            eprintln!("error: cannot write `{file}`: {e}");
            return 2;
        }
        eprintln!("wrote {file}");
    }
    if json {
        let text = compat::json_text(&analysis, changes.as_deref());
        out::println(&with_layouts(text, analysis.plan.as_ref()));
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

/// The check's JSON with each topic's field layout added as `fields`: name, type, byte
/// offset, bytes, and `len` for arrays (the layout tools such as SavvyCAN need to decode
/// every topic, including those a DBC cannot hold).
fn with_layouts(text: String, plan: Option<&rtcan_model::Plan>) -> String {
    let Some(plan) = plan else { return text };
    let Ok(mut v) = serde_json::from_str::<serde_json::Value>(&text) else {
        return text;
    };
    let Some(topics) = v.get_mut("topics").and_then(|t| t.as_array_mut()) else {
        return text;
    };
    for t in topics.iter_mut() {
        let Some(obj) = t.as_object_mut() else {
            continue;
        };
        let name = obj.get("name").and_then(|n| n.as_str()).unwrap_or("");
        let Some(tp) = plan.topics.iter().find(|p| p.name == name) else {
            continue;
        };
        let fields: Vec<serde_json::Value> = plan
            .types
            .get(tp.ty)
            .map(|ty| {
                ty.fields
                    .iter()
                    .map(|f| {
                        let n = f.ty.len.map_or(1, usize::from);
                        let mut o = serde_json::json!({
                            "name": f.name,
                            "type": f.ty.prim.name(),
                            "offset": f.offset,
                            "bytes": f.ty.prim.size() * n,
                        });
                        if let (Some(len), Some(m)) = (f.ty.len, o.as_object_mut()) {
                            m.insert("len".into(), len.into());
                        }
                        o
                    })
                    .collect()
            })
            .unwrap_or_default();
        obj.insert("fields".into(), fields.into());
    }
    serde_json::to_string_pretty(&v).unwrap_or(text)
}
