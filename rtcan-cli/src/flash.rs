//! `rtcan flash [robot.toml] [--module M | --all] [--image FILE] [--json]`: firmware
//! update over the bus (docs/SERVICES.md §4) against the simulated robot (`--sim
//! robot.toml`, the default): host → gateway link → bus → module, with the robot's HRT
//! and SRT traffic running. Prints per module the bytes, request frames, simulated bus
//! time, retries and the result, then what the robot's traffic saw.
use std::path::PathBuf;

use rtcan_boot::sender::{Config, Outcome};
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
    /// The other buses of the host tools: refused with a reason (simulator only so far)
    #[arg(long, hide = true, value_name = "BUS")]
    serial: Option<String>,
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
    for (flag, given) in [
        ("--serial", &a.serial),
        ("--can", &a.can),
        ("--replay", &a.replay),
    ] {
        if given.is_some() {
            return crate::usage_error(
                "flash",
                &format!("{flag}: `rtcan flash` runs against the simulator only so far (--sim)"),
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
