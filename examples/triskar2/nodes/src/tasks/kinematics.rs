//! `kinematics`: inverse kinematics at 100 Hz (`velocity` → `wheel_setpoints` for all
//! three motors). No hardware: robot.toml may put it on any module.
use rtcan::pubsub::SlotEvery;
use rtcan::robot_toml as msg;
use rtcan::robot_toml::nodes::kinematics as n;

use crate::app::{run_node, twist_from_msg, AppStats, MS};
use crate::kinematics::{InverseKinematicsNode, KinematicsConfig};
use crate::Nanos;

pub use super::NoHw as Hw;

/// The node's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Task {
    ik: InverseKinematicsNode,
    every: SlotEvery,
    pub stats: AppStats,
}

/// At power-on: `lead` before each `wheel_setpoints` slot once synchronised, every
/// 10 ms before.
pub const fn new() -> Task {
    Task {
        ik: InverseKinematicsNode::new(KinematicsConfig::TRISKAR2),
        every: SlotEvery::new(n::WHEEL_SETPOINTS_SLOTS, 10 * MS),
        stats: AppStats {
            published: 0,
            publish_errors: 0,
        },
    }
}

impl Task {
    /// One step: latest velocity in, wheel setpoints out (zero while the node is stopped
    /// or the command is stale).
    pub fn step(&mut self, now: Nanos) {
        let running = run_node(&n::NODE, &n::module::STATUS);
        let sub = n::velocity_sub();
        while let Some(m) = sub.try_recv() {
            if running {
                self.ik.on_velocity(now, twist_from_msg(&m));
            }
        }
        let w = if running { self.ik.step(now) } else { [0.0; 3] };
        self.stats
            .count(n::wheel_setpoints_pub().send(msg::WheelSpeeds { w }, now));
    }
}

/// A step when due; returns when the next one is.
pub fn poll(t: &mut Task, now: Nanos, _hw: &mut impl Hw) -> Nanos {
    if t.every.due(now, n::module::STATUS.grid()) {
        t.step(now);
    }
    t.every.next()
}
