//! DC motor with gearbox and quadrature encoder.
//!
//! Armature: `L di/dt = V - R i - Ke ω`; shaft: `J dω/dt = Kt i - b ω - τ_load/N`
//! (ω at the motor, `N` the gear ratio, `J` including the reflected load). With
//! `Kt = Ke = k`, the steady-state wheel speed for a constant voltage is
//! `ω_wheel = V · k / (R b + k²) / N`.

/// Motor, gearbox and encoder constants (SI).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DcMotorParams {
    pub resistance_ohm: f64,
    /// 0 gives a purely first-order (mechanical) model: `i = (V - k ω)/R`.
    pub inductance_h: f64,
    /// Torque constant = back-EMF constant, N·m/A = V·s/rad.
    pub k: f64,
    /// Rotor + reflected load inertia at the motor shaft, kg·m².
    pub inertia_kg_m2: f64,
    /// Viscous friction at the motor shaft, N·m·s/rad.
    pub friction: f64,
    /// Motor revolutions per wheel revolution.
    pub gear_ratio: f64,
    /// Encoder counts per motor revolution (after ×4 quadrature decoding).
    pub encoder_cpr: u32,
}

impl DcMotorParams {
    /// A 70 W, 24 V Triskar2 drive: 10:1 gearbox, 500-line encoder, a third of the
    /// 20 kg robot reflected onto each wheel (m r² / N² = 6.7 · 0.05² / 100).
    pub const TRISKAR2: Self = Self {
        resistance_ohm: 0.5,
        inductance_h: 2e-4,
        k: 0.05,
        inertia_kg_m2: 2e-4,
        friction: 1e-5,
        gear_ratio: 10.0,
        encoder_cpr: 2000,
    };

    /// Steady-state wheel speed per volt, rad/s/V.
    pub fn wheel_speed_per_volt(&self) -> f64 {
        self.k / (self.resistance_ohm * self.friction + self.k * self.k) / self.gear_ratio
    }

    /// Mechanical time constant `J R / (R b + k²)`, s.
    pub fn mechanical_time_constant_s(&self) -> f64 {
        self.inertia_kg_m2 * self.resistance_ohm
            / (self.resistance_ohm * self.friction + self.k * self.k)
    }

    /// Encoder counts per wheel revolution.
    pub fn counts_per_wheel_rev(&self) -> f64 {
        f64::from(self.encoder_cpr) * self.gear_ratio
    }
}

/// Motor state.
#[derive(Clone, Debug, PartialEq)]
pub struct DcMotor {
    params: DcMotorParams,
    current_a: f64,
    speed_rad_s: f64,
    angle_rad: f64,
}

/// Integration sub-step: a tenth of the Triskar2 electrical time constant (L/R = 0.4 ms).
const MAX_SUBSTEP_S: f64 = 20e-6;

impl DcMotor {
    pub fn new(params: DcMotorParams) -> Self {
        Self {
            params,
            current_a: 0.0,
            speed_rad_s: 0.0,
            angle_rad: 0.0,
        }
    }

    pub fn params(&self) -> &DcMotorParams {
        &self.params
    }

    /// Advance `dt_s` with `voltage_v` across the armature and `load_torque_nm` at the
    /// wheel opposing motion. Semi-implicit Euler (the R and b terms implicit), which is
    /// stable for any sub-step and accurate at `MAX_SUBSTEP_S`.
    pub fn step(&mut self, dt_s: f64, voltage_v: f64, load_torque_nm: f64) {
        if dt_s.is_nan() || dt_s <= 0.0 || !voltage_v.is_finite() || !load_torque_nm.is_finite() {
            return;
        }
        let p = self.params;
        let n = (dt_s / MAX_SUBSTEP_S).ceil().max(1.0);
        let h = dt_s / n;
        let load_at_motor = load_torque_nm / p.gear_ratio;
        for _ in 0..n as u64 {
            self.current_a = if p.inductance_h > 0.0 {
                (self.current_a + h / p.inductance_h * (voltage_v - p.k * self.speed_rad_s))
                    / (1.0 + h * p.resistance_ohm / p.inductance_h)
            } else {
                (voltage_v - p.k * self.speed_rad_s) / p.resistance_ohm
            };
            self.speed_rad_s = (self.speed_rad_s
                + h / p.inertia_kg_m2 * (p.k * self.current_a - load_at_motor))
                / (1.0 + h * p.friction / p.inertia_kg_m2);
            self.angle_rad += self.speed_rad_s * h;
        }
    }

    pub fn current_a(&self) -> f64 {
        self.current_a
    }

    pub fn motor_speed_rad_s(&self) -> f64 {
        self.speed_rad_s
    }

    pub fn wheel_speed_rad_s(&self) -> f64 {
        self.speed_rad_s / self.params.gear_ratio
    }

    /// Wheel angle since start, rad.
    pub fn wheel_angle_rad(&self) -> f64 {
        self.angle_rad / self.params.gear_ratio
    }

    /// Encoder position since start, whole counts (towards -∞).
    pub fn encoder_ticks(&self) -> i64 {
        (self.angle_rad / std::f64::consts::TAU * f64::from(self.params.encoder_cpr)).floor() as i64
    }

    /// What a 16-bit timer in encoder mode reads: the position modulo 2^16.
    pub fn encoder_count(&self) -> u16 {
        self.encoder_ticks() as u16
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steady_state_speed_is_gain_times_voltage() {
        let p = DcMotorParams::TRISKAR2;
        let mut m = DcMotor::new(p);
        // 12 V for 1 s = 25 mechanical time constants.
        for _ in 0..200 {
            m.step(0.005, 12.0, 0.0);
        }
        let expected = 12.0 * p.wheel_speed_per_volt();
        assert!((expected - 23.952_095).abs() < 1e-5, "{expected}");
        assert!(
            (m.wheel_speed_rad_s() - expected).abs() < 1e-6,
            "{}",
            m.wheel_speed_rad_s()
        );
        // Steady current only overcomes friction: b ω / k.
        let i = p.friction * m.motor_speed_rad_s() / p.k;
        assert!((m.current_a() - i).abs() < 1e-6);
    }

    #[test]
    fn first_order_rise_reaches_63_percent_at_one_time_constant() {
        let p = DcMotorParams {
            inductance_h: 0.0,
            ..DcMotorParams::TRISKAR2
        };
        let tau = p.mechanical_time_constant_s();
        assert!((tau - 0.039_920).abs() < 1e-6, "{tau}");
        let mut m = DcMotor::new(p);
        m.step(tau, 24.0, 0.0);
        let frac = m.wheel_speed_rad_s() / (24.0 * p.wheel_speed_per_volt());
        assert!((frac - (1.0 - (-1.0_f64).exp())).abs() < 1e-3, "{frac}");
    }

    #[test]
    fn load_torque_lowers_speed_and_draws_current() {
        let p = DcMotorParams::TRISKAR2;
        let mut m = DcMotor::new(p);
        for _ in 0..400 {
            m.step(0.005, 24.0, 1.0);
        }
        // 1 N·m at the wheel = 0.1 N·m at the motor = 2 A more than friction needs.
        let free = 24.0 * p.wheel_speed_per_volt();
        assert!(m.wheel_speed_rad_s() < free - 1.0);
        let i = (p.friction * m.motor_speed_rad_s() + 0.1) / p.k;
        assert!((m.current_a() - i).abs() < 1e-6, "{} vs {i}", m.current_a());
    }

    #[test]
    fn encoder_counts_and_wraps() {
        let p = DcMotorParams::TRISKAR2;
        let mut m = DcMotor::new(p);
        for _ in 0..200 {
            m.step(0.005, 24.0, 0.0);
        }
        let ticks = m.encoder_ticks();
        let expect = m.wheel_angle_rad() / std::f64::consts::TAU * p.counts_per_wheel_rev();
        assert!((ticks as f64 - expect).abs() <= 1.0);
        assert!(
            ticks > 65_536,
            "one second at speed must wrap the counter: {ticks}"
        );
        assert_eq!(m.encoder_count(), (ticks & 0xFFFF) as u16);
        // Reverse: negative positions wrap downwards.
        let mut r = DcMotor::new(p);
        r.step(0.01, -24.0, 0.0);
        assert!(r.encoder_ticks() < 0);
        assert_eq!(
            r.encoder_count(),
            r.encoder_ticks().rem_euclid(65_536) as u16
        );
    }

    #[test]
    fn bad_inputs_leave_state_unchanged() {
        let mut m = DcMotor::new(DcMotorParams::TRISKAR2);
        m.step(0.005, 12.0, 0.0);
        let before = m.clone();
        m.step(0.005, f64::NAN, 0.0);
        m.step(-1.0, 12.0, 0.0);
        m.step(0.0, 12.0, 0.0);
        assert_eq!(m, before);
    }
}
