//! Per-node clocks. The simulator runs on global time; each node's engine only ever sees
//! its local time `local(g) = g + offset + g * drift_ppb / 1e9`, as a crystal with an
//! offset and a constant frequency error would give it.
use rtcan_core::Nanos;

/// A node's clock relative to global (bus-physical) time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NodeClock {
    /// Local time at global time 0, ns (non-negative so local time never underflows).
    pub offset_ns: u64,
    /// Frequency error in parts per billion (+ = runs fast), |drift| < 1e9.
    pub drift_ppb: i64,
}

const GIGA: i128 = 1_000_000_000;

impl NodeClock {
    /// Clock with `offset_ns` and a drift in ppm (e.g. 50.0 for a +50 ppm crystal).
    pub fn new(offset_ns: u64, drift_ppm: f64) -> Self {
        NodeClock {
            offset_ns,
            drift_ppb: (drift_ppm * 1000.0).round() as i64,
        }
    }

    /// Local time at global time `g` (monotonic non-decreasing in `g`).
    pub fn local(&self, g: Nanos) -> Nanos {
        if self.drift_ppb == 0 {
            return g.saturating_add(self.offset_ns);
        }
        // Fast path in i64 (no 128-bit division) while the product fits: hours of
        // simulated time at realistic drifts.
        if let (Ok(gi), Ok(off)) = (i64::try_from(g), i64::try_from(self.offset_ns)) {
            if let Some(p) = gi.checked_mul(self.drift_ppb) {
                let l = gi
                    .saturating_add(off)
                    .saturating_add(p.div_euclid(1_000_000_000));
                return l.max(0) as u64;
            }
        }
        let g = i128::from(g);
        let l = g + i128::from(self.offset_ns) + (g * i128::from(self.drift_ppb)).div_euclid(GIGA);
        l.clamp(0, i128::from(u64::MAX)) as u64
    }

    /// Earliest global time at which the local clock reads at least `l`.
    pub fn global_at(&self, l: Nanos) -> Nanos {
        if self.drift_ppb == 0 {
            // local = g + offset (saturating): the inverse is a subtraction.
            return l.saturating_sub(self.offset_ns);
        }
        let rel = i128::from(l) - i128::from(self.offset_ns);
        if rel <= 0 {
            return 0;
        }
        // First guess g = rel * 1e9 / (1e9 + drift) = rel - rel * drift / (1e9 + drift):
        // the correction term in f64 (a 128-bit or even 64-bit integer division costs
        // more than the rest together; the term is at most rel * 1e-3 for |drift| below
        // 1000 ppm, so its rounding error is far below 1 ns). Any guess within a few ns
        // settles to the same exact result below.
        let rate = GIGA + i128::from(self.drift_ppb);
        let guess = i64::try_from(rel)
            .ok()
            .filter(|_| rate > 0)
            .map(|r| r.saturating_sub((r as f64 * self.drift_ppb as f64 / rate as f64) as i64));
        let mut g = match guess {
            Some(g) => g.max(0) as u64,
            None => (rel * GIGA / rate.max(1)).max(0) as u64,
        };
        // The integer inverse is off by at most a couple of ns; settle it exactly.
        while g > 0 && self.local(g - 1) >= l {
            g -= 1;
        }
        while self.local(g) < l {
            g += 1;
        }
        g
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ideal_clock_is_identity_plus_offset() {
        let c = NodeClock::new(1_000, 0.0);
        assert_eq!(c.local(0), 1_000);
        assert_eq!(c.local(5_000_000), 5_001_000);
        assert_eq!(c.global_at(5_001_000), 5_000_000);
        assert_eq!(c.global_at(10), 0);
    }

    #[test]
    fn drift_in_ppm() {
        let fast = NodeClock::new(0, 100.0);
        // +100 ppm: 1 s of global time reads 1 s + 100 us.
        assert_eq!(fast.local(1_000_000_000), 1_000_100_000);
        let slow = NodeClock::new(0, -50.0);
        assert_eq!(slow.local(1_000_000_000), 999_950_000);
    }

    #[test]
    fn global_at_is_the_exact_inverse_on_random_times() {
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        for k in 0..20_000u64 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let ppm = ((x >> 40) % 2001) as f64 - 1000.0;
            let clock = NodeClock::new((x >> 20) % 10_000_000, ppm);
            // Up to about 3 hours, and now and then up to 300 years.
            let l = if k % 100 == 0 {
                x >> 1
            } else {
                x % 10_000_000_000_000
            };
            let g = clock.global_at(l);
            assert!(clock.local(g) >= l, "{clock:?} {l}");
            assert!(g == 0 || clock.local(g - 1) < l, "{clock:?} {l}");
        }
    }

    #[test]
    fn global_at_is_the_exact_inverse() {
        for clock in [
            NodeClock::new(123, 37.5),
            NodeClock::new(0, -81.0),
            NodeClock::new(9, 0.0),
            NodeClock::new(5_000, 0.0),
            NodeClock::new(77, 500.0),
        ] {
            // Below the offset, short and long spans, and one past the 64-bit fast path
            // of the first guess (rel * drift overflows i64: about 12 days here).
            for l in [
                3u64,
                200,
                1_000_003,
                987_654_321,
                5_000_000_017,
                10u64.pow(15),
            ] {
                let g = clock.global_at(l);
                assert!(clock.local(g) >= l);
                assert!(g == 0 || clock.local(g - 1) < l);
            }
        }
    }
}
