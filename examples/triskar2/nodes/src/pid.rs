//! PID controller with output saturation and anti-windup.

use crate::clamp;

/// Gains and output limits. The integral and derivative gains are per second
/// (`ki` multiplies the error integrated over seconds, `kd` the rate in units/s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PidGains {
    pub kp: f32,
    pub ki: f32,
    pub kd: f32,
    pub out_min: f32,
    pub out_max: f32,
}

/// A PID controller.
///
/// * The derivative acts on the measurement, not the error, so a setpoint step does
///   not kick the output.
/// * Anti-windup by clamping: the integral only grows until P + I + D reaches the output
///   limit (so a saturated output sits exactly at the limit), does not grow while P and
///   D alone saturate, and is itself bounded by the output range. The controller leaves
///   saturation as soon as the error changes sign, instead of after unwinding a huge
///   integral.
/// * A non-finite setpoint or measurement (a corrupt message) yields output 0 and leaves
///   the state untouched.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pid {
    gains: PidGains,
    /// Integral term, already multiplied by `ki` (so gain changes do not bump it).
    i_term: f32,
    prev_measured: Option<f32>,
}

impl Pid {
    pub const fn new(gains: PidGains) -> Self {
        Self {
            gains,
            i_term: 0.0,
            prev_measured: None,
        }
    }

    pub const fn gains(&self) -> PidGains {
        self.gains
    }

    /// The integral term's current contribution to the output.
    pub const fn integral(&self) -> f32 {
        self.i_term
    }

    /// Forget the integral and the derivative history (after a stop or a mode change).
    pub fn reset(&mut self) {
        self.i_term = 0.0;
        self.prev_measured = None;
    }

    /// One control step of `dt_s` seconds; returns the saturated output.
    pub fn step(&mut self, setpoint: f32, measured: f32, dt_s: f32) -> f32 {
        if !setpoint.is_finite() || !measured.is_finite() || !dt_s.is_finite() {
            return 0.0;
        }
        let g = self.gains;
        let error = setpoint - measured;
        let p = g.kp * error;
        let d = match self.prev_measured {
            Some(prev) if dt_s > 0.0 => -g.kd * (measured - prev) / dt_s,
            _ => 0.0,
        };
        self.prev_measured = Some(measured);

        // The integral may grow only up to the headroom P and D leave below the limit,
        // and not at all while P and D alone saturate the output.
        let upper = self.i_term.max(g.out_max - p - d);
        let lower = self.i_term.min(g.out_min - p - d);
        let candidate = self.i_term + g.ki * error * dt_s;
        self.i_term = clamp(clamp(candidate, lower, upper), g.out_min, g.out_max);
        clamp(p + self.i_term + d, g.out_min, g.out_max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PI_GAINS: PidGains = PidGains {
        kp: 0.5,
        ki: 2.0,
        kd: 0.0,
        out_min: -1.0,
        out_max: 1.0,
    };

    #[test]
    fn proportional_only_is_kp_times_error() {
        let mut pid = Pid::new(PidGains {
            ki: 0.0,
            ..PI_GAINS
        });
        assert_eq!(pid.step(1.0, 0.2, 0.01), 0.4);
        assert_eq!(pid.step(-1.0, 0.2, 0.01), -0.6);
    }

    #[test]
    fn integral_accumulates_error_times_dt() {
        let mut pid = Pid::new(PI_GAINS);
        // error 0.1, dt 0.01: i += 2 * 0.1 * 0.01 = 0.002 per step.
        let mut out = 0.0;
        for _ in 0..10 {
            out = pid.step(0.1, 0.0, 0.01);
        }
        assert!((pid.integral() - 0.02).abs() < 1e-6, "{}", pid.integral());
        assert!((out - (0.05 + 0.02)).abs() < 1e-6, "{out}");
    }

    #[test]
    fn output_saturates_at_limits() {
        let mut pid = Pid::new(PI_GAINS);
        assert_eq!(pid.step(100.0, 0.0, 0.01), 1.0);
        assert_eq!(pid.step(-100.0, 0.0, 0.01), -1.0);
    }

    #[test]
    fn anti_windup_stops_integrating_while_saturated() {
        let mut pid = Pid::new(PI_GAINS);
        // Large error for 10 s: without anti-windup the integral would reach 2*10*10 = 200.
        for _ in 0..1000 {
            assert_eq!(pid.step(10.0, 0.0, 0.01), 1.0);
        }
        assert!(pid.integral() <= 1.0, "{}", pid.integral());
        // Once the measurement overshoots, the output leaves saturation on the first step.
        let out = pid.step(10.0, 10.5, 0.01);
        assert!(
            out < 1.0,
            "still saturated after the error changed sign: {out}"
        );
    }

    #[test]
    fn integral_fills_exactly_the_headroom_to_the_limit() {
        let mut pid = Pid::new(PI_GAINS);
        // P = 0.5 * 1.2 = 0.6; the integral grows to 0.4 and stops there: output 1.0.
        for _ in 0..1000 {
            pid.step(1.2, 0.0, 0.01);
        }
        assert!((pid.integral() - 0.4).abs() < 1e-6, "{}", pid.integral());
        assert_eq!(pid.step(1.2, 0.0, 0.01), 1.0);
        // Same on the negative side.
        let mut pid = Pid::new(PI_GAINS);
        for _ in 0..1000 {
            pid.step(-1.2, 0.0, 0.01);
        }
        assert!((pid.integral() + 0.4).abs() < 1e-6, "{}", pid.integral());
    }

    #[test]
    fn inverted_limits_do_not_panic() {
        let mut pid = Pid::new(PidGains {
            out_min: 1.0,
            out_max: -1.0,
            ..PI_GAINS
        });
        assert_eq!(pid.step(1.0, 0.0, 0.01), -1.0);
    }

    #[test]
    fn saturated_proportional_does_not_wind_the_integral_at_all() {
        let mut pid = Pid::new(PI_GAINS);
        // kp * error = 5 alone saturates: nothing may be integrated.
        for _ in 0..100 {
            pid.step(10.0, 0.0, 0.01);
        }
        assert_eq!(pid.integral(), 0.0);
    }

    #[test]
    fn derivative_acts_on_measurement_not_setpoint() {
        let mut pid = Pid::new(PidGains {
            kp: 0.0,
            ki: 0.0,
            kd: 0.1,
            out_min: -10.0,
            out_max: 10.0,
        });
        assert_eq!(pid.step(0.0, 0.0, 0.01), 0.0);
        // Setpoint step: no kick.
        assert_eq!(pid.step(5.0, 0.0, 0.01), 0.0);
        // Measurement rises 0.02 in 0.01 s: -0.1 * 2 = -0.2.
        assert!((pid.step(5.0, 0.02, 0.01) + 0.2).abs() < 1e-6);
    }

    #[test]
    fn non_finite_inputs_give_zero_and_keep_state() {
        let mut pid = Pid::new(PI_GAINS);
        pid.step(0.1, 0.0, 0.01);
        let before = pid;
        assert_eq!(pid.step(f32::NAN, 0.0, 0.01), 0.0);
        assert_eq!(pid.step(0.0, f32::INFINITY, 0.01), 0.0);
        assert_eq!(pid, before);
    }

    #[test]
    fn reset_clears_integral() {
        let mut pid = Pid::new(PI_GAINS);
        pid.step(0.1, 0.0, 0.01);
        assert!(pid.integral() > 0.0);
        pid.reset();
        assert_eq!(pid.integral(), 0.0);
    }
}
