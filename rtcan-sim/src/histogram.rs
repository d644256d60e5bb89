//! Bounded summaries of unbounded streams: a uniform sample for plots (`Reservoir`) and
//! a latency distribution with exact count, sum and maximum and quantiles from a
//! log-linear histogram (`LatencyHist`).
use rtcan_core::Nanos;

/// Samples kept for a plot: a uniform reservoir of at most `RESERVOIR` values
/// (deterministic, so the same run draws the same plot).
pub const RESERVOIR: usize = 4096;

/// A bounded uniform sample of a stream (Vitter's algorithm R, xorshift draws).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Reservoir<T> {
    /// The kept values.
    pub values: Vec<T>,
    seen: u64,
    rng: u64,
}

impl<T: Copy> Reservoir<T> {
    /// Offers one value.
    pub fn push(&mut self, v: T) {
        self.seen += 1;
        if self.values.len() < RESERVOIR {
            self.values.push(v);
            return;
        }
        if self.rng == 0 {
            self.rng = 0x9E37_79B9_7F4A_7C15;
        }
        self.rng ^= self.rng << 13;
        self.rng ^= self.rng >> 7;
        self.rng ^= self.rng << 17;
        let k = self.rng % self.seen;
        if let Some(slot) = self.values.get_mut(k as usize) {
            *slot = v;
        }
    }
}

/// Sub-buckets per power of two of `LatencyHist` (relative error below 1/2^SUB_BITS).
const SUB_BITS: u32 = 8;
const SUB: usize = 1 << SUB_BITS;
/// Largest shift: values up to 2^48 ns (3 days) have their own bucket.
const MAX_SHIFT: u32 = 48 - SUB_BITS - 1;
const BUCKETS: usize = SUB * (MAX_SHIFT as usize + 2);

/// Latency distribution in fixed memory: exact count, sum and max; quantiles from a
/// log-linear histogram (exact below 512 ns, else within 0.4 %); a bounded sample for
/// plots.
#[derive(Clone, Debug, PartialEq)]
pub struct LatencyHist {
    /// Values recorded.
    pub n: u64,
    /// Their sum, ns.
    pub sum: u128,
    /// Largest, ns.
    pub max: Nanos,
    buckets: Vec<u64>,
    /// Sample for plots.
    pub sample: Reservoir<Nanos>,
}

impl Default for LatencyHist {
    fn default() -> Self {
        LatencyHist {
            n: 0,
            sum: 0,
            max: 0,
            buckets: vec![0; BUCKETS],
            sample: Reservoir::default(),
        }
    }
}

/// Values below 2·SUB have a bucket each; above, SUB buckets per power of two.
fn bucket_of(v: Nanos) -> usize {
    if v < 2 * SUB as Nanos {
        return v as usize;
    }
    let bits = 64 - v.leading_zeros();
    let shift = (bits - SUB_BITS - 1).min(MAX_SHIFT);
    let sub = ((v >> shift) as usize).min(2 * SUB - 1) - SUB;
    SUB * (shift as usize + 1) + sub
}

/// Smallest value of bucket `b`.
fn bucket_floor(b: usize) -> Nanos {
    if b < 2 * SUB {
        return b as Nanos;
    }
    let shift = (b / SUB - 1) as u32;
    ((b % SUB + SUB) as Nanos) << shift
}

impl LatencyHist {
    /// Records one value.
    pub fn push(&mut self, v: Nanos) {
        self.n += 1;
        self.sum += u128::from(v);
        self.max = self.max.max(v);
        if let Some(c) = self.buckets.get_mut(bucket_of(v)) {
            *c += 1;
        }
        self.sample.push(v);
    }

    /// Mean, ns.
    pub fn mean(&self) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            self.sum as f64 / self.n as f64
        }
    }

    /// Percentile `p` (0..=100), ns: the nearest-rank value, to the histogram's
    /// resolution (never above the maximum).
    pub fn percentile(&self, p: f64) -> Nanos {
        if self.n == 0 {
            return 0;
        }
        let rank = ((p / 100.0) * (self.n - 1) as f64).round() as u64;
        let mut seen = 0;
        for (b, &c) in self.buckets.iter().enumerate() {
            seen += c;
            if seen > rank {
                let lo = bucket_floor(b);
                let hi = bucket_floor(b + 1).saturating_sub(1);
                return (lo + (hi - lo) / 2).min(self.max);
            }
        }
        self.max
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn histogram_quantiles_are_within_half_a_percent() {
        let mut h = LatencyHist::default();
        for v in 1..=100_000u64 {
            h.push(v * 97);
        }
        assert_eq!(h.n, 100_000);
        assert_eq!(h.max, 9_700_000);
        let exact = 95_000.0 * 97.0;
        let p95 = h.percentile(95.0) as f64;
        assert!((p95 - exact).abs() / exact < 0.005, "{p95} vs {exact}");
        assert_eq!(h.percentile(100.0), 9_700_000);
        for v in [
            0u64,
            1,
            255,
            256,
            257,
            1 << 20,
            (1 << 40) + 12345,
            u64::MAX / 4,
        ] {
            let b = bucket_of(v);
            assert!(bucket_floor(b) <= v, "{v}");
            assert!(v < bucket_floor(b + 1) || b + 1 >= BUCKETS, "{v}");
        }
        assert!(h.sample.values.len() <= RESERVOIR);
    }
}
