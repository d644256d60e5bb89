//! The bus options every host command takes (`echo`, `pub`, `record`, `monitor`): which
//! bus (`--sim ROBOT.toml`, the default `robot.toml`; `--replay LOG`; `--serial PORT`;
//! `--can IFACE`), the robot for the non-simulated ones (`--robot`), pacing (`--speed`)
//! and the limits that make a run end (`--seconds`, `--count`).
use std::path::PathBuf;

use rtcan_host::{Link, Source};
use rtcan_sim::decode::{plan_catalog, Catalog};

/// Parsed bus options, shared by `echo`, `pub`, `record`, `monitor` and `bridge`.
#[derive(clap::Args, Debug)]
#[command(next_help_heading = "Bus (one of; default --sim robot.toml)")]
pub struct LinkArgs {
    /// The simulated robot, in-process, paced to the wall clock
    #[arg(long, value_name = "ROBOT.toml", group = "bus")]
    sim: Option<PathBuf>,
    /// A candump log (`-`: standard input)
    #[arg(long, value_name = "LOG", group = "bus")]
    replay: Option<PathBuf>,
    /// The gateway's serial link
    #[arg(long, value_name = "PORT", group = "bus")]
    serial: Option<String>,
    /// A SocketCAN interface (listen-only monitor, NRT sender)
    #[arg(long, value_name = "IFACE", group = "bus")]
    can: Option<String>,
    /// The robot of --replay/--serial/--can (default robot.toml)
    #[arg(long, value_name = "ROBOT.toml")]
    pub robot: Option<PathBuf>,
    /// Pace simulated/replayed time at X times the wall clock (0 = as fast as possible)
    #[arg(long, value_name = "X", default_value_t = 1.0, value_parser = non_negative)]
    pub speed: f64,
    /// Stop after S seconds of bus time
    #[arg(long, value_name = "S", value_parser = non_negative)]
    pub seconds: Option<f64>,
    /// Stop after N messages
    #[arg(long, value_name = "N")]
    pub count: Option<u64>,
}

/// A finite number >= 0 (clap value parser).
pub fn non_negative(v: &str) -> Result<f64, String> {
    match v.parse::<f64>() {
        Ok(s) if s >= 0.0 && s.is_finite() => Ok(s),
        _ => Err(format!("`{v}`: give a finite number >= 0")),
    }
}

/// A finite number > 0 (clap value parser).
pub fn positive(v: &str) -> Result<f64, String> {
    match v.parse::<f64>() {
        Ok(s) if s > 0.0 && s.is_finite() => Ok(s),
        _ => Err(format!("`{v}`: give a finite number > 0")),
    }
}

impl LinkArgs {
    /// Which bus the options name.
    pub fn source(&self) -> Source {
        if let Some(p) = &self.replay {
            Source::Replay(p.clone())
        } else if let Some(p) = &self.serial {
            Source::Serial(p.clone())
        } else if let Some(i) = &self.can {
            Source::Can(i.clone())
        } else {
            Source::Sim(
                self.sim
                    .clone()
                    .unwrap_or_else(|| PathBuf::from("robot.toml")),
            )
        }
    }

    /// The robot's plan and catalog.
    pub fn robot(&self) -> Result<(rtcan_model::Plan, Catalog), String> {
        let path = match (&self.source(), &self.robot) {
            (Source::Sim(p), None) => p.clone(),
            (Source::Sim(_), Some(_)) => {
                return Err("--robot is for --replay/--serial/--can; --sim names its robot".into())
            }
            (_, r) => r.clone().unwrap_or_else(|| PathBuf::from("robot.toml")),
        };
        let plan = rtcan_model::Robot::load(&path).map_err(|d| d.render())?;
        let cat = plan_catalog(&plan);
        Ok((plan, cat))
    }

    /// Opens the bus.
    pub fn open(&self, plan: &rtcan_model::Plan) -> Result<Box<dyn Link>, String> {
        rtcan_host::open(&self.source(), plan, self.speed)
    }

    /// Bus time (ns) at which the run ends, from the link's start.
    pub fn end_ns(&self, start: u64) -> u64 {
        self.seconds
            .map_or(u64::MAX, |s| start.saturating_add((s * 1e9) as u64))
    }
}

/// The frame as a decoder entry.
pub fn entry(s: &rtcan_host::Stamped) -> rtcan_sim::candump::Entry {
    rtcan_sim::candump::Entry {
        time_ns: s.time_ns,
        iface: "can0".into(),
        frame: s.frame,
        standard: false,
    }
}
