//! The three motor modules: a 200 Hz wheel-speed controller each (`motor_ctrl1..3`),
//! plus inverse kinematics on motor1 (100 Hz) and odometry on motor2 (50 Hz).
use rtcan::pubsub::{HrtSlots, Node, Publisher, SlotEvery, Subscriber, SystemStatus};
use rtcan::robot_toml as msg;
use rtcan::robot_toml::{motor1, motor2, motor3};

use super::{run_node, twist_from_msg, AppStats, MS};
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
    every: SlotEvery,
    last: Option<MotorOutput>,
    pub stats: AppStats,
}

impl MotorCtrl {
    /// Controller of wheel `index` (0..3), 200 Hz: `lead` before each slot of its
    /// encoder topic (`slots`, R2P §3.4.5) once synchronised, every 5 ms before.
    pub const fn new(index: usize, slots: Option<HrtSlots>) -> Self {
        Self {
            index,
            motor: MotorNode::new(MotorConfig::TRISKAR2),
            encoder: EncoderSpeed::new(COUNTS_PER_WHEEL_REV),
            speed_rad_s: 0.0,
            every: SlotEvery::new(slots, 5 * MS),
            last: None,
            stats: AppStats {
                published: 0,
                publish_errors: 0,
            },
        }
    }

    /// The last step's output (`None` before the first step).
    pub const fn output(&self) -> Option<MotorOutput> {
        self.last
    }

    /// Measured wheel speed, rad/s.
    pub const fn speed_rad_s(&self) -> f32 {
        self.speed_rad_s
    }

    /// Whether the controller is held in the safe state (motor stopped).
    pub fn is_safe(&self) -> bool {
        self.last.is_some_and(|o| o.state == MotorState::Safe)
    }

    /// One control step on the module's generated handles: lifecycle, setpoints,
    /// encoder, PID, duty, encoder publication.
    #[allow(clippy::too_many_arguments)]
    pub fn step<
        const N1: usize,
        const S1: usize,
        const Q1: usize,
        const N2: usize,
        const S2: usize,
        const Q2: usize,
    >(
        &mut self,
        now: Nanos,
        hw: &mut impl MotorHw,
        setpoints: &Subscriber<'static, msg::WheelSpeeds, N1, S1, Q1>,
        encoder: &Publisher<'static, msg::Encoder, N2, S2, Q2>,
        node: &Node,
        status: &SystemStatus,
    ) {
        let running = run_node(node, status);
        self.motor.set_safe(!running);
        while let Some(m) = setpoints.try_recv() {
            if let Some(&w) = m.w.get(self.index) {
                self.motor.on_setpoint(now, w);
            }
        }
        if let Some(w) = self.encoder.step(now, hw.encoder_count()) {
            self.speed_rad_s = w;
        }
        let out = self.motor.step(now, self.speed_rad_s);
        hw.set_duty(out.duty);
        self.last = Some(out);
        self.stats.count(encoder.send(
            msg::Encoder {
                ticks: self.encoder.ticks(),
                speed: self.speed_rad_s,
            },
            now,
        ));
    }
}

/// motor1: `kinematics` (100 Hz: velocity → wheel_setpoints) and `motor_ctrl1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motor1App {
    pub ctrl: MotorCtrl,
    ik: InverseKinematicsNode,
    ik_every: SlotEvery,
    pub stats: AppStats,
}

impl Default for Motor1App {
    fn default() -> Self {
        Self::new()
    }
}

impl Motor1App {
    pub const fn new() -> Self {
        Self {
            ctrl: MotorCtrl::new(0, motor1::nodes::motor_ctrl1::ENCODER1_SLOTS),
            ik: InverseKinematicsNode::new(KinematicsConfig::TRISKAR2),
            ik_every: SlotEvery::new(motor1::nodes::kinematics::WHEEL_SETPOINTS_SLOTS, 10 * MS),
            stats: AppStats {
                published: 0,
                publish_errors: 0,
            },
        }
    }

    /// Inverse kinematics step: latest velocity in, wheel setpoints out (zero while the
    /// node is stopped or the command is stale).
    pub fn kinematics_step(&mut self, now: Nanos) {
        use motor1::nodes::kinematics as k;
        let running = run_node(&k::NODE, &motor1::STATUS);
        let sub = k::velocity_sub();
        while let Some(m) = sub.try_recv() {
            if running {
                self.ik.on_velocity(now, twist_from_msg(&m));
            }
        }
        let w = if running { self.ik.step(now) } else { [0.0; 3] };
        self.stats
            .count(k::wheel_setpoints_pub().send(msg::WheelSpeeds { w }, now));
    }

    /// Runs what is due; returns the next local time to run at.
    pub fn poll(&mut self, now: Nanos, hw: &mut impl MotorHw) -> Nanos {
        // Kinematics first: a fresh setpoint reaches the local controller in the same
        // poll (the same priority order as the firmware's tasks).
        let grid = motor1::STATUS.grid();
        if self.ik_every.due(now, grid) {
            self.kinematics_step(now);
        }
        if self.ctrl.every.due(now, grid) {
            use motor1::nodes::motor_ctrl1 as m;
            self.ctrl.step(
                now,
                hw,
                &m::wheel_setpoints_sub(),
                &m::encoder1_pub(),
                &m::NODE,
                &motor1::STATUS,
            );
        }
        self.ik_every.next().min(self.ctrl.every.next())
    }
}

/// motor2: `odometry` (50 Hz from encoder1..3) and `motor_ctrl2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motor2App {
    pub ctrl: MotorCtrl,
    odometry: OdometryNode,
    odo_every: SlotEvery,
    wheels: [f32; 3],
    pub stats: AppStats,
}

impl Default for Motor2App {
    fn default() -> Self {
        Self::new()
    }
}

impl Motor2App {
    pub const fn new() -> Self {
        Self {
            ctrl: MotorCtrl::new(1, motor2::nodes::motor_ctrl2::ENCODER2_SLOTS),
            odometry: OdometryNode::new(TRISKAR2, 20 * MS),
            odo_every: SlotEvery::new(motor2::nodes::odometry::ODOMETRY_SLOTS, 20 * MS),
            wheels: [0.0; 3],
            stats: AppStats {
                published: 0,
                publish_errors: 0,
            },
        }
    }

    /// Odometry's current pose estimate.
    pub const fn pose(&self) -> Pose {
        self.odometry.pose()
    }

    /// Odometry step: latest wheel speeds of the three encoders, pose integrated,
    /// `odometry` published.
    pub fn odometry_step(&mut self, now: Nanos) {
        use motor2::nodes::odometry as o;
        let running = run_node(&o::NODE, &motor2::STATUS);
        let (s1, s2, s3) = (o::encoder1_sub(), o::encoder2_sub(), o::encoder3_sub());
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
        self.stats.count(o::odometry_pub().send(
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

    /// Runs what is due; returns the next local time to run at.
    pub fn poll(&mut self, now: Nanos, hw: &mut impl MotorHw) -> Nanos {
        let grid = motor2::STATUS.grid();
        if self.ctrl.every.due(now, grid) {
            use motor2::nodes::motor_ctrl2 as m;
            self.ctrl.step(
                now,
                hw,
                &m::wheel_setpoints_sub(),
                &m::encoder2_pub(),
                &m::NODE,
                &motor2::STATUS,
            );
        }
        if self.odo_every.due(now, grid) {
            self.odometry_step(now);
        }
        self.odo_every.next().min(self.ctrl.every.next())
    }
}

fn latest(it: impl Iterator<Item = f32>) -> Option<f32> {
    it.last()
}

/// motor3: `motor_ctrl3` only.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motor3App {
    pub ctrl: MotorCtrl,
}

impl Default for Motor3App {
    fn default() -> Self {
        Self::new()
    }
}

impl Motor3App {
    pub const fn new() -> Self {
        Self {
            ctrl: MotorCtrl::new(2, motor3::nodes::motor_ctrl3::ENCODER3_SLOTS),
        }
    }

    /// Runs what is due; returns the next local time to run at.
    pub fn poll(&mut self, now: Nanos, hw: &mut impl MotorHw) -> Nanos {
        if self.ctrl.every.due(now, motor3::STATUS.grid()) {
            use motor3::nodes::motor_ctrl3 as m;
            self.ctrl.step(
                now,
                hw,
                &m::wheel_setpoints_sub(),
                &m::encoder3_pub(),
                &m::NODE,
                &motor3::STATUS,
            );
        }
        self.ctrl.every.next()
    }
}
