//! `rtcan monitor`: modules, topics and bus load of a running bus. Live on a terminal,
//! the ratatui screen (monitor_tui.rs) is redrawn every `--every` seconds of wall time
//! until q, Esc or Ctrl-C (into a pipe, the plain table is); `--once` prints the table
//! once at the end of the run (`--seconds`, default 2), `--once --screen` the screen as
//! text: what scripts and CI use.
use std::io::Write as _;
use std::time::{Duration, Instant};

use rtcan_host::monitor::Monitor;
use rtcan_sim::decode::Decoder;

use crate::link_args::{entry, positive, LinkArgs};

/// `rtcan monitor`: live, the table is redrawn every --every seconds until stopped;
/// --once runs the bus for --seconds (default 2) and prints the table once.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Run the bus for --seconds (default 2) and print the table once
    #[arg(long)]
    once: bool,
    /// With --once: print the live screen (as text) instead of the plain table
    #[arg(long, requires = "once")]
    screen: bool,
    /// Live: redraw every S wall-clock seconds
    #[arg(long, value_name = "S", default_value_t = 0.5, value_parser = positive)]
    every: f64,
    #[command(flatten)]
    la: LinkArgs,
}

/// Runs `rtcan monitor`; returns the exit code.
pub fn run(mut a: Args) -> i32 {
    if a.once && a.la.seconds.is_none() {
        a.la.seconds = Some(2.0);
    }
    match monitor(&a.la, a.once, a.screen, Duration::from_secs_f64(a.every)) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}

/// The bus's name on the screen's first line.
fn title(la: &LinkArgs) -> String {
    match la.source() {
        rtcan_host::Source::Sim(p) => format!("--sim {}", p.display()),
        rtcan_host::Source::Replay(p) => format!("--replay {}", p.display()),
        rtcan_host::Source::Serial(p) => format!("--serial {p}"),
        rtcan_host::Source::Can(i) => format!("--can {i}"),
    }
}

fn monitor(la: &LinkArgs, once: bool, screen: bool, every: Duration) -> Result<(), String> {
    let title = title(la);
    let (plan, cat) = la.robot()?;
    let names: Vec<String> = plan.modules.iter().map(|m| m.name.clone()).collect();
    let mut mon = Monitor::new(&cat, names.clone(), plan.bus.bitrate);
    // A supervised robot's module tables (`module_state_<module>`): the last one is shown.
    let tables: Vec<usize> = plan.module_state.as_ref().map_or_else(Vec::new, |s| {
        s.tables
            .iter()
            .filter_map(|&(_, t)| plan.topics.get(t))
            .filter_map(|t| cat.topics.iter().position(|c| c.name == t.name))
            .collect()
    });
    let mut table = None;
    let mut link = la.open(&plan)?;
    let end = la.end_ns(link.now_ns());
    let mut dec = Decoder::new(&cat);
    let mut last_draw = Instant::now();
    let mut messages = 0u64;
    let mut live = if once {
        None
    } else {
        crate::monitor_tui::Live::start()
    };
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
                if let rtcan_sim::decode::Decoded::Message {
                    time_ns,
                    topic,
                    payload,
                    ..
                } = &d
                {
                    if let Some(tp) = tables
                        .contains(topic)
                        .then(|| cat.topics.get(*topic))
                        .flatten()
                    {
                        let v = rtcan_host::value::to_json(tp, payload);
                        table = crate::module_table::from_json(&v, &names, *time_ns).or(table);
                    }
                }
            }
        }
        if let Some(l) = live.as_mut() {
            if l.quit_asked() {
                break;
            }
        }
        if !once && last_draw.elapsed() >= every {
            last_draw = Instant::now();
            match live.as_mut() {
                Some(l) => l.draw(&mon.view(&cat), &title)?,
                None => {
                    // Not a terminal: the plain table, homed and cleared.
                    print!("\x1b[H\x1b[2J{}", mon.render(&cat));
                    let _ = std::io::stdout().flush();
                }
            }
        }
    }
    // Leave the alternate screen before the final table.
    drop(live);
    if screen {
        print!(
            "{}",
            crate::monitor_tui::screen_text(&mon.view(&cat), &title, 120)?
        );
    } else {
        print!("{}", mon.render(&cat));
    }
    if let Some(t) = &table {
        print!("{}", crate::module_table::render(t));
    }
    Ok(())
}
