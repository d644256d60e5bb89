//! `rtcan flash [robot.toml] [--module M | --all] [--image FILE] [--json]
//! [--serial PORT]`: firmware update over the bus (docs/SERVICES.md §4) against the
//! simulated robot (`--sim robot.toml`, the default): host → gateway link → bus → module,
//! with the robot's HRT and SRT traffic running. Prints per module the bytes, request
//! frames, simulated bus time, retries and the result, then what the robot's traffic saw.
//! With `--serial PORT` this process is the host: its sender's frames go through the
//! gateway's serial link (`triskar2_link::BUS_FRAME`) onto the robot's bus, the modules'
//! replies come back the same way; times are wall-clock.
use std::path::PathBuf;

use rtcan_boot::sender::{Config, Outcome, Sender};
use rtcan_sim::run::SimConfig;
use rtcan_sim::triskar::{self, TriskarConfig, MODULES};
use rtcan_sim::update::{crc, test_image, Target, UpdateJob};

use crate::out;

/// When the host starts sending (the robot has synchronised by then).
const START_NS: u64 = 500_000_000;

/// `rtcan flash`: firmware update over the bus, simulated robot.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("which").required(true).args(["module", "all"])))]
pub struct Args {
    /// The robot (same as --sim)
    #[arg(value_name = "robot.toml")]
    robot: Option<PathBuf>,
    /// The simulated robot (the default bus)
    #[arg(long, value_name = "robot.toml", conflicts_with = "robot")]
    sim: Option<PathBuf>,
    /// The module to update (repeatable)
    #[arg(long, value_name = "M")]
    module: Vec<String>,
    /// Every module on the bus (not the gateway: it is updated over its host link)
    #[arg(long)]
    all: bool,
    /// The image to send (raw flash bytes, the robot fingerprint at offset 0x1D0);
    /// default: a deterministic 28 KiB test image
    #[arg(long, value_name = "FILE")]
    image: Option<PathBuf>,
    /// Simulated time per module before giving up (the budget)
    #[arg(long, value_name = "S", default_value_t = 10.0, value_parser = crate::link_args::positive)]
    seconds: f64,
    /// One JSON object per module: module, bytes, bus_time_ms, frames, retries, ok
    #[arg(long)]
    json: bool,
    /// The gateway's serial link (a tty, or a pty to a simulated gateway): the host
    /// sends the update through the gateway; --seconds is then wall time per module
    #[arg(long, value_name = "PORT", conflicts_with = "sim")]
    serial: Option<String>,
    /// The other buses of the host tools: refused with a reason (not supported yet)
    #[arg(long, hide = true, value_name = "BUS")]
    can: Option<String>,
    #[arg(long, hide = true, value_name = "BUS")]
    replay: Option<String>,
}

fn json_row(name: &str, r: &rtcan_sim::update::UpdateResult) -> String {
    serde_json::json!({
        "module": name,
        "bytes": r.bytes,
        "bus_time_ms": (r.bus_time_ns as f64 / 1e4).round() / 100.0,
        "frames": r.frames,
        "retries": r.retries,
        "ok": matches!(r.outcome, Some(Outcome::Done { .. })),
    })
    .to_string()
}

fn result_text(o: Option<Outcome>) -> String {
    match o {
        Some(Outcome::Done { slot, seq }) => format!("ok (committed to slot {slot}, seq {seq})"),
        Some(Outcome::Failed(why)) => format!("FAILED: refused by the module ({why:?})"),
        Some(Outcome::Timeout) => "FAILED: no answer (timeout)".into(),
        None => "FAILED: not finished in the simulated time (--seconds)".into(),
    }
}

/// Exit code: 0 all committed, 1 a module refused or did not finish, 2 bad input.
pub fn run(a: Args) -> i32 {
    for (flag, given) in [("--can", &a.can), ("--replay", &a.replay)] {
        if given.is_some() {
            return crate::usage_error(
                "flash",
                &format!(
                    "{flag}: `rtcan flash` runs against the simulator (--sim) or through the \
                     gateway's serial link (--serial PORT) only so far"
                ),
            );
        }
    }
    let robot = a
        .sim
        .clone()
        .or_else(|| a.robot.clone())
        .unwrap_or_else(|| PathBuf::from("robot.toml"));
    let plan = match rtcan_model::Robot::load(&robot) {
        Ok(p) => p,
        Err(d) => {
            out::eprint(&d.render());
            return 2;
        }
    };
    if let Some(port) = &a.serial {
        return over_serial(&a, &robot, &plan, port);
    }
    if let Err(e) = triskar::check_plan(&plan) {
        eprintln!("error: {e}");
        return 2;
    }
    let targets: Vec<usize> = if a.all {
        (1..MODULES.len()).collect()
    } else {
        let mut t = Vec::new();
        for m in &a.module {
            match MODULES.iter().position(|x| x == m) {
                Some(0) => {
                    eprintln!("error: the gateway is updated over its host link, not the bus");
                    return 2;
                }
                Some(i) => t.push(i),
                None => {
                    eprintln!("error: no module `{m}` (modules: {})", MODULES.join(", "));
                    return 2;
                }
            }
        }
        t
    };
    let fp = plan.fingerprint;
    let (image, what) = match &a.image {
        Some(p) => match std::fs::read(p) {
            Ok(b) => {
                let n = b.len();
                (b, format!("{} ({n} bytes)", p.display()))
            }
            Err(e) => {
                eprintln!("error: {}: {e}", p.display());
                return 2;
            }
        },
        // The module images of examples/triskar2 are linked for the whole flash, not
        // for a slot with the fingerprint at 0x1D0: they cannot be sent as they are.
        None => (
            test_image(28 * 1024, fp, 0x5A),
            "deterministic 28 KiB test image (no --image; the built module ELFs are not \
             linked for the update slots)"
                .into(),
        ),
    };
    let job = UpdateJob {
        targets: targets
            .iter()
            .map(|&m| Target {
                module: m,
                image: image.clone(),
                fingerprint: fp,
            })
            .collect(),
        start_ns: START_NS,
        config: Config::default(),
        flash: Vec::new(),
        cut: None,
    };
    let cfg = TriskarConfig {
        sim: SimConfig {
            seconds: START_NS as f64 / 1e9 + a.seconds * targets.len() as f64,
            ..SimConfig::default()
        },
        update: Some(job),
        ..TriskarConfig::default()
    };
    let r = match triskar::run(&plan, &cfg) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let ok = r
        .update
        .iter()
        .all(|u| matches!(u.outcome, Some(Outcome::Done { .. })));
    let hrt_misses: u64 = r.run.figures.hrt.iter().map(|h| h.misses).sum();
    let srt_misses: u64 = r.run.figures.srt.iter().map(|s| s.misses).sum();
    if a.json {
        for u in &r.update {
            if !out::println(&json_row(MODULES.get(u.module).unwrap_or(&"?"), u)) {
                break;
            }
        }
    } else {
        let mut text = format!(
            "{} (fingerprint {fp:#010x}), simulated, {} bit/s; image: {what}, CRC-32 {:#010x}\n",
            robot.display(),
            plan.bus.bitrate,
            crc(&image)
        );
        for u in &r.update {
            text.push_str(&format!(
                "{:<10} {} bytes, {} frames, {:.3} s bus time, {} retries: {}\n",
                MODULES.get(u.module).unwrap_or(&"?"),
                u.bytes,
                u.frames,
                u.bus_time_ns as f64 / 1e9,
                u.retries,
                result_text(u.outcome)
            ));
        }
        text.push_str(&format!(
            "robot traffic meanwhile ({:.1} s): {hrt_misses} HRT misses, {srt_misses} SRT misses\n",
            cfg.sim.seconds
        ));
        out::print(&text);
    }
    if ok {
        0
    } else {
        1
    }
}

/// The gateway of `plan`: the module publishing the topics the host sends over its link
/// (`link = "in"`), if any.
fn gateway(plan: &rtcan_model::Plan) -> Option<usize> {
    let first_in = plan
        .bridge
        .link
        .iter()
        .find(|l| l.dir == rtcan_model::bridge_keys::LinkDir::In)?;
    plan.topics
        .iter()
        .find(|t| t.name == first_in.name)
        .map(|t| t.module)
}

/// The image to send: `--image`, or the deterministic 28 KiB test image; with its
/// description.
fn image_of(a: &Args, fp: u32) -> Result<(Vec<u8>, String), String> {
    match &a.image {
        Some(p) => std::fs::read(p)
            .map(|b| {
                let n = b.len();
                (b, format!("{} ({n} bytes)", p.display()))
            })
            .map_err(|e| format!("{}: {e}", p.display())),
        None => Ok((
            test_image(28 * 1024, fp, 0x5A),
            "deterministic 28 KiB test image (no --image)".into(),
        )),
    }
}

/// `--serial PORT`: this process runs the sender; each request frame goes through the
/// gateway's link onto the bus, each reply comes back through it.
fn over_serial(a: &Args, robot: &std::path::Path, plan: &rtcan_model::Plan, port: &str) -> i32 {
    let names: Vec<&str> = plan.modules.iter().map(|m| m.name.as_str()).collect();
    let gw = gateway(plan);
    let targets: Vec<usize> = if a.all {
        (0..names.len()).filter(|&m| Some(m) != gw).collect()
    } else {
        let mut t = Vec::new();
        for m in &a.module {
            match names.iter().position(|x| x == m) {
                Some(i) if Some(i) == gw => {
                    eprintln!("error: `{m}` is the gateway: it is updated over its host link, not the bus");
                    return 2;
                }
                Some(i) => t.push(i),
                None => {
                    eprintln!("error: no module `{m}` (modules: {})", names.join(", "));
                    return 2;
                }
            }
        }
        t
    };
    let fp = plan.fingerprint;
    let (image, what) = match image_of(a, fp) {
        Ok(x) => x,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let cat = rtcan_sim::decode::plan_catalog(plan);
    let mut link = match rtcan_host::serial::SerialLink::open(port, &cat, &plan.bridge.link) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let mut results = Vec::new();
    for &m in &targets {
        match send_one(&mut link, m, &image, fp, a.seconds) {
            Ok(r) => results.push(r),
            Err(e) => {
                eprintln!("error: {e}");
                return 1;
            }
        }
    }
    let ok = results
        .iter()
        .all(|u| matches!(u.outcome, Some(Outcome::Done { .. })));
    let name = |m: usize| names.get(m).copied().unwrap_or("?");
    if a.json {
        for u in &results {
            if !out::println(&json_row(name(u.module), u)) {
                break;
            }
        }
    } else {
        let mut text = format!(
            "{} (fingerprint {fp:#010x}), through the gateway link {port}; image: {what}, CRC-32 {:#010x}\n",
            robot.display(),
            crc(&image)
        );
        for u in &results {
            text.push_str(&format!(
                "{:<10} {} bytes, {} frames, {:.3} s, {} retries: {}\n",
                name(u.module),
                u.bytes,
                u.frames,
                u.bus_time_ns as f64 / 1e9,
                u.retries,
                result_text(u.outcome)
            ));
        }
        out::print(&text);
    }
    if ok {
        0
    } else {
        1
    }
}

/// One module's update through `link`, at most `seconds` of wall time.
fn send_one<P: std::io::Read + std::io::Write>(
    link: &mut rtcan_host::serial::SerialLink<P>,
    module: usize,
    image: &[u8],
    fp: u32,
    seconds: f64,
) -> Result<rtcan_sim::update::UpdateResult, String> {
    use rtcan_host::Link;
    let m = u8::try_from(module).map_err(|_| format!("module {module}: no update channel"))?;
    let mut s = Sender::new(m, image, fp, Config::default());
    let t0 = std::time::Instant::now();
    let now = || t0.elapsed().as_nanos() as u64;
    let limit = (seconds * 1e9) as u64;
    while s.outcome().is_none() && now() < limit {
        // Everything the sender has to say now (its window bounds it), then the replies.
        let mut wrote = false;
        while let Some(f) = s.next_frame(now()) {
            link.send_frame(&f)?;
            s.sent(now());
            wrote = true;
        }
        if wrote {
            link.flush()?;
        }
        for st in link.recv()?.unwrap_or_default() {
            if rtcan_core::service::is_service(st.frame.id().msg_id()) {
                s.on_frame(&st.frame, now());
            }
        }
    }
    Ok(rtcan_sim::update::UpdateResult {
        module,
        bytes: image.len(),
        frames: s.stats.frames,
        retries: s.stats.retries,
        bus_time_ns: now(),
        outcome: s.outcome(),
    })
}
