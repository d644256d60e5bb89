//! `obstacle_avoid`: on every teleop command and proximity sample, the command limited
//! by the ranges → `velocity`. No hardware: robot.toml may put it on any module.
use rtcan::robot_toml::nodes::obstacle_avoid as n;

use crate::app::{run_node, twist_from_msg, twist_to_msg, AppStats, MS};
use crate::kinematics::Twist;
use crate::obstacle::{AvoidanceConfig, ObstacleAvoidance};
use crate::proximity::{mm_to_m, ProximityConfig, SENSOR_COUNT};
use crate::Nanos;

pub use super::NoHw as Hw;

/// A teleop command older than this is not forwarded: a silent gateway must not leave
/// the robot driving on its last command (5 teleop periods).
pub const TELEOP_TIMEOUT_NS: Nanos = 250 * MS;

/// The node's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Task {
    avoidance: ObstacleAvoidance,
    teleop: Option<(Nanos, Twist)>,
    ranges_m: [f32; SENSOR_COUNT],
    /// Sensors that limited the last published velocity (bit i = sensor i).
    pub limited_mask: u8,
    /// Velocity publications that were overridden (limited by an obstacle).
    pub overrides: u32,
    /// The last velocity published.
    pub last_velocity: Option<Twist>,
    pub stats: AppStats,
}

/// At power-on: no command, nothing in range.
pub const fn new() -> Task {
    Task {
        avoidance: ObstacleAvoidance::new(AvoidanceConfig::TRISKAR2),
        teleop: None,
        ranges_m: [ProximityConfig::TRISKAR2.max_range_m; SENSOR_COUNT],
        limited_mask: 0,
        overrides: 0,
        last_velocity: None,
        stats: AppStats {
            published: 0,
            publish_errors: 0,
        },
    }
}

impl Task {
    /// Takes every queued teleop command and proximity sample and publishes the limited
    /// command after each (nothing without a fresh command).
    pub fn step(&mut self, now: Nanos) {
        let running = run_node(&n::NODE, &n::module::STATUS);
        let (teleop, proximity) = (n::teleop_sub(), n::proximity_sub());
        loop {
            let mut event = false;
            if let Some(m) = teleop.try_recv() {
                self.teleop = Some((now, twist_from_msg(&m)));
                event = true;
            }
            if let Some(m) = proximity.try_recv() {
                self.ranges_m = mm_to_m(m.range_mm);
                event = true;
            }
            if !event {
                break;
            }
            let Some((at, cmd)) = self.teleop else {
                continue;
            };
            if !running || now.saturating_sub(at) > TELEOP_TIMEOUT_NS {
                continue;
            }
            let out = self.avoidance.filter(cmd, self.ranges_m);
            self.limited_mask = out.limited_mask;
            if out.limited_mask != 0 {
                self.overrides = self.overrides.wrapping_add(1);
            }
            self.last_velocity = Some(out.twist);
            self.stats
                .count(n::velocity_pub().send(twist_to_msg(out.twist), now));
        }
    }
}

/// Event driven: drains its subscriptions at every poll; never due by itself.
pub fn poll(t: &mut Task, now: Nanos, _hw: &mut impl Hw) -> Nanos {
    t.step(now);
    Nanos::MAX
}
