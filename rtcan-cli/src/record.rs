//! `rtcan record FILE`: the bus as a candump log (`candump -l` format, readable by
//! can-utils and `rtcan decode`). Simulated frames are stamped from a real epoch: the
//! wall clock at start, or `--log-epoch SECONDS`; a replayed log keeps its own times.
use std::io::Write as _;

use rtcan_host::Source;
use rtcan_sim::candump;

use crate::link_args::LinkArgs;

/// `rtcan record`: writes every frame of the bus to FILE (`-`: standard output) in
/// `candump -l` format; --count counts frames here.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The log to write (`-`: standard output)
    #[arg(allow_hyphen_values = true)]
    file: String,
    /// Stamp simulated frames from this epoch: seconds since 1970 or `now` (default)
    #[arg(long, value_name = "SECONDS|now", value_parser = crate::log_epoch::parse)]
    log_epoch: Option<u64>,
    #[command(flatten)]
    la: LinkArgs,
}

/// Runs `rtcan record`; returns the exit code.
pub fn run(a: Args) -> i32 {
    match record(&a.la, &a.file, a.log_epoch) {
        Ok(n) => {
            eprintln!("recorded {n} frames to {}", a.file);
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
    let epoch = match (&la.source(), epoch) {
        (Source::Replay(_), _) => 0,
        (_, Some(e)) => e,
        (_, None) => crate::log_epoch::parse("now")?,
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
