//! `rtcan bridge`: every topic of the bus on Zenoh under `rtcan/<robot>/<topic>`, and
//! commands from Zenoh for the topics writable from outside; `--ros2`: the mapped topics
//! as rmw_zenoh puts them, a ROS 2 node joining through a Zenoh router (docs/BRIDGE.md).
use rtcan_bridge::ros2::Ros2Bridge;
use rtcan_bridge::{key, open_session, Bridge, Counts, Options};
use rtcan_host::Source;

use crate::link_args::LinkArgs;

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

/// `rtcan bridge`: runs until --seconds or Ctrl-C (then prints what it did); puts every
/// message on Zenoh key rtcan/<robot>/<topic> (JSON objects; --raw: the little-endian
/// payload); samples other Zenoh nodes put on the topics robot.toml marks writable are
/// published on the bus, samples on other topics are refused and counted. <robot> is
/// --robot-name or robot.toml's `[robot] name` (default: its file stem).
///
/// --ros2: the topics robot.toml maps to ROS 2 types (`ros2 = ...`) as rmw_zenoh puts
/// them (node /<robot>/rtcan_bridge, CDR, liveliness tokens), joining ROS 2 through a
/// Zenoh router (--connect, default tcp/127.0.0.1:7447); writable topics are taken from
/// ROS 2.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Zenoh endpoint to listen on, e.g. tcp/127.0.0.1:7447 (repeatable)
    #[arg(long, value_name = "ENDPOINT")]
    listen: Vec<String>,
    /// Zenoh endpoint to connect to (repeatable)
    #[arg(long, value_name = "ENDPOINT")]
    connect: Vec<String>,
    /// The <robot> of the key expressions
    #[arg(long, value_name = "NAME")]
    robot_name: Option<String>,
    /// Payloads as raw little-endian bytes instead of JSON
    #[arg(long)]
    raw: bool,
    /// Speak rmw_zenoh (ROS 2) for the topics robot.toml maps
    #[arg(long)]
    ros2: bool,
    /// ROS_DOMAIN_ID with --ros2 (default: that variable, else 0)
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    domain_id: Option<String>,
    #[command(flatten)]
    la: LinkArgs,
}

/// Runs `rtcan bridge`; returns the exit code.
pub fn run(a: Args) -> i32 {
    let opts = Options {
        listen: a.listen,
        connect: a.connect,
        raw: a.raw,
        ..Options::default()
    };
    let domain = match ros2_domain(a.ros2, opts.raw, a.domain_id) {
        Ok(d) => d,
        Err(e) => return crate::usage_error("bridge", &e),
    };
    match bridge(&a.la, opts, a.robot_name, domain) {
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
    opts.writable = match la.source() {
        Source::Sim(_) | Source::Serial(_) => plan.bridge.writable(),
        // A CAN adapter sends NRT topics only (rtcan_host::can).
        Source::Can(_) => plan
            .bridge
            .writable()
            .into_iter()
            .filter(|w| {
                cat.topics
                    .iter()
                    .any(|t| &t.name == w && t.class == rtcan_core::Class::Nrt)
            })
            .collect(),
        Source::Replay(_) => Vec::new(),
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
