//! The three motor modules: a 200 Hz wheel-speed controller each (`motor_ctrl1..3`),
//! plus inverse kinematics on motor1 (100 Hz) and odometry on motor2 (50 Hz).
use rtcan::pubsub::{Node, Publisher, Subscriber, SystemStatus};
use rtcan::robot_toml as msg;
use rtcan::robot_toml::{motor1, motor2, motor3};

use super::{run_node, twist_from_msg, AppStats, Every, MS};
use crate::encoder::EncoderSpeed;
use crate::kinematics::{InverseKinematicsNode, KinematicsConfig, TRISKAR2};
use crate::motor::{MotorConfig, MotorNode, MotorOutput, MotorState};
use crate::odometry::{OdometryNode, Pose};
use crate::Nanos;

/// Encoder counts per wheel revolution: 500-line encoder, ×4 quadrature, 10:1 gearbox.
pub const COUNTS_PER_WHEEL_REV: f32 = 20_000.0;

/// A motor module's hardware: the encoder timer and the H-bridge.
pub trait MotorHw {
    /// The free-running 16-bit encoder counter.
    fn encoder_count(&mut self) -> u16;
    /// Duty cycle -1..=1 (sign = direction); 0 stops the motor.
    fn set_duty(&mut self, duty: f32);
}

/// One wheel's controller (`motor_ctrl<i>`): setpoint from `wheel_setpoints.w[index]`,
/// speed from the encoder, PID to duty, `encoder<i>` published every step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorCtrl {
    index: usize,
    motor: MotorNode,
    encoder: EncoderSpeed,
    speed_rad_s: f32,
    every: Every,
    last: Option<MotorOutput>,
    pub stats: AppStats,
}

impl MotorCtrl {
    /// Controller of wheel `index` (0..3).
    pub const fn new(index: usize) -> Self {
        Self {
            index,
            motor: MotorNode::new(MotorConfig::TRISKAR2),
            encoder: EncoderSpeed::new(COUNTS_PER_WHEEL_REV),
            speed_rad_s: 0.0,
            every: Every::new(5 * MS),
            last: None,
            pub_stats_init(),
        }
    }
}
