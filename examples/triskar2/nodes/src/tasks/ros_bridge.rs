//! `ros_bridge`: forwards the host's velocity command as `teleop` at 20 Hz and hands
//! what the robot reports (odometry, proximity, battery, log) to the host link. It
//! needs the host link of the module it runs on ([`GatewayHw`]).
use rtcan::robot_toml as msg;
use rtcan::robot_toml::nodes::ros_bridge as n;

use crate::app::{run_node, twist_to_msg, AppStats, Every, MS};
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

pub use GatewayHw as Hw;

/// The node's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Task {
    teleop: Every,
    pub stats: AppStats,
}

/// At power-on.
pub const fn new() -> Task {
    Task {
        teleop: Every::new(50 * MS),
        stats: AppStats {
            published: 0,
            publish_errors: 0,
        },
    }
}

/// Forwards the command when due and hands every received message to `hw`; returns
/// when the next command is due (poll it also whenever a frame was received).
pub fn poll(t: &mut Task, now: Nanos, hw: &mut impl Hw) -> Nanos {
    let running = run_node(&n::NODE, &n::module::STATUS);
    if t.teleop.due(now) {
        if let (true, Some(cmd)) = (running, hw.velocity_command(now)) {
            t.stats.count(n::teleop_pub().send(twist_to_msg(cmd), now));
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
    t.teleop.next()
}
