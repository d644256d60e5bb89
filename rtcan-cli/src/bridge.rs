//! `rtcan bridge`: every topic of the bus on Zenoh under `rtcan/<robot>/<topic>`, and
//! commands from Zenoh for the topics writable from outside (docs/BRIDGE.md).
use rtcan_bridge::{key, Bridge, Options};
use rtcan_host::Source;

use crate::link_args::{LinkArgs, HELP};

/// Set by SIGINT/SIGTERM: the bridge stops at the next step and prints its report.
static STOP: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

extern "C" fn on_signal(_: libc::c_int) {
    STOP.store(true, std::sync::atomic::Ordering::Relaxed);
}

fn stop_on_signals() {
    let h = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
    // SAFETY: the handler only stores to an atomic (async-signal-safe).
    unsafe {
        libc::signal(libc::SIGINT, h);
        libc::signal(libc::SIGTERM, h);
    }
}

fn usage() -> String {
    format!(
        "usage: rtcan bridge [--listen ENDPOINT]... [--connect ENDPOINT]... [--robot-name NAME]\n\
         \x20                   [--raw] [bus options] [--seconds S]\n\n\
         runs until --seconds or Ctrl-C (then prints what it did);\n\
         puts every message on Zenoh key rtcan/<robot>/<topic> (JSON objects; --raw: the\n\
         little-endian payload); samples other Zenoh nodes put on rtcan/<robot>/teleop are\n\
         published on the bus, samples on other topics are refused and counted.\n\
         <robot> is --robot-name or robot.toml's `[robot] name` (default: its file stem).\n\
         ENDPOINT: e.g. tcp/127.0.0.1:7447\n\n{HELP}"
    )
}

/// Runs `rtcan bridge`; returns the exit code.
pub fn run(args: &[String]) -> i32 {
    let mut la = LinkArgs::default();
    let mut opts = Options::default();
    let mut name = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match la.take(a, &mut it) {
            Err(e) => return crate::usage_error(&e, &usage()),
            Ok(true) => continue,
            Ok(false) => {}
        }
        let mut val = |flag: &str| it.next().cloned().ok_or(format!("{flag} needs a value"));
        let r = match a.as_str() {
            "-h" | "--help" => {
                println!("{}", usage());
                return 0;
            }
            "--listen" => val(a).map(|v| opts.listen.push(v)),
            "--connect" => val(a).map(|v| opts.connect.push(v)),
            "--robot-name" => val(a).map(|v| name = Some(v)),
            "--raw" => {
                opts.raw = true;
                Ok(())
            }
            s => Err(format!("unexpected `{s}`")),
        };
        if let Err(e) = r {
            return crate::usage_error(&e, &usage());
        }
    }
    match bridge(&la, opts, name) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}

fn bridge(la: &LinkArgs, mut opts: Options, name: Option<String>) -> Result<(), String> {
    let (plan, cat) = la.robot()?;
    opts.robot = name.unwrap_or_else(|| plan.bridge.robot.clone());
    if opts.robot.is_empty() || opts.robot.contains(['/', '*', '$', '?', '#']) {
        return Err(format!(
            "robot name `{}` cannot be a Zenoh key chunk (give --robot-name)",
            opts.robot
        ));
    }
    // What robot.toml marks writable, on a link that can send (a replay cannot).
    opts.writable = match la.source {
        Source::Sim(_) | Source::Serial(_) => plan.bridge.writable(),
        _ => Vec::new(),
    };
    let mut link = la.open(&plan)?;
    let mut b = Bridge::new(&cat, opts.clone())?;
    println!(
        "bridge ready: {} topics on {} (listen {:?}, connect {:?}); writable: {}",
        cat.topics.len(),
        key(&opts.robot, "*"),
        opts.listen,
        opts.connect,
        if opts.writable.is_empty() {
            "none".to_string()
        } else {
            opts.writable.join(", ")
        }
    );
    stop_on_signals();
    let end = la.end_ns(link.now_ns());
    while link.now_ns() < end && !STOP.load(std::sync::atomic::Ordering::Relaxed) {
        if !b.step(link.as_mut())? {
            break;
        }
    }
    let c = b.counts;
    println!(
        "bridged {} messages; commands: {} accepted, {} refused (not writable), {} bad",
        c.published, c.accepted, c.refused, c.bad
    );
    if let Some(e) = &b.last_error {
        println!("last refusal: {e}");
    }
    Ok(())
}
