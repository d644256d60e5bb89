#![cfg_attr(not(test), no_std)]
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::indexing_slicing,
        clippy::panic
    )
)]
//! Triskar2 nodes (R2P paper §5): the robot's control logic as plain structs.
//!
//! Every node is pure logic: it is given the time (`now_ns`, nanoseconds on the caller's
//! clock, the same `Nanos` the rtcan core uses) and its inputs, and returns its outputs.
//! No node does I/O, allocates or keeps global state, so an RTIC task on a motor board
//! and a simulated module in `rtcan-sim` run the same code.
//!
//! Units are SI throughout (m, m/s, rad, rad/s, V, A); wheel speeds are wheel-shaft
//! angular speeds in rad/s, positive when the wheel pushes the robot along its drive
//! direction (see [`kinematics`]).
//!
//! | node | rate | in | out |
//! |---|---|---|---|
//! | [`MotorNode`] | 200 Hz, per motor | wheel setpoint, measured wheel speed | duty cycle |
//! | [`EncoderSpeed`] | 200 Hz, per motor | 16-bit encoder counter | wheel speed |
//! | [`InverseKinematicsNode`] | 100 Hz | body twist | three wheel setpoints |
//! | [`OdometryNode`] | per wheel-speed sample | three wheel speeds | twist, pose |
//! | [`ProximityNode`] | per IR sample | four raw ranges | filtered ranges, obstacle flags |
//! | [`ObstacleAvoidance`] | per command / proximity sample | twist, four ranges | overridden twist |
//! | [`BatteryNode`] | e.g. 10 Hz | voltage, current | percentage, low flag |

pub mod app;
pub mod battery;
pub mod encoder;
pub mod kinematics;
pub mod motor;
pub mod obstacle;
pub mod odometry;
pub mod pid;
pub mod proximity;
mod step_clock;
pub mod tasks;
pub mod trig;

pub use battery::{BatteryConfig, BatteryNode, BatteryStatus};
pub use encoder::EncoderSpeed;
pub use kinematics::{Geometry, InverseKinematicsNode, KinematicsConfig, Twist, TRISKAR2};
pub use motor::{MotorConfig, MotorNode, MotorOutput, MotorState};
pub use obstacle::{AvoidanceConfig, AvoidanceOutput, ObstacleAvoidance, SENSOR_DIRECTIONS};
pub use odometry::{OdometryNode, OdometryOutput, Pose};
pub use pid::{Pid, PidGains};
pub use proximity::{
    m_to_mm, mm_to_m, ProximityConfig, ProximityNode, ProximityOutput, SENSOR_COUNT,
};

/// Nanoseconds on the caller's clock (same type as `rtcan_core::time::Nanos`).
pub type Nanos = u64;

/// `x` limited to `lo..=hi`. Unlike `f32::clamp` it cannot panic on a bad configuration
/// (`lo > hi` gives `hi`; a NaN bound is ignored).
pub(crate) fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    x.max(lo).min(hi)
}
