//! `rtcan bridge`: every topic of the bus on Zenoh under `rtcan/<robot>/<topic>`, and
//! commands from Zenoh for the topics writable from outside; `--ros2`: the mapped topics
//! as rmw_zenoh puts them, a ROS 2 node joining through a Zenoh router (docs/BRIDGE.md).
use rtcan_bridge::ros2::Ros2Bridge;
use rtcan_bridge::{key, open_session, Bridge, Counts, Options};
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
         \x20                   [--raw | --ros2 [--domain-id N]] [bus options] [--seconds S]\n\n\
         runs until --seconds or Ctrl-C (then prints what it did);\n\
         puts every message on Zenoh key rtcan/<robot>/<topic> (JSON objects; --raw: the\n\
         little-endian payload); samples other Zenoh nodes put on rtcan/<robot>/teleop are\n\
         published on the bus, samples on other topics are refused and counted.\n\
         <robot> is --robot-name or robot.toml's `[robot] name` (default: its file stem).\n\
         ENDPOINT: e.g. tcp/127.0.0.1:7447\n\n\
         --ros2: the topics robot.toml maps to ROS 2 types (`ros2 = ...`) as rmw_zenoh\n\
         puts them (node /<robot>/rtcan_bridge, CDR, liveliness tokens), joining ROS 2\n\
         through a Zenoh router (--connect, default tcp/127.0.0.1:7447); writable\n\
         topics are taken from ROS 2. --domain-id: ROS_DOMAIN_ID (default: that\n\
         variable, else 0).\n\n{HELP}"
    )
}

/// Runs `rtcan bridge`; returns the exit code.
pub fn run(args: &[String]) -> i32 {
    let mut la = LinkArgs::default();
    let mut opts = Options::default();
    let mut name = None;
    let mut ros2 = false;
    let mut domain: Option<String> = None;
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
            "--ros2" => {
                ros2 = true;
                Ok(())
            }
            "--domain-id" => val(a).map(|v| domain = Some(v)),
            s => Err(format!("unexpected `{s}`")),
        };
        if let Err(e) = r {
            return crate::usage_error(&e, &usage());
        }
    }
    let domain = match ros2_domain(ros2, opts.raw, domain) {
        Ok(d) => d,
        Err(e) => return crate::usage_error(&e, &usage()),
    };
    match bridge(&la, opts, name, domain) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}

/// `--ros2` and `--domain-id` checked: `Some(domain)` in ROS 2 mode.
fn ros2_domain(ros2: bool, raw: bool, domain: Option<String>) -> Result<Option<u32>, String> {
    if !ros2 {
        return match domain {
            Some(_) => Err("--domain-id needs --ros2".into()),
            None => Ok(None),
        };
    }
    if raw {
        return Err("--raw and --ros2 exclude each other (--ros2 puts CDR)".into());
    }
    let text = domain.or_else(|| std::env::var("ROS_DOMAIN_ID").ok());
    match text {
        None => Ok(Some(0)),
        // rmw's limit for ROS_DOMAIN_ID.
        Some(t) => match t.trim().parse::<u32>() {
            Ok(d) if d <= 232 => Ok(Some(d)),
            _ => Err(format!("domain id `{t}`: expected 0..=232")),
        },
    }
}

/// One of the two bridges, stepped the same way.
enum Any<'c> {
    Zenoh(Box<Bridge<'c>>),
    Ros2(Box<Ros2Bridge<'c>>),
}

impl Any<'_> {
    fn step(&mut self, link: &mut dyn rtcan_host::Link) -> Result<bool, String> {
        match self {
            Any::Zenoh(b) => b.step(link),
            Any::Ros2(b) => b.step(link),
        }
    }
    fn report(&self) -> (Counts, Option<&String>) {
        match self {
            Any::Zenoh(b) => (b.counts, b.last_error.as_ref()),
            Any::Ros2(b) => (b.counts, b.last_error.as_ref()),
        }
    }
}

fn bridge(
    la: &LinkArgs,
    mut opts: Options,
    name: Option<String>,
    ros2: Option<u32>,
) -> Result<(), String> {
    let (plan, cat) = la.robot()?;
    opts.robot = name.unwrap_or_else(|| plan.bridge.robot.clone());
    if ros2.is_some() && !rtcan_model::bridge_keys::valid_robot_name(&opts.robot) {
        return Err(format!(
            "robot name `{}` cannot be a ROS 2 namespace (an ASCII letter, then letters, digits and single `_`)",
            opts.robot
        ));
    }
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
    // WAN of CANs: topics robot.toml takes from other robots' bridges.
    if !opts.writable.is_empty() && ros2.is_none() {
        opts.imports = plan.bridge.imports();
    }
    let mut link = la.open(&plan)?;
    let writable = if opts.writable.is_empty() {
        "none".to_string()
    } else {
        opts.writable.join(", ")
    };
    let mut b = match ros2 {
        None => {
            let b = Bridge::new(&cat, opts.clone())?;
            println!(
                "bridge ready: {} topics on {} (listen {:?}, connect {:?}); writable: {writable}",
                cat.topics.len(),
                key(&opts.robot, "*"),
                opts.listen,
                opts.connect,
            );
            for (local, robot, topic) in &opts.imports {
                println!("  {local} <- {}", key(robot, topic));
            }
            Any::Zenoh(Box::new(b))
        }
        Some(domain) => {
            // rmw_zenoh's session default: a peer that connects to the local router.
            if opts.connect.is_empty() {
                opts.connect.push("tcp/127.0.0.1:7447".into());
            }
            let session = open_session(&opts.listen, &opts.connect)?;
            let b = Ros2Bridge::new(session, &plan, &cat, &opts.robot, domain, &opts.writable)?;
            let n = b.node();
            println!(
                "ros2 bridge ready: node {}/{} in domain {domain} (connect {:?}); writable: {writable}",
                n.namespace, n.name, opts.connect
            );
            for t in b.tokens() {
                println!("  {t}");
            }
            Any::Ros2(Box::new(b))
        }
    };
    stop_on_signals();
    let end = la.end_ns(link.now_ns());
    while link.now_ns() < end && !STOP.load(std::sync::atomic::Ordering::Relaxed) {
        if !b.step(link.as_mut())? {
            break;
        }
    }
    let (c, last) = b.report();
    println!(
        "bridged {} messages; commands: {} accepted, {} refused (not writable), {} bad",
        c.published, c.accepted, c.refused, c.bad
    );
    if !opts.imports.is_empty() {
        println!("imported {} messages from other robots", c.imported);
    }
    if let Some(e) = last {
        println!("last refusal: {e}");
    }
    Ok(())
}
