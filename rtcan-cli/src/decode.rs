//! `rtcan decode <log|-> --robot robot.toml`: candump log → topic-level messages, line by
//! line (a record is printed as soon as its last frame is read; memory does not grow
//! with the log).
use std::io::{BufRead, Read as _};

use rtcan_sim::candump::{classify, Line};
use rtcan_sim::decode::{plan_catalog, render, scenario_catalog, Catalog, Decoder};
use rtcan_sim::paper;

/// Malformed lines reported one by one; the rest only counted.
const REPORTED_BAD_LINES: u64 = 10;

/// Longest line read as one (a candump line is under 100 bytes; longer input is cut
/// into malformed pieces of this size).
const MAX_LINE: u64 = 4096;

/// `rtcan decode`: remote, error and CAN FD frames are skipped and counted; malformed
/// lines are reported (first 10) and counted; exit 0 when every line parsed, 1
/// otherwise, 2 on usage errors.
#[derive(clap::Args, Debug)]
#[command(group = clap::ArgGroup::new("catalog").required(true).args(["robot", "scenario"]))]
pub struct Args {
    /// A `candump -l` log; `-` reads standard input
    #[arg(value_name = "candump.log | -", allow_hyphen_values = true)]
    log: String,
    /// The robot the log was recorded on (topics, types, fingerprint)
    #[arg(long, value_name = "FILE")]
    robot: Option<String>,
    /// A built-in scenario's catalog (rtcan-paper)
    #[arg(long, value_name = "NAME")]
    scenario: Option<String>,
    /// Decode messages of senders whose heartbeat carries another robot's fingerprint
    /// too (marked FOREIGN SENDER); by default they are refused
    #[arg(long)]
    force: bool,
}

fn catalog(a: &Args) -> Result<Catalog, String> {
    match (&a.robot, a.scenario.as_deref()) {
        (Some(_), Some(_)) => Err("give --robot or --scenario, not both".into()),
        (Some(r), None) => rtcan_model::Robot::load(r)
            .map(|plan| plan_catalog(&plan))
            .map_err(|d| d.render()),
        (None, Some("rtcan-paper")) => {
            paper::scenario(paper::our_laxity(), 1.0).map(|sc| scenario_catalog(&sc))
        }
        (None, Some(other)) => Err(format!(
            "unknown scenario `{other}` (decode knows rtcan-paper; other robots: --robot FILE)"
        )),
        (None, None) => Err("need --robot FILE or --scenario rtcan-paper".into()),
    }
}

/// Runs `rtcan decode`; returns the exit code.
pub fn run(a: Args) -> i32 {
    let cat = match catalog(&a) {
        Ok(c) => c,
        Err(e) => {
            eprint!("{e}");
            if !e.ends_with('\n') {
                eprintln!();
            }
            return 2;
        }
    };
    let input: Box<dyn BufRead> = if a.log == "-" {
        Box::new(std::io::stdin().lock())
    } else {
        match std::fs::File::open(&a.log) {
            Ok(f) => Box::new(std::io::BufReader::new(f)),
            Err(e) => {
                eprintln!("error: {}: {e}", a.log);
                return 2;
            }
        }
    };
    let name = if a.log == "-" {
        "<stdin>"
    } else {
        a.log.as_str()
    };
    decode_stream(input, name, &cat, a.force, &mut std::io::stdout().lock())
}

/// Decodes `input` line by line onto `out`; diagnostics on stderr. Returns the exit code.
fn decode_stream(
    mut input: impl BufRead,
    name: &str,
    cat: &Catalog,
    force: bool,
    out: &mut impl std::io::Write,
) -> i32 {
    let mut dec = Decoder::new(cat);
    dec.force = force;
    let (mut skipped, mut bad_lines, mut lineno) = (0u64, 0u64, 0u64);
    let mut warned = false;
    let mut line = Vec::new();
    loop {
        line.clear();
        // A line is read up to MAX_LINE bytes: input without newlines (`/dev/zero`) is
        // malformed lines of bounded size, not an ever-growing buffer.
        match (&mut input).take(MAX_LINE).read_until(b'\n', &mut line) {
            Ok(0) => break,
            Ok(_) => {}
            Err(e) => {
                eprintln!("error: {name}: {e}");
                return 1;
            }
        }
        lineno += 1;
        let too_long = line.len() as u64 == MAX_LINE && line.last() != Some(&b'\n');
        let parsed = if too_long {
            Err("line too long")
        } else {
            std::str::from_utf8(&line)
                .map_err(|_| "not UTF-8")
                .and_then(classify)
        };
        let entry = match parsed {
            Ok(Line::Frame(e)) => e,
            Ok(Line::Blank) => continue,
            Ok(Line::Skipped(_)) => {
                skipped += 1;
                continue;
            }
            Err(what) => {
                bad_lines += 1;
                if bad_lines <= REPORTED_BAD_LINES {
                    eprintln!("warning: {name}:{lineno}: {what} (line skipped)");
                }
                continue;
            }
        };
        let Some(rec) = dec.push(&entry) else {
            continue;
        };
        if !warned && dec.counts.foreign_heartbeats > 0 {
            warned = true;
            if let Some(fp) = cat.fingerprint {
                eprintln!(
                    "warning: {name}:{lineno}: a heartbeat carries another robot's fingerprint (robot: {fp:#010x}); {}",
                    if force {
                        "its senders' messages are decoded anyway (--force), marked FOREIGN SENDER"
                    } else {
                        "its senders' messages are not decoded (--force decodes them)"
                    }
                );
            }
        }
        // A closed pipe (`| head`) ends the listing quietly.
        if writeln!(out, "{}", render(&rec, cat)).is_err() {
            return 0;
        }
    }
    let c = dec.counts;
    let _ = writeln!(
        out,
        "-- {} frames: {} messages, {} frames not attributed, {skipped} remote/error/FD frames skipped, {bad_lines} malformed lines",
        c.frames, c.messages, c.unattributed
    );
    if c.foreign_heartbeats > 0 {
        let _ = writeln!(
            out,
            "-- {} heartbeats carry another robot's fingerprint: {} messages of their senders refused, {} decoded with --force",
            c.foreign_heartbeats, c.refused, c.forced
        );
        eprintln!(
            "warning: {} heartbeats carry another robot's fingerprint than {:#010x}: the log is not of this robot (or of another version of it)",
            c.foreign_heartbeats,
            cat.fingerprint.unwrap_or(0)
        );
    }
    let _ = out.flush();
    if bad_lines > REPORTED_BAD_LINES {
        eprintln!(
            "warning: {name}: {} more malformed lines",
            bad_lines - REPORTED_BAD_LINES
        );
    }
    i32::from(bad_lines > 0)
}
