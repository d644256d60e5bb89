//! The gateway (bus master): `ros_bridge` forwards the host's velocity command as
//! `teleop` at 20 Hz and hands what the robot reports (odometry, proximity, battery,
//! log) to the host link.
use rtcan::robot_toml as msg;
use rtcan::robot_toml::gateway as module;

use super::{run_node, twist_to_msg, AppStats, Every, MS};
use crate::kinematics::Twist;
use crate::Nanos;

/// The gateway's host link (uROSnode on the real robot, a script in the simulator).
pub trait GatewayHw {
    /// The command to forward now (`None`: nothing to send).
    fn velocity_command(&mut self, now: Nanos) -> Option<Twist>;
    /// An odometry message arrived.
    fn odometry(&mut self, _now: Nanos, _m: &msg::Odometry) {}
    /// A proximity message arrived.
    fn proximity(&mut self, _now: Nanos, _m: &msg::Proximity) {}
    /// A battery message arrived.
    fn battery(&mut self, _now: Nanos, _m: &msg::Battery) {}
    /// A log line arrived.
    fn log(&mut self, _now: Nanos, _m: &msg::LogLine) {}
}

/// The gateway module.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatewayApp {
    teleop: Every,
    pub stats: AppStats,
}

impl Default for GatewayApp {
    fn default() -> Self {
        Self::new()
    }
}

impl GatewayApp {
    pub const fn new() -> Self {
        Self {
            teleop: Every::new(50 * MS),
            stats: AppStats {
                published: 0,
                publish_errors: 0,
            },
        }
    }

    /// Runs what is due and hands every received message to `hw`; returns the next
    /// local time to run at (call it also whenever a frame was received).
    pub fn poll(&mut self, now: Nanos, hw: &mut impl GatewayHw) -> Nanos {
        use module::nodes::ros_bridge as n;
        let running = run_node(&n::NODE, &module::STATUS);
        if self.teleop.due(now) {
            if let (true, Some(cmd)) = (running, hw.velocity_command(now)) {
                self.stats
                    .count(n::teleop_pub().send(twist_to_msg(cmd), now));
            }
        }
        let sub = n::odometry_sub();
        while let Some(m) = sub.try_recv() {
            hw.odometry(now, &m);
        }
        let sub = n::proximity_sub();
        while let Some(m) = sub.try_recv() {
            hw.proximity(now, &m);
        }
        let sub = n::battery_sub();
        while let Some(m) = sub.try_recv() {
            hw.battery(now, &m);
        }
        let sub = n::log_sub();
        while let Some(m) = sub.try_recv() {
            hw.log(now, &m);
        }
        self.teleop.next()
    }
}
