//! Motor controller node: one per DC-motor module, PID on wheel speed at 200 Hz.

use crate::clamp;
use crate::pid::{Pid, PidGains};
use crate::step_clock::StepClock;
use crate::Nanos;

/// Motor controller configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorConfig {
    /// Wheel speed (rad/s) → duty cycle (-1..=1, sign = direction).
    pub gains: PidGains,
    /// Nominal control period; the first step integrates over this.
    pub period_ns: Nanos,
    /// A setpoint older than this stops the motor: a silent bus must not leave the
    /// robot driving on its last command.
    pub setpoint_timeout_ns: Nanos,
    /// Setpoints are clamped to ±this (what the motor can reach at full duty).
    pub max_speed_rad_s: f32,
}

impl MotorConfig {
    /// Triskar2 motor module: 200 Hz loop, 100 ms setpoint timeout (ten periods of the
    /// 100 Hz kinematics node), gains for the rtcan-sim DC motor (≈ 48 rad/s per unit
    /// duty at the wheel, 40 ms mechanical time constant).
    pub const TRISKAR2: Self = Self {
        gains: PidGains {
            kp: 0.04,
            ki: 1.0,
            kd: 0.0,
            out_min: -1.0,
            out_max: 1.0,
        },
        period_ns: 5_000_000,
        setpoint_timeout_ns: 100_000_000,
        max_speed_rad_s: 40.0,
    };
}

/// Why the motor is (or is not) being driven.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotorState {
    /// No setpoint received yet since start or since leaving the safe state.
    WaitingForSetpoint,
    /// Tracking a fresh setpoint.
    Running,
    /// The last setpoint is older than `setpoint_timeout_ns`.
    SetpointTimeout,
    /// Commanded into the safe state: output forced to 0 until released.
    Safe,
}

/// One step's result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorOutput {
    /// Duty cycle for the H-bridge, -1..=1; exactly 0 unless `state == Running`.
    pub duty: f32,
    /// The setpoint actually tracked (after clamping), rad/s.
    pub setpoint_rad_s: f32,
    pub state: MotorState,
}

/// The motor controller node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorNode {
    config: MotorConfig,
    pid: Pid,
    clock: StepClock,
    setpoint: Option<(Nanos, f32)>,
    safe: bool,
}

impl MotorNode {
    pub const fn new(config: MotorConfig) -> Self {
        Self {
            config,
            pid: Pid::new(config.gains),
            clock: StepClock::new(config.period_ns, 4 * config.period_ns),
            setpoint: None,
            safe: false,
        }
    }

    /// A new wheel-speed setpoint (rad/s) arrived at `now_ns`. Non-finite values are
    /// ignored (the previous setpoint keeps ageing towards the timeout).
    pub fn on_setpoint(&mut self, now_ns: Nanos, speed_rad_s: f32) {
        if speed_rad_s.is_finite() {
            let max = self.config.max_speed_rad_s;
            self.setpoint = Some((now_ns, clamp(speed_rad_s, -max, max)));
        }
    }

    /// Enter (`true`) or leave (`false`) the safe state. Entering drops the setpoint
    /// and the controller history, so leaving it needs a fresh setpoint to move again.
    pub fn set_safe(&mut self, safe: bool) {
        if safe && !self.safe {
            self.stop();
        }
        self.safe = safe;
    }

    pub const fn is_safe(&self) -> bool {
        self.safe
    }

    /// One control step with the measured wheel speed (rad/s).
    pub fn step(&mut self, now_ns: Nanos, measured_rad_s: f32) -> MotorOutput {
        let dt_s = self.clock.dt_s(now_ns);
        let state = if self.safe {
            MotorState::Safe
        } else {
            match self.setpoint {
                None => MotorState::WaitingForSetpoint,
                Some((at, _)) if now_ns.saturating_sub(at) > self.config.setpoint_timeout_ns => {
                    MotorState::SetpointTimeout
                }
                Some(_) => MotorState::Running,
            }
        };
        match (state, self.setpoint) {
            (MotorState::Running, Some((_, setpoint))) => MotorOutput {
                duty: self.pid.step(setpoint, measured_rad_s, dt_s),
                setpoint_rad_s: setpoint,
                state,
            },
            _ => {
                // Not driving: keep the integral from carrying stale effort into the
                // next run.
                self.pid.reset();
                MotorOutput {
                    duty: 0.0,
                    setpoint_rad_s: 0.0,
                    state,
                }
            }
        }
    }

    fn stop(&mut self) {
        self.setpoint = None;
        self.pid.reset();
        self.clock.reset();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Nanos = 1_000_000;

    #[test]
    fn waits_for_first_setpoint_with_zero_duty() {
        let mut m = MotorNode::new(MotorConfig::TRISKAR2);
        let out = m.step(0, 0.0);
        assert_eq!(out.state, MotorState::WaitingForSetpoint);
        assert_eq!(out.duty, 0.0);
    }

    #[test]
    fn runs_on_fresh_setpoint_and_clamps_it() {
        let mut m = MotorNode::new(MotorConfig::TRISKAR2);
        m.on_setpoint(0, 100.0);
        let out = m.step(5 * MS, 0.0);
        assert_eq!(out.state, MotorState::Running);
        assert_eq!(out.setpoint_rad_s, 40.0);
        // kp * 40 = 1.6 → saturated.
        assert_eq!(out.duty, 1.0);
    }

    #[test]
    fn stale_setpoint_stops_the_motor() {
        let mut m = MotorNode::new(MotorConfig::TRISKAR2);
        m.on_setpoint(0, 10.0);
        assert_eq!(m.step(100 * MS, 0.0).state, MotorState::Running);
        let out = m.step(101 * MS, 0.0);
        assert_eq!(out.state, MotorState::SetpointTimeout);
        assert_eq!(out.duty, 0.0);
        m.on_setpoint(102 * MS, 10.0);
        assert_eq!(m.step(103 * MS, 0.0).state, MotorState::Running);
    }

    #[test]
    fn safe_state_forces_zero_until_released_and_fresh_setpoint() {
        let mut m = MotorNode::new(MotorConfig::TRISKAR2);
        m.on_setpoint(0, 10.0);
        assert!(m.step(5 * MS, 0.0).duty > 0.0);
        m.set_safe(true);
        // Setpoints keep arriving but must not move the motor.
        m.on_setpoint(6 * MS, 10.0);
        let out = m.step(10 * MS, 0.0);
        assert_eq!((out.state, out.duty), (MotorState::Safe, 0.0));
        m.set_safe(false);
        // The setpoint received while safe still counts once released (it is fresh)...
        assert_eq!(m.step(15 * MS, 0.0).state, MotorState::Running);
        // ...but one received before entering safe does not.
        m.set_safe(true);
        m.set_safe(false);
        assert_eq!(m.step(20 * MS, 0.0).state, MotorState::WaitingForSetpoint);
    }

    #[test]
    fn non_finite_setpoint_is_ignored() {
        let mut m = MotorNode::new(MotorConfig::TRISKAR2);
        m.on_setpoint(0, f32::NAN);
        assert_eq!(m.step(5 * MS, 0.0).state, MotorState::WaitingForSetpoint);
    }
}
