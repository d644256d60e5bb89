//! The simulated Triskar2 as a [`Link`]: `rtcan_sim::live::Live` stepped in 10 ms
//! chunks, paced to the wall clock at `speed` (0: as fast as the machine goes). The host
//! publishes `teleop` as the gateway would forward it from ROS.
use std::time::{Duration, Instant};

use rtcan_core::Nanos;
use rtcan_sim::decode::{plan_catalog, TopicDesc};
use rtcan_sim::live::Live;

use crate::link::{Link, Stamped};
use crate::value::to_json;

/// Simulated time advanced per step, ns.
const STEP_NS: Nanos = 10_000_000;

/// The topics the simulated gateway takes from the host side.
pub const HOST_TOPICS: [&str; 1] = ["teleop"];

/// The live simulated robot.
pub struct SimLink {
    live: Live,
    teleop: Option<TopicDesc>,
    speed: f64,
    started: Instant,
}

impl SimLink {
    /// Powers the robot of `plan` on (standing still until the host publishes `teleop`).
    pub fn start(plan: &rtcan_model::Plan, speed: f64) -> Result<Self, String> {
        Ok(Self::with(plan, Live::start(plan, 1)?, speed))
    }

    fn with(plan: &rtcan_model::Plan, live: Live, speed: f64) -> Self {
        let teleop = plan_catalog(plan)
            .topics
            .into_iter()
            .find(|t| t.name == "teleop");
        SimLink {
            live,
            teleop,
            speed,
            started: Instant::now(),
        }
    }

    /// [`SimLink::start`] with every module's firmware-update port on and the gateway
    /// relaying the host channels (`rtcan_sim::live::Live::start_with_updates`).
    pub fn start_with_updates(plan: &rtcan_model::Plan, speed: f64) -> Result<Self, String> {
        Ok(Self::with(plan, Live::start_with_updates(plan, 1)?, speed))
    }

    /// The host-channel frame `frame` from the host for the bus; `false` if the gateway
    /// refuses it (not an NRT frame of the host channels, or no update ports).
    pub fn relay_to_bus(&mut self, frame: rtcan_core::Frame) -> bool {
        self.live.relay_to_bus(frame)
    }

    /// The host-channel frames the gateway received from the bus since the last call.
    pub fn relay_from_bus(&mut self) -> Vec<rtcan_core::Frame> {
        self.live.relay_from_bus()
    }

    /// What module `m` would boot now: (slot, image length, CRC-32).
    pub fn booted(&self, m: usize) -> Option<(usize, u32, u32)> {
        self.live.booted(m)
    }

    /// Robot pose (x, y m) in the simulated world.
    pub fn pose_m(&self) -> (f64, f64) {
        self.live.pose_m()
    }
}

impl Link for SimLink {
    fn recv(&mut self) -> Result<Option<Vec<Stamped>>, String> {
        let next = self.live.now() + STEP_NS;
        if self.speed > 0.0 {
            let due = Duration::from_secs_f64(next as f64 * 1e-9 / self.speed);
            if let Some(wait) = due.checked_sub(self.started.elapsed()) {
                std::thread::sleep(wait);
            }
        }
        Ok(Some(
            self.live
                .step_to(next)
                .into_iter()
                .map(|w| Stamped {
                    time_ns: w.sof,
                    frame: w.frame,
                })
                .collect(),
        ))
    }

    fn publish(&mut self, topic: &str, payload: &[u8]) -> Result<(), String> {
        let Some(t) = self.teleop.as_ref().filter(|t| t.name == topic) else {
            return Err(format!(
                "the simulated gateway takes only {} from the host, not `{topic}`",
                HOST_TOPICS.join(", ")
            ));
        };
        let v = to_json(t, payload);
        let f = |k: &str| v.get(k).and_then(serde_json::Value::as_f64).unwrap_or(0.0) as f32;
        self.live.set_teleop(f("vx"), f("vy"), f("wz"));
        Ok(())
    }

    fn now_ns(&self) -> Nanos {
        self.live.now()
    }
}
