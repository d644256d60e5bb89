//! Battery monitor node (PSU module): voltage and current → charge estimate and a
//! low-battery flag.

use crate::clamp;
use crate::step_clock::StepClock;
use crate::Nanos;

/// Battery model and thresholds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatteryConfig {
    /// Open-circuit voltage at 0 % and 100 %; the percentage is linear in between.
    pub empty_v: f32,
    pub full_v: f32,
    /// Terminal voltage sags by `I·R` under load; adding it back estimates the
    /// open-circuit voltage, so accelerating does not read as a flat battery.
    pub internal_resistance_ohm: f32,
    /// Low flag goes up below `low_on_pct` and down only above `low_off_pct`.
    pub low_on_pct: f32,
    pub low_off_pct: f32,
    /// EMA weight of a new open-circuit estimate.
    pub ema_alpha: f32,
    /// Nominal sample period (first step integrates charge over it).
    pub period_ns: Nanos,
}

impl BatteryConfig {
    /// Triskar2's 24 V lead-acid pack (2 × 12 V): 21.0 V empty, 25.4 V full.
    pub const TRISKAR2: Self = Self {
        empty_v: 21.0,
        full_v: 25.4,
        internal_resistance_ohm: 0.05,
        low_on_pct: 20.0,
        low_off_pct: 25.0,
        ema_alpha: 0.2,
        period_ns: 100_000_000,
    };
}

/// What the battery node publishes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatteryStatus {
    /// Filtered open-circuit voltage estimate.
    pub voltage_v: f32,
    pub current_a: f32,
    /// 0.0..=100.0
    pub percent: f32,
    pub low: bool,
    /// Charge drawn since start, mAh (negative while charging).
    pub consumed_mah: f32,
}

impl BatteryStatus {
    /// robot.toml `Battery.mv`: the filtered open-circuit estimate, mV (saturating).
    pub fn mv(&self) -> u16 {
        (self.voltage_v * 1000.0 + 0.5) as u16
    }

    /// robot.toml `Battery.ma`: the last current, mA (saturating, rounded to nearest).
    pub fn ma(&self) -> i16 {
        libm::roundf(self.current_a * 1000.0) as i16
    }

    /// robot.toml `Battery.pct`: whole percent, rounded to nearest.
    pub fn pct(&self) -> u8 {
        libm::roundf(self.percent) as u8
    }
}

/// The battery monitor node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatteryNode {
    config: BatteryConfig,
    clock: StepClock,
    ocv: Option<f32>,
    low: bool,
    consumed_mah: f32,
    current_a: f32,
}

impl BatteryNode {
    pub const fn new(config: BatteryConfig) -> Self {
        Self {
            config,
            clock: StepClock::new(config.period_ns, 10 * config.period_ns),
            ocv: None,
            low: false,
            consumed_mah: 0.0,
            current_a: 0.0,
        }
    }

    /// One measurement of terminal voltage (V) and discharge current (A, positive out of
    /// the battery). A non-finite measurement is skipped (status unchanged).
    pub fn step(&mut self, now_ns: Nanos, voltage_v: f32, current_a: f32) -> BatteryStatus {
        let dt_s = self.clock.dt_s(now_ns);
        if voltage_v.is_finite() && current_a.is_finite() {
            let c = &self.config;
            let estimate = voltage_v + current_a * c.internal_resistance_ohm;
            let ocv = match self.ocv {
                None => estimate,
                Some(prev) => prev + c.ema_alpha * (estimate - prev),
            };
            self.ocv = Some(ocv);
            self.current_a = current_a;
            self.consumed_mah += current_a * dt_s * (1000.0 / 3600.0);
            let pct = self.percent_of(ocv);
            if pct < c.low_on_pct {
                self.low = true;
            } else if pct > c.low_off_pct {
                self.low = false;
            }
        }
        self.status()
    }

    pub fn status(&self) -> BatteryStatus {
        let v = self.ocv.unwrap_or(0.0);
        BatteryStatus {
            voltage_v: v,
            current_a: self.current_a,
            percent: if self.ocv.is_some() {
                self.percent_of(v)
            } else {
                0.0
            },
            low: self.low,
            consumed_mah: self.consumed_mah,
        }
    }

    fn percent_of(&self, ocv: f32) -> f32 {
        let c = &self.config;
        let span = c.full_v - c.empty_v;
        if span <= 0.0 {
            return 0.0;
        }
        clamp((ocv - c.empty_v) / span * 100.0, 0.0, 100.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS100: Nanos = 100_000_000;

    fn exact() -> BatteryConfig {
        BatteryConfig {
            ema_alpha: 1.0,
            ..BatteryConfig::TRISKAR2
        }
    }

    #[test]
    fn percentage_is_linear_and_clamped() {
        let mut b = BatteryNode::new(exact());
        assert!((b.step(0, 23.2, 0.0).percent - 50.0).abs() < 1e-4);
        assert_eq!(b.step(MS100, 26.0, 0.0).percent, 100.0);
        assert_eq!(b.step(2 * MS100, 20.0, 0.0).percent, 0.0);
    }

    #[test]
    fn load_sag_is_compensated() {
        let mut b = BatteryNode::new(exact());
        // 20 A through 0.05 Ω sags 1 V: 22.2 V terminal is 23.2 V open-circuit.
        let s = b.step(0, 22.2, 20.0);
        assert!((s.voltage_v - 23.2).abs() < 1e-5 && (s.percent - 50.0).abs() < 1e-3);
    }

    #[test]
    fn low_flag_hysteresis() {
        let mut b = BatteryNode::new(exact());
        // Percent → voltage: v = 21.0 + 0.044 * pct.
        let v = |pct: f32| 21.0 + 0.044 * pct;
        let mut t = 0;
        let mut at = |pct: f32| {
            t += MS100;
            b.step(t, v(pct), 0.0).low
        };
        assert!(!at(22.0));
        assert!(at(19.0)); // below 20: low
        assert!(at(24.0)); // recovers a bit (load removed): still low
        assert!(!at(26.0)); // above 25: cleared
        assert!(!at(21.0)); // between: stays clear
        assert!(at(10.0));
    }

    #[test]
    fn charge_is_integrated() {
        let mut b = BatteryNode::new(exact());
        // 36 A for 10 s (first step uses the nominal 100 ms) = 100 mAh.
        for k in 0..100 {
            b.step(k * MS100, 24.0, 36.0);
        }
        assert!(
            (b.status().consumed_mah - 100.0).abs() < 1e-2,
            "{:?}",
            b.status()
        );
    }

    #[test]
    fn ema_smooths_and_faults_are_skipped() {
        let mut b = BatteryNode::new(BatteryConfig::TRISKAR2);
        b.step(0, 24.0, 0.0);
        let s = b.step(MS100, 23.0, 0.0);
        assert!((s.voltage_v - 23.8).abs() < 1e-5);
        let s2 = b.step(2 * MS100, f32::NAN, 1.0);
        assert_eq!(s2, s);
    }

    #[test]
    fn wire_fields() {
        let mut b = BatteryNode::new(exact());
        let s = b.step(0, 22.2, 20.0);
        assert_eq!((s.mv(), s.ma(), s.pct()), (23_200, 20_000, 50));
        let s = b.step(MS100, 24.0, -40.0); // regenerating beyond i16 mA
        assert_eq!(s.ma(), i16::MIN);
    }

    #[test]
    fn no_sample_yet_reads_empty_but_not_low() {
        let b = BatteryNode::new(BatteryConfig::TRISKAR2);
        let s = b.status();
        assert_eq!((s.percent, s.low), (0.0, false));
    }
}
