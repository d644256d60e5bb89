//! `rtcan echo TOPIC [--json]`: every message of one topic as it arrives on the bus.
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
    let Some(ti) = cat.topics.iter().position(|t| t.name == topic) else {
        let names: Vec<&str> = cat.topics.iter().map(|t| t.name.as_str()).collect();
        return Err(format!(
            "no topic `{topic}` on the bus of {}; its topics: {}",
            plan.file,
            names.join(", ")
        ));
    };
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
            if *t != ti {
                continue;
            }
            seen += 1;
            let line = if json {
                let tp = cat.topics.get(ti).ok_or("topic vanished")?;
                serde_json::json!({
                    "time": *time_ns as f64 * 1e-9,
                    "topic": topic,
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
