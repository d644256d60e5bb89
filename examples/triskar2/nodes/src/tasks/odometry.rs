//! `odometry`: forward kinematics at 50 Hz from the three wheel speeds (`encoder1..3`)
//! → `odometry` for the gateway. No hardware: robot.toml may put it on any module.
use rtcan::pubsub::SlotEvery;
use rtcan::robot_toml as msg;
use rtcan::robot_toml::nodes::odometry as n;

use crate::app::{run_node, AppStats, MS};
use crate::kinematics::TRISKAR2;
use crate::odometry::{OdometryNode, Pose};
use crate::Nanos;

pub use super::NoHw as Hw;

/// The node's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Task {
    odometry: OdometryNode,
    every: SlotEvery,
    wheels: [f32; 3],
    pub stats: AppStats,
}

/// At power-on: `lead` before each `odometry` slot once synchronised, every 20 ms
/// before.
pub const fn new() -> Task {
    Task {
        odometry: OdometryNode::new(TRISKAR2, 20 * MS),
        every: SlotEvery::new(n::ODOMETRY_SLOTS, 20 * MS),
        wheels: [0.0; 3],
        stats: AppStats {
            published: 0,
            publish_errors: 0,
        },
    }
}

impl Task {
    /// The current pose estimate.
    pub const fn pose(&self) -> Pose {
        self.odometry.pose()
    }

    /// One step: latest wheel speeds of the three encoders, pose integrated, `odometry`
    /// published.
    pub fn step(&mut self, now: Nanos) {
        let running = run_node(&n::NODE, &n::module::STATUS);
        let (s1, s2, s3) = (n::encoder1_sub(), n::encoder2_sub(), n::encoder3_sub());
        for (w, speed) in self.wheels.iter_mut().zip([
            latest(core::iter::from_fn(|| s1.try_recv().map(|m| m.speed))),
            latest(core::iter::from_fn(|| s2.try_recv().map(|m| m.speed))),
            latest(core::iter::from_fn(|| s3.try_recv().map(|m| m.speed))),
        ]) {
            if let Some(s) = speed {
                *w = s;
            }
        }
        if !running {
            return;
        }
        let out = self.odometry.step(now, self.wheels);
        self.stats.count(n::odometry_pub().send(
            msg::Odometry {
                x: out.pose.x,
                y: out.pose.y,
                theta: out.pose.theta,
                vx: out.twist.vx,
                vy: out.twist.vy,
                wz: out.twist.wz,
            },
            now,
        ));
    }
}

fn latest(it: impl Iterator<Item = f32>) -> Option<f32> {
    it.last()
}

/// A step when due; returns when the next one is.
pub fn poll(t: &mut Task, now: Nanos, _hw: &mut impl Hw) -> Nanos {
    if t.every.due(now, n::module::STATUS.grid()) {
        t.step(now);
    }
    t.every.next()
}
