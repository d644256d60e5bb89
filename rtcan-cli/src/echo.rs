//! `rtcan echo TOPIC [--json]`: every message of one topic as it arrives on the bus.
use std::io::Write as _;

use rtcan_host::value::to_json;
use rtcan_sim::decode::{render, Decoded, Decoder};

use crate::link_args::{entry, LinkArgs, HELP};

fn usage() -> String {
    format!(
        "usage: rtcan echo TOPIC [--json] [bus options] [--seconds S] [--count N]\n\n\
         prints each message of TOPIC (one line, or one JSON object per line with --json:\n\
         {{\"time\":SECONDS,\"topic\":NAME,\"value\":{{FIELDS}}}})\n\n{HELP}"
    )
}

/// Runs `rtcan echo`; returns the exit code.
pub fn run(args: &[String]) -> i32 {
    let mut la = LinkArgs::default();
    let (mut topic, mut json) = (None, false);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match la.take(a, &mut it) {
            Err(e) => return crate::usage_error(&e, &usage()),
            Ok(true) => continue,
            Ok(false) => {}
        }
        match a.as_str() {
            "-h" | "--help" => {
                println!("{}", usage());
                return 0;
            }
            "--json" => json = true,
            s if s.starts_with('-') => {
                return crate::usage_error(&format!("unknown option `{s}`"), &usage())
            }
            s if topic.is_none() => topic = Some(s.to_string()),
            s => return crate::usage_error(&format!("one topic only (`{s}`)"), &usage()),
        }
    }
    let Some(topic) = topic else {
        return crate::usage_error("no topic given", &usage());
    };
    match echo(&la, &topic, json) {
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
