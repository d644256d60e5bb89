//! `rtcan monitor`: modules, topics and bus load of a running bus. Live, the table is
//! redrawn in place every `--every` seconds of wall time; `--once` prints it once at the
//! end of the run (`--seconds`, default 2), which is what scripts and CI use.
use std::io::Write as _;
use std::time::{Duration, Instant};

use rtcan_host::monitor::Monitor;
use rtcan_sim::decode::Decoder;

use crate::link_args::{entry, LinkArgs, HELP};

fn usage() -> String {
    format!(
        "usage: rtcan monitor [--once] [--every S] [bus options] [--seconds S]\n\n\
         --once      run the bus for --seconds (default 2) and print the table once\n\
         --every S   live: redraw every S wall-clock seconds (default 0.5) until stopped\n\n{HELP}"
    )
}

/// Runs `rtcan monitor`; returns the exit code.
pub fn run(args: &[String]) -> i32 {
    let mut la = LinkArgs::default();
    let (mut once, mut every) = (false, 0.5f64);
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
            "--once" => once = true,
            "--every" => match it.next().map(|v| v.parse::<f64>()) {
                Some(Ok(e)) if e > 0.0 && e.is_finite() => every = e,
                _ => return crate::usage_error("--every needs seconds > 0", &usage()),
            },
            s => return crate::usage_error(&format!("unexpected `{s}`"), &usage()),
        }
    }
    if once && la.seconds.is_none() {
        la.seconds = Some(2.0);
    }
    match monitor(&la, once, Duration::from_secs_f64(every)) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}

fn monitor(la: &LinkArgs, once: bool, every: Duration) -> Result<(), String> {
    let (plan, cat) = la.robot()?;
    let names = plan.modules.iter().map(|m| m.name.clone()).collect();
    let mut mon = Monitor::new(&cat, names, plan.bus.bitrate);
    let mut link = la.open(&plan)?;
    let end = la.end_ns(link.now_ns());
    let mut dec = Decoder::new(&cat);
    let mut last_draw = Instant::now();
    let mut messages = 0u64;
    'run: while link.now_ns() < end {
        let Some(batch) = link.recv()? else { break };
        for s in batch {
            if s.time_ns >= end || la.count.is_some_and(|c| messages >= c) {
                break 'run;
            }
            mon.frame(&s, &cat);
            if let Some(d) = dec.push(&entry(&s)) {
                messages += 1;
                mon.record(&d, s.time_ns);
            }
        }
        if !once && last_draw.elapsed() >= every {
            last_draw = Instant::now();
            // Home the cursor and clear: the table redraws in place.
            print!("\x1b[H\x1b[2J{}", mon.render(&cat));
            let _ = std::io::stdout().flush();
        }
    }
    print!("{}", mon.render(&cat));
    Ok(())
}
