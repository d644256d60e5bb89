//! `motor_ctrl1..3`: one wheel's 200 Hz speed controller each. It needs the motor
//! hardware of the module it runs on ([`MotorHw`]), so robot.toml places it on a motor
//! board.
use rtcan::pubsub::{HrtSlots, Node, Publisher, SlotEvery, Subscriber, SystemStatus};
use rtcan::robot_toml as msg;

use crate::app::{run_node, AppStats, MS};
use crate::encoder::EncoderSpeed;
use crate::motor::{MotorConfig, MotorNode, MotorOutput, MotorState};
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

    /// The wheel it drives (0..3).
    pub const fn index(&self) -> usize {
        self.index
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

    /// One control step on the node's generated handles: lifecycle, setpoints,
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

/// The task of node `$node`: wheel `$index`, publishing `$pub` in the slots `$slots`.
macro_rules! motor_ctrl_node {
    ($(#[$doc:meta])* $node:ident, $index:literal, $pub:ident, $slots:ident) => {
        $(#[$doc])*
        pub mod $node {
            use rtcan::robot_toml::nodes::$node as n;

            pub use super::MotorHw as Hw;
            /// The controller.
            pub type Task = super::MotorCtrl;

            /// At power-on.
            pub const fn new() -> Task {
                super::MotorCtrl::new($index, n::$slots)
            }

            /// A control step when due; returns when the next one is.
            pub fn poll(t: &mut Task, now: crate::Nanos, hw: &mut impl Hw) -> crate::Nanos {
                if t.every.due(now, n::module::STATUS.grid()) {
                    t.step(
                        now,
                        hw,
                        &n::wheel_setpoints_sub(),
                        &n::$pub(),
                        &n::NODE,
                        &n::module::STATUS,
                    );
                }
                t.every.next()
            }
        }
    };
}

motor_ctrl_node!(
    /// `motor_ctrl1`: wheel 1, publishes `encoder1`.
    motor_ctrl1, 0, encoder1_pub, ENCODER1_SLOTS
);
motor_ctrl_node!(
    /// `motor_ctrl2`: wheel 2, publishes `encoder2`.
    motor_ctrl2, 1, encoder2_pub, ENCODER2_SLOTS
);
motor_ctrl_node!(
    /// `motor_ctrl3`: wheel 3, publishes `encoder3`.
    motor_ctrl3, 2, encoder3_pub, ENCODER3_SLOTS
);
