//! `ir_ranger`: the four IR ranges sampled and filtered at 25 Hz → `proximity` (mm). It
//! needs the rangers of the module it runs on ([`ProximityHw`]).
use rtcan::pubsub::SlotEvery;
use rtcan::robot_toml as msg;
use rtcan::robot_toml::nodes::ir_ranger as n;

use crate::app::{run_node, AppStats, MS};
use crate::proximity::{ProximityConfig, ProximityNode, SENSOR_COUNT};
use crate::Nanos;

/// The proximity module's hardware: four IR rangers (front, left, back, right).
pub trait ProximityHw {
    /// Raw ranges, m (non-finite: no reading).
    fn ranges_m(&mut self) -> [f32; SENSOR_COUNT];
}

pub use ProximityHw as Hw;

/// The node's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Task {
    ranger: ProximityNode,
    every: SlotEvery,
    pub stats: AppStats,
}

/// At power-on: `lead` before each `proximity` slot once synchronised (R2P §3.4.5),
/// every 40 ms before.
pub const fn new() -> Task {
    Task {
        ranger: ProximityNode::new(ProximityConfig::TRISKAR2),
        every: SlotEvery::new(n::PROXIMITY_SLOTS, 40 * MS),
        stats: AppStats {
            published: 0,
            publish_errors: 0,
        },
    }
}

impl Task {
    /// One step: sample, filter, publish `proximity` (mm).
    pub fn step(&mut self, now: Nanos, hw: &mut impl ProximityHw) {
        let running = run_node(&n::NODE, &n::module::STATUS);
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
}

/// A step when due; returns when the next one is.
pub fn poll(t: &mut Task, now: Nanos, hw: &mut impl Hw) -> Nanos {
    if t.every.due(now, n::module::STATUS.grid()) {
        t.step(now, hw);
    }
    t.every.next()
}
