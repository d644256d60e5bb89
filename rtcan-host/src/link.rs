//! How a host reaches a bus: the [`Link`] trait and the command line's choice of backend.
use std::path::PathBuf;

use rtcan_core::{Frame, Nanos};

/// A frame seen on the bus, stamped with bus time (ns since the link started, or the
/// log's own time for a replay).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stamped {
    /// When its start of frame was seen, ns.
    pub time_ns: Nanos,
    /// The frame.
    pub frame: Frame,
}

/// A bus as a host sees it. `recv` blocks at most about one pacing step.
pub trait Link {
    /// Frames seen since the last call, in order; `None` once the bus has ended (end of
    /// a replayed log).
    fn recv(&mut self) -> Result<Option<Vec<Stamped>>, String>;
    /// Publishes `payload` (the topic's little-endian bytes) on topic `topic` from the
    /// host side; an error when this link cannot send that topic.
    fn publish(&mut self, topic: &str, payload: &[u8]) -> Result<(), String>;
    /// Bus time reached, ns.
    fn now_ns(&self) -> Nanos;
}

/// Which bus the command line named (`--sim`, `--replay`, `--serial`, `--can`).
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// The simulated robot of this robot.toml.
    Sim(PathBuf),
    /// A candump log.
    Replay(PathBuf),
    /// The gateway's serial link.
    Serial(String),
    /// A SocketCAN interface.
    Can(String),
}

/// Opens `source` for the robot of `plan`. `speed` paces simulated and replayed time
/// against the wall clock (1.0 = real time; 0 = as fast as possible).
pub fn open(
    source: &Source,
    plan: &rtcan_model::Plan,
    speed: f64,
) -> Result<Box<dyn Link>, String> {
    match source {
        Source::Sim(_) => Ok(Box::new(crate::sim::SimLink::start(plan, speed)?)),
        Source::Replay(p) => Ok(Box::new(crate::replay::ReplayLink::open(p, speed)?)),
        Source::Serial(port) => Ok(Box::new(crate::serial::SerialLink::open(
            port,
            &rtcan_sim::decode::plan_catalog(plan),
            &plan.bridge.link,
        )?)),
        Source::Can(iface) => open_can(iface, plan),
    }
}

/// A SocketCAN interface as a [`crate::can::CanLink`].
#[cfg(all(target_os = "linux", feature = "socketcan"))]
fn open_can(iface: &str, plan: &rtcan_model::Plan) -> Result<Box<dyn Link>, String> {
    let port = crate::can::socket::SocketPort::open(iface, plan.bus.bitrate)?;
    Ok(Box::new(crate::can::CanLink::new(
        port,
        rtcan_sim::decode::plan_catalog(plan),
    )))
}

/// Without the `socketcan` feature (or off Linux) there is no socket to open.
#[cfg(not(all(target_os = "linux", feature = "socketcan")))]
fn open_can(iface: &str, _plan: &rtcan_model::Plan) -> Result<Box<dyn Link>, String> {
    Err(format!(
        "--can {iface}: SocketCAN is not built into this rtcan \
         (build it with `--features socketcan` on Linux; or reach the robot with \
         --sim ROBOT.toml or --replay LOG, recording a log on the robot with \
         `candump -l {iface}`)"
    ))
}
