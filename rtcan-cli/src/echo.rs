//! `rtcan echo TOPIC [--json]`: every message of one topic as it arrives on the bus.
//! `module_state` names the module tables of a supervised robot, whichever module
//! publishes them (`module_state_<sync master>`, docs/SERVICES.md §1).
use std::io::Write as _;

use rtcan_host::value::to_json;
use rtcan_sim::decode::{render, Decoded, Decoder};

use crate::link_args::{entry, LinkArgs};

/// `rtcan echo`: prints each message of TOPIC (one line, or with --json one object per
/// line: {"time":SECONDS,"topic":NAME,"value":{FIELDS}}).
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The topic, by its robot.toml name
    topic: String,
    /// One JSON object per message
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    la: LinkArgs,
}

/// Runs `rtcan echo`; returns the exit code.
pub fn run(a: Args) -> i32 {
    match echo(&a.la, &a.topic, a.json) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}

fn echo(la: &LinkArgs, topic: &str, json: bool) -> Result<(), String> {
    let (plan, cat) = la.robot()?;
    let wanted = wanted(&plan, &cat, topic);
    if wanted.is_empty() {
        let names: Vec<&str> = cat.topics.iter().map(|t| t.name.as_str()).collect();
        return Err(format!(
            "no topic `{topic}` on the bus of {}; its topics: {}",
            plan.file,
            names.join(", ")
        ));
    }
    let mut link = la.open(&plan)?;
    let end = la.end_ns(link.now_ns());
    let mut dec = Decoder::new(&cat);
    let mut seen = 0u64;
    let out = std::io::stdout();
    let mut out = out.lock();
    while link.now_ns() < end && la.count.is_none_or(|c| seen < c) {
        let Some(batch) = link.recv()? else { break };
        for s in batch {
            if s.time_ns >= end || la.count.is_some_and(|c| seen >= c) {
                break;
            }
            let Some(d) = dec.push(&entry(&s)) else {
                continue;
            };
            let Decoded::Message {
                time_ns,
                topic: t,
                payload,
                ..
            } = &d
            else {
                continue;
            };
            if !wanted.contains(t) {
                continue;
            }
            seen += 1;
            let line = if json {
                let tp = cat.topics.get(*t).ok_or("topic vanished")?;
                serde_json::json!({
                    "time": *time_ns as f64 * 1e-9,
                    "topic": tp.name,
                    "value": to_json(tp, payload),
                })
                .to_string()
            } else {
                render(&d, &cat)
            };
            // A closed pipe (`| head`) ends the run quietly.
            if writeln!(out, "{line}").is_err() {
                return Ok(());
            }
        }
    }
    Ok(())
}

/// Catalog indices of the topics `name` names: the topic of that name, or for
/// `module_state` on a supervised robot every module table topic.
fn wanted(plan: &rtcan_model::Plan, cat: &rtcan_sim::decode::Catalog, name: &str) -> Vec<usize> {
    let family: Vec<&str> = match (&plan.module_state, name) {
        (Some(s), rtcan_model::module_state::FAMILY) => s
            .tables
            .iter()
            .filter_map(|&(_, t)| plan.topics.get(t).map(|x| x.name.as_str()))
            .collect(),
        _ => vec![name],
    };
    cat.topics
        .iter()
        .enumerate()
        .filter(|(_, t)| family.contains(&t.name.as_str()))
        .map(|(i, _)| i)
        .collect()
}
