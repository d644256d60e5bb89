//! `rtcan record FILE`: the bus as a candump log (`candump -l` format, readable by
//! can-utils and `rtcan decode`). Simulated frames are stamped from a real epoch: the
//! wall clock at start, or `--log-epoch SECONDS`; a replayed log keeps its own times.
use std::io::Write as _;

use rtcan_host::Source;
use rtcan_sim::candump;

use crate::link_args::{LinkArgs, HELP};

fn usage() -> String {
    format!(
        "usage: rtcan record FILE [--log-epoch SECONDS] [bus options] [--seconds S] [--count N]\n\n\
         writes every frame of the bus to FILE (`-`: standard output) in candump -l format;\n\
         --count counts frames here\n\n{HELP}"
    )
}

/// Runs `rtcan record`; returns the exit code.
pub fn run(args: &[String]) -> i32 {
    let mut la = LinkArgs::default();
    let (mut file, mut epoch) = (None, None);
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
            "--log-epoch" => match it.next().map(|v| v.parse::<f64>()) {
                Some(Ok(e)) if (0.0..1e11).contains(&e) => epoch = Some((e * 1e9) as u64),
                _ => {
                    return crate::usage_error(
                        "--log-epoch needs seconds since 1970 (e.g. 1700000000)",
                        &usage(),
                    )
                }
            },
            s if s.starts_with('-') && s != "-" => {
                return crate::usage_error(&format!("unknown option `{s}`"), &usage())
            }
            s if file.is_none() => file = Some(s.to_string()),
            s => return crate::usage_error(&format!("one file only (`{s}`)"), &usage()),
        }
    }
    let Some(file) = file else {
        return crate::usage_error("no output file given", &usage());
    };
    match record(&la, &file, epoch) {
        Ok(n) => {
            eprintln!("recorded {n} frames to {file}");
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}

fn record(la: &LinkArgs, file: &str, epoch: Option<u64>) -> Result<u64, String> {
    let (plan, _) = la.robot()?;
    let mut out: Box<dyn std::io::Write> = if file == "-" {
        Box::new(std::io::stdout().lock())
    } else {
        Box::new(std::io::BufWriter::new(
            std::fs::File::create(file).map_err(|e| format!("{file}: {e}"))?,
        ))
    };
    let epoch = match (&la.source, epoch) {
        (Source::Replay(_), _) => 0,
        (_, Some(e)) => e,
        (_, None) => std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_err(|e| e.to_string())?
            .as_nanos() as u64,
    };
    let mut link = la.open(&plan)?;
    let end = la.end_ns(link.now_ns());
    let mut n = 0u64;
    'run: while link.now_ns() < end {
        let Some(batch) = link.recv()? else { break };
        for s in batch {
            if s.time_ns >= end || la.count.is_some_and(|c| n >= c) {
                break 'run;
            }
            writeln!(
                out,
                "{}",
                candump::line(epoch + s.time_ns, "can0", &s.frame)
            )
            .map_err(|e| format!("{file}: {e}"))?;
            n += 1;
        }
    }
    out.flush().map_err(|e| format!("{file}: {e}"))?;
    Ok(n)
}
