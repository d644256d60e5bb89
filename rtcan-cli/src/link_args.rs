//! The bus options every host command takes (`echo`, `pub`, `record`, `monitor`): which
//! bus (`--sim ROBOT.toml`, the default `robot.toml`; `--replay LOG`; `--serial PORT`;
//! `--can IFACE`), the robot for the non-simulated ones (`--robot`), pacing (`--speed`)
//! and the limits that make a run end (`--seconds`, `--count`).
use std::path::PathBuf;

use rtcan_host::{Link, Source};
use rtcan_sim::decode::{plan_catalog, Catalog};

pub const HELP: &str = "\
bus (one of; default --sim robot.toml):
  --sim ROBOT.toml   the simulated robot, in-process, paced to the wall clock
  --replay LOG       a candump log (`-`: standard input)
  --serial PORT      the gateway's serial link
  --can IFACE        a SocketCAN interface
  --robot ROBOT.toml the robot of --replay/--serial/--can (default robot.toml)
  --speed X          pace simulated/replayed time at X times the wall clock
                     (default 1; 0 = as fast as possible)
limits:
  --seconds S        stop after S seconds of bus time
  --count N          stop after N messages";

/// Parsed bus options.
pub struct LinkArgs {
    pub source: Source,
    pub robot: Option<PathBuf>,
    pub speed: f64,
    pub seconds: Option<f64>,
    pub count: Option<u64>,
}

impl Default for LinkArgs {
    fn default() -> Self {
        LinkArgs {
            source: Source::Sim(PathBuf::from("robot.toml")),
            robot: None,
            speed: 1.0,
            seconds: None,
            count: None,
        }
    }
}

fn num<T: std::str::FromStr>(flag: &str, v: Option<&String>) -> Result<T, String> {
    let v = v.ok_or_else(|| format!("{flag} needs a value"))?;
    v.parse()
        .map_err(|_| format!("{flag}: `{v}` is not a valid number"))
}

impl LinkArgs {
    /// Takes `a` (and its value from `it`) if it is a bus option: `Ok(true)`.
    pub fn take<'a>(
        &mut self,
        a: &str,
        it: &mut impl Iterator<Item = &'a String>,
    ) -> Result<bool, String> {
        let mut val = |flag: &str| {
            it.next()
                .cloned()
                .ok_or_else(|| format!("{flag} needs a value"))
        };
        match a {
            "--sim" => self.source = Source::Sim(val(a)?.into()),
            "--replay" => self.source = Source::Replay(val(a)?.into()),
            "--serial" => self.source = Source::Serial(val(a)?),
            "--can" => self.source = Source::Can(val(a)?),
            "--robot" => self.robot = Some(val(a)?.into()),
            "--speed" => {
                let s: f64 = num(a, it.next())?;
                if !(s >= 0.0 && s.is_finite()) {
                    return Err(format!("--speed {s}: give a finite number >= 0"));
                }
                self.speed = s;
            }
            "--seconds" => {
                let s: f64 = num(a, it.next())?;
                if !(s >= 0.0 && s.is_finite()) {
                    return Err(format!("--seconds {s}: give a finite number >= 0"));
                }
                self.seconds = Some(s);
            }
            "--count" => self.count = Some(num(a, it.next())?),
            _ => return Ok(false),
        }
        Ok(true)
    }

    /// The robot's plan and catalog.
    pub fn robot(&self) -> Result<(rtcan_model::Plan, Catalog), String> {
        let path = match (&self.source, &self.robot) {
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
        rtcan_host::open(&self.source, plan, self.speed)
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
