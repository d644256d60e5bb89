//! Battery pack: open-circuit voltage linear in state of charge, internal resistance,
//! coulomb counting.

/// Pack constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatteryParams {
    pub capacity_ah: f64,
    /// Open-circuit voltage at 0 % and 100 % state of charge.
    pub empty_v: f64,
    pub full_v: f64,
    pub internal_resistance_ohm: f64,
}

impl BatteryParams {
    /// Triskar2's 24 V, 7 Ah lead-acid pack (matches the node crate's battery monitor).
    pub const TRISKAR2: Self = Self {
        capacity_ah: 7.0,
        empty_v: 21.0,
        full_v: 25.4,
        internal_resistance_ohm: 0.05,
    };
}

/// Pack state.
#[derive(Clone, Debug, PartialEq)]
pub struct BatteryPack {
    params: BatteryParams,
    charge_ah: f64,
    current_a: f64,
}

impl BatteryPack {
    /// A pack at `soc` (0..=1).
    pub fn new(params: BatteryParams, soc: f64) -> Self {
        Self {
            params,
            charge_ah: params.capacity_ah * soc.clamp(0.0, 1.0),
            current_a: 0.0,
        }
    }

    /// Draw `current_a` (positive = discharge) for `dt_s`. Charge stays within
    /// `0..=capacity`.
    pub fn step(&mut self, dt_s: f64, current_a: f64) {
        if dt_s.is_nan() || dt_s <= 0.0 || !current_a.is_finite() {
            return;
        }
        self.current_a = current_a;
        self.charge_ah =
            (self.charge_ah - current_a * dt_s / 3600.0).clamp(0.0, self.params.capacity_ah);
    }

    /// State of charge, 0..=1.
    pub fn soc(&self) -> f64 {
        if self.params.capacity_ah > 0.0 {
            self.charge_ah / self.params.capacity_ah
        } else {
            0.0
        }
    }

    pub fn open_circuit_v(&self) -> f64 {
        let p = &self.params;
        p.empty_v + (p.full_v - p.empty_v) * self.soc()
    }

    /// Terminal voltage under the last step's current (what the PSU module measures).
    pub fn terminal_v(&self) -> f64 {
        self.open_circuit_v() - self.current_a * self.params.internal_resistance_ohm
    }

    pub fn current_a(&self) -> f64 {
        self.current_a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drains_linearly_and_sags_under_load() {
        let mut b = BatteryPack::new(BatteryParams::TRISKAR2, 1.0);
        assert_eq!(b.open_circuit_v(), 25.4);
        // 14 A for 15 min = 3.5 Ah = half the pack.
        for _ in 0..900 {
            b.step(1.0, 14.0);
        }
        assert!((b.soc() - 0.5).abs() < 1e-9, "{}", b.soc());
        assert!((b.open_circuit_v() - 23.2).abs() < 1e-9);
        assert!((b.terminal_v() - (23.2 - 14.0 * 0.05)).abs() < 1e-9);
    }

    #[test]
    fn charge_is_bounded() {
        let mut b = BatteryPack::new(BatteryParams::TRISKAR2, 0.01);
        b.step(3600.0, 10.0);
        assert_eq!(b.soc(), 0.0);
        assert_eq!(b.open_circuit_v(), 21.0);
        b.step(3600.0, -100.0);
        assert_eq!(b.soc(), 1.0);
    }
}
