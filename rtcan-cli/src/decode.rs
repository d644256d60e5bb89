//! `rtcan decode <log> --robot robot.toml`: candump log → topic-level messages.
use rtcan_sim::decode::{decode, plan_catalog, render, scenario_catalog, Catalog, Decoded};
use std::io::Write as _;

use rtcan_sim::{candump, paper};

const USAGE: &str =
    "usage: rtcan decode <candump.log> (--robot robot.toml | --scenario rtcan-paper)";

/// Runs `rtcan decode`; returns the exit code.
pub fn run(args: &[String]) -> i32 {
    let mut log = None;
    let mut robot = None;
    let mut scenario = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--robot" => robot = it.next().cloned(),
            "--scenario" => scenario = it.next().cloned(),
            s if s.starts_with("--") => {
                eprintln!("error: unknown option `{s}`\n{USAGE}");
                return 2;
            }
            s => log = Some(s.to_string()),
        }
    }
    let Some(log) = log else {
        eprintln!("error: no log file\n{USAGE}");
        return 2;
    };
    let cat: Catalog = match (robot, scenario.as_deref()) {
        (Some(r), _) => match rtcan_model::Robot::load(&r) {
            Ok(plan) => plan_catalog(&plan),
            Err(d) => {
                eprint!("{}", d.render());
                return 2;
            }
        },
        (None, Some("rtcan-paper")) => match paper::scenario(paper::our_laxity(), 1.0) {
            Ok(sc) => scenario_catalog(&sc),
            Err(e) => {
                eprintln!("error: {e}");
                return 2;
            }
        },
        _ => {
            eprintln!("error: need --robot or --scenario rtcan-paper\n{USAGE}");
            return 2;
        }
    };
    let text = match std::fs::read_to_string(&log) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {log}: {e}");
            return 2;
        }
    };
    let entries = match candump::parse(&text) {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: {log}:{}: {}", e.line, e.what);
            return 2;
        }
    };
    let out = decode(&entries, &cat);
    let (mut msgs, mut unknown) = (0, 0);
    let mut stdout = std::io::stdout().lock();
    for d in &out {
        match d {
            Decoded::Message { .. } => msgs += 1,
            Decoded::Unattributed { .. } => unknown += 1,
            _ => {}
        }
        // A closed pipe (`| head`) ends the listing quietly.
        if writeln!(stdout, "{}", render(d, &cat)).is_err() {
            return 0;
        }
    }
    let _ = writeln!(
        stdout,
        "-- {} frames: {msgs} messages, {unknown} frames not attributed",
        entries.len()
    );
    0
}
