//! Proximity node: four Sharp IR rangers → filtered distances and obstacle flags.

use crate::clamp;

/// Rangers on the proximity module, in [`crate::SENSOR_DIRECTIONS`] order
/// (front, left, back, right).
pub const SENSOR_COUNT: usize = 4;

/// Filter and threshold settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProximityConfig {
    /// Readings are clamped into `min_range_m..=max_range_m` (the ranger's valid band;
    /// "nothing in range" reads as the maximum).
    pub min_range_m: f32,
    pub max_range_m: f32,
    /// Weight of a new (median-filtered) sample in the exponential moving average.
    pub ema_alpha: f32,
    /// Obstacle flag goes up below `near_m` and down only above `clear_m`
    /// (`clear_m > near_m`), so a reading hovering at the threshold does not chatter.
    pub near_m: f32,
    pub clear_m: f32,
}

impl ProximityConfig {
    /// Sharp GP2Y0A21-class rangers (0.10–0.80 m).
    pub const TRISKAR2: Self = Self {
        min_range_m: 0.10,
        max_range_m: 0.80,
        ema_alpha: 0.5,
        near_m: 0.30,
        clear_m: 0.35,
    };
}

/// One step's result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProximityOutput {
    /// Filtered distance per sensor, m (the maximum range until a first valid sample).
    pub distance_m: [f32; SENSOR_COUNT],
    /// Obstacle flag per sensor (with hysteresis).
    pub obstacle: [bool; SENSOR_COUNT],
}

impl ProximityOutput {
    pub fn any_obstacle(&self) -> bool {
        self.obstacle.iter().any(|&o| o)
    }

    /// Distances in whole millimetres, as robot.toml's `Proximity.range_mm`.
    pub fn range_mm(&self) -> [u16; SENSOR_COUNT] {
        self.distance_m.map(m_to_mm)
    }
}

/// Metres → millimetres, rounded; saturates at 0 and `u16::MAX` (NaN gives 0).
pub fn m_to_mm(m: f32) -> u16 {
    // `as` from float saturates and maps NaN to 0; +0.5 rounds the positive range.
    (m * 1000.0 + 0.5) as u16
}

/// Millimetres → metres (for a subscriber of `Proximity.range_mm`).
pub fn mm_to_m(range_mm: [u16; SENSOR_COUNT]) -> [f32; SENSOR_COUNT] {
    range_mm.map(|mm| f32::from(mm) * 1e-3)
}

/// Median-of-three then EMA, per sensor: the median removes the single-sample spikes IR
/// rangers produce on edges and shiny surfaces, the EMA smooths the rest.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RangeFilter {
    window: [f32; 3],
    len: usize,
    next: usize,
    ema: Option<f32>,
    near: bool,
}

impl RangeFilter {
    const EMPTY: Self = Self {
        window: [0.0; 3],
        len: 0,
        next: 0,
        ema: None,
        near: false,
    };

    fn push(&mut self, sample: f32, cfg: &ProximityConfig) -> f32 {
        if sample.is_finite() {
            let clamped = clamp(sample, cfg.min_range_m, cfg.max_range_m);
            if let Some(slot) = self.window.get_mut(self.next) {
                *slot = clamped;
            }
            self.next = (self.next + 1) % self.window.len();
            self.len = (self.len + 1).min(self.window.len());
            let median = self.median();
            let ema = match self.ema {
                None => median,
                Some(prev) => prev + cfg.ema_alpha * (median - prev),
            };
            self.ema = Some(ema);
        }
        // A non-finite sample (sensor fault) is skipped: the last estimate holds.
        let d = self.ema.unwrap_or(cfg.max_range_m);
        if d < cfg.near_m {
            self.near = true;
        } else if d > cfg.clear_m {
            self.near = false;
        }
        d
    }

    fn median(&self) -> f32 {
        let [a, b, c] = self.window;
        match self.len {
            0 | 1 => a,
            // Two samples so far: their mean (the median of an even window).
            2 => 0.5 * (a + b),
            _ => a.max(b).min(a.min(b).max(c)),
        }
    }
}

/// The proximity node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProximityNode {
    config: ProximityConfig,
    filters: [RangeFilter; SENSOR_COUNT],
}

impl ProximityNode {
    pub const fn new(config: ProximityConfig) -> Self {
        Self {
            config,
            filters: [RangeFilter::EMPTY; SENSOR_COUNT],
        }
    }

    /// Feed one raw reading (m) per sensor.
    pub fn step(&mut self, raw_m: [f32; SENSOR_COUNT]) -> ProximityOutput {
        let mut out = ProximityOutput {
            distance_m: [self.config.max_range_m; SENSOR_COUNT],
            obstacle: [false; SENSOR_COUNT],
        };
        for (((f, raw), d), o) in self
            .filters
            .iter_mut()
            .zip(raw_m)
            .zip(out.distance_m.iter_mut())
            .zip(out.obstacle.iter_mut())
        {
            *d = f.push(raw, &self.config);
            *o = f.near;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CFG: ProximityConfig = ProximityConfig::TRISKAR2;

    #[test]
    fn millimetre_conversions_round_and_saturate() {
        assert_eq!(m_to_mm(0.2996), 300);
        assert_eq!(m_to_mm(-1.0), 0);
        assert_eq!(m_to_mm(f32::NAN), 0);
        assert_eq!(m_to_mm(100.0), u16::MAX);
        assert_eq!(mm_to_m([0, 250, 800, 1000]), [0.0, 0.25, 0.8, 1.0]);
        let mut n = ProximityNode::new(CFG);
        assert_eq!(
            n.step([0.5, 2.0, 0.01, 0.2]).range_mm(),
            [500, 800, 100, 200]
        );
    }

    #[test]
    fn first_sample_passes_through_clamped() {
        let mut n = ProximityNode::new(CFG);
        let out = n.step([0.5, 2.0, 0.01, 0.2]);
        assert_eq!(out.distance_m, [0.5, 0.8, 0.1, 0.2]);
        assert_eq!(out.obstacle, [false, false, true, true]);
    }

    #[test]
    fn median_rejects_a_single_spike() {
        let mut n = ProximityNode::new(CFG);
        n.step([0.5; 4]);
        n.step([0.5; 4]);
        // One-sample spike to 0.1 m on the front sensor: median of (0.5, 0.5, 0.1) = 0.5.
        let out = n.step([0.1, 0.5, 0.5, 0.5]);
        assert_eq!(out.distance_m[0], 0.5);
        assert!(!out.obstacle[0]);
    }

    #[test]
    fn ema_converges_to_a_step() {
        let mut n = ProximityNode::new(CFG);
        n.step([0.6; 4]);
        // 0.6 then 0.4s: medians 0.5 (2-sample mean), 0.4, 0.4...; EMA α=0.5:
        // 0.6 → 0.55 → 0.475 → 0.4375.
        let expect = [0.55, 0.475, 0.4375];
        for e in expect {
            let out = n.step([0.4; 4]);
            assert!(
                (out.distance_m[1] - e).abs() < 1e-6,
                "{} vs {e}",
                out.distance_m[1]
            );
        }
    }

    #[test]
    fn hysteresis_between_near_and_clear() {
        let cfg = ProximityConfig {
            ema_alpha: 1.0,
            ..CFG
        };
        let mut n = ProximityNode::new(cfg);
        let mut feed = |d: f32| {
            // Three equal samples so the median is exactly d.
            n.step([d; 4]);
            n.step([d; 4]);
            n.step([d; 4]).obstacle[0]
        };
        assert!(!feed(0.32)); // between thresholds, starting clear: stays clear
        assert!(feed(0.29)); // below near: set
        assert!(feed(0.34)); // between: stays set
        assert!(feed(0.35)); // at clear: still set (must be above)
        assert!(!feed(0.36)); // above clear: cleared
        assert!(!feed(0.31)); // between: stays clear
    }

    #[test]
    fn non_finite_sample_holds_the_estimate() {
        let mut n = ProximityNode::new(CFG);
        n.step([0.25; 4]);
        let out = n.step([f32::NAN, 0.25, 0.25, 0.25]);
        assert_eq!(out.distance_m[0], 0.25);
        assert!(out.obstacle[0]);
        // Before any valid sample a faulty sensor reads as max range, no obstacle.
        let mut fresh = ProximityNode::new(CFG);
        let out = fresh.step([f32::NAN; 4]);
        assert_eq!(out.distance_m, [0.8; 4]);
        assert!(!out.any_obstacle());
    }
}
