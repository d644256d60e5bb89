//! The proximity module: `ir_ranger` (25 Hz: four IR ranges → `proximity`) and
//! `obstacle_avoid` (on every teleop command and proximity sample: the command limited
//! by the ranges → `velocity`).
use rtcan::robot_toml as msg;
use rtcan::robot_toml::proximity as module;

use super::{run_node, twist_from_msg, twist_to_msg, AppStats, MS};
use crate::kinematics::Twist;
use crate::obstacle::{AvoidanceConfig, ObstacleAvoidance};
use crate::proximity::{mm_to_m, ProximityConfig, ProximityNode, SENSOR_COUNT};
use crate::Nanos;
use rtcan::pubsub::SlotEvery;

/// The proximity module's hardware: four IR rangers (front, left, back, right).
pub trait ProximityHw {
    /// Raw ranges, m (non-finite: no reading).
    fn ranges_m(&mut self) -> [f32; SENSOR_COUNT];
}

/// A teleop command older than this is not forwarded: a silent gateway must not leave
/// the robot driving on its last command (5 teleop periods).
pub const TELEOP_TIMEOUT_NS: Nanos = 250 * MS;

/// The proximity module.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProximityApp {
    ranger: ProximityNode,
    ranger_every: SlotEvery,
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

impl Default for ProximityApp {
    fn default() -> Self {
        Self::new()
    }
}

impl ProximityApp {
    pub const fn new() -> Self {
        Self {
            ranger: ProximityNode::new(ProximityConfig::TRISKAR2),
            // `lead` before each `proximity` slot once synchronised (R2P §3.4.5).
            ranger_every: SlotEvery::new(module::nodes::ir_ranger::PROXIMITY_SLOTS, 40 * MS),
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

    /// `ir_ranger`: sample, filter, publish `proximity` (mm).
    pub fn ranger_step(&mut self, now: Nanos, hw: &mut impl ProximityHw) {
        use module::nodes::ir_ranger as n;
        let running = run_node(&n::NODE, &module::STATUS);
        let out = self.ranger.step(hw.ranges_m());
        if running {
            self.stats.count(n::proximity_pub().send(
                msg::Proximity {
                    range_mm: out.range_mm(),
                },
                now,
            ));
        }
    }

    /// `obstacle_avoid`: takes every queued teleop command and proximity sample and
    /// publishes the limited command after each (nothing without a fresh command).
    pub fn avoid_step(&mut self, now: Nanos) {
        use module::nodes::obstacle_avoid as n;
        let running = run_node(&n::NODE, &module::STATUS);
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

    /// Runs what is due and drains the subscriptions; returns the next local time to
    /// run at (call it also whenever a frame was received).
    pub fn poll(&mut self, now: Nanos, hw: &mut impl ProximityHw) -> Nanos {
        if self.ranger_every.due(now, module::STATUS.grid()) {
            self.ranger_step(now, hw);
        }
        self.avoid_step(now);
        self.ranger_every.next()
    }
}
