//! One app per Triskar2 module, generated from robot.toml (build.rs,
//! `rtcan_codegen::apps`): `<Module>App` owns the tasks (`crate::tasks`) of exactly the
//! nodes robot.toml places on that module and runs them on the module's generated
//! topics, with the hardware behind the small traits re-exported here. The firmware
//! images (HAL drivers) and `rtcan-sim` (plant models) implement the traits and call the
//! same code. Moving a node in robot.toml moves its task; no node code changes.
//!
//! Every app has `poll(now, hw) -> Nanos`: it runs the periodic node steps that are due
//! at `now` (rates as robot.toml declares them; HRT publishers `lead` before their slots),
//! drains the event-driven subscriptions, and returns the local time at which it next
//! needs to run; `task::<T>()` finds a node's task wherever it was placed.
//!
//! Lifecycle (R2P §3.4.2): a node starts (Init → Run) once the module's `STATUS` allows
//! it (synchronised and the master heard) and stops when the safe state is required; it
//! does not restart by itself. A stopped motor controller drives 0 duty.

pub use crate::tasks::battery_monitor::{log_line, PsuHw, LOG_LOW, LOG_STATUS};
pub use crate::tasks::ir_ranger::ProximityHw;
pub use crate::tasks::motor_ctrl::{MotorCtrl, MotorHw, COUNTS_PER_WHEEL_REV};
pub use crate::tasks::obstacle_avoid::TELEOP_TIMEOUT_NS;
pub use crate::tasks::ros_bridge::GatewayHw;

include!(concat!(env!("OUT_DIR"), "/apps.rs"));

use crate::kinematics::Twist;
use crate::Nanos;
use rtcan::pubsub::{Node, NodeState, SystemStatus};
use rtcan::robot_toml as msg;

/// Milliseconds in nanoseconds.
pub const MS: Nanos = 1_000_000;

/// A periodic task's schedule on the module's local clock. The first call is due at
/// once; a late call does not try to catch up with the periods it missed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Every {
    period: Nanos,
    next: Option<Nanos>,
}

impl Every {
    pub const fn new(period: Nanos) -> Self {
        Self { period, next: None }
    }

    /// Whether the task is due at `now` (and if so, schedules the next run).
    pub fn due(&mut self, now: Nanos) -> bool {
        let next = match self.next {
            None => now,
            Some(n) if now >= n => n,
            Some(_) => return false,
        };
        let mut following = next.saturating_add(self.period);
        if following <= now {
            following = now.saturating_add(self.period);
        }
        self.next = Some(following);
        true
    }

    /// When the task is next due (`0`: at the first poll).
    pub fn next(&self) -> Nanos {
        self.next.unwrap_or(0)
    }
}

/// Applies the lifecycle rule to `node` and tells whether it may act: starts it from
/// Init when the system allows, stops it when the safe state is required.
pub fn run_node(node: &Node, status: &SystemStatus) -> bool {
    if node.state() == NodeState::Init {
        let _ = node.start(status);
    }
    node.run(status)
}

pub(crate) fn twist_from_msg(t: &msg::Twist) -> Twist {
    Twist {
        vx: t.vx,
        vy: t.vy,
        wz: t.wz,
    }
}

pub(crate) fn twist_to_msg(t: Twist) -> msg::Twist {
    msg::Twist {
        vx: t.vx,
        vy: t.vy,
        wz: t.wz,
    }
}

/// Publications a module could not make (pool exhausted, queue full): they are counted,
/// never fatal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AppStats {
    pub published: u32,
    pub publish_errors: u32,
}

impl AppStats {
    pub(crate) fn count<E>(&mut self, r: Result<(), E>) {
        match r {
            Ok(()) => self.published = self.published.wrapping_add(1),
            Err(_) => self.publish_errors = self.publish_errors.wrapping_add(1),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_is_due_at_once_then_each_period_without_catch_up() {
        let mut e = Every::new(10);
        assert!(e.due(3));
        assert_eq!(e.next(), 13);
        assert!(!e.due(12));
        assert!(e.due(14));
        assert_eq!(e.next(), 23, "keeps the phase of the first run");
        assert!(e.due(100));
        assert_eq!(e.next(), 110, "far behind: restarts from now");
    }
}
