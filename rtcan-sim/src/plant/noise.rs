//! Noise drawn from a caller-owned generator: plants hold no random state, so a run is
//! reproduced by reseeding the caller's PRNG.

/// A source of uniformly random 64-bit words. Implemented for every `FnMut() -> u64`, so
/// the simulator passes `&mut || rng.next_u64()` and tests pass any seeded closure.
pub trait NoiseSource {
    fn next_u64(&mut self) -> u64;

    /// Uniform in (0, 1]: never 0, so it is safe under a logarithm.
    fn unit_open(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 1.0) * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal sample (Box–Muller; one of the pair is discarded to stay
    /// stateless).
    fn gaussian(&mut self) -> f64 {
        let u1 = self.unit_open();
        let u2 = self.unit_open();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

impl<F: FnMut() -> u64> NoiseSource for F {
    fn next_u64(&mut self) -> u64 {
        self()
    }
}

/// SplitMix64 step, for tests and callers without a generator of their own.
pub fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_has_unit_variance_and_zero_mean() {
        let mut s = 42_u64;
        let mut src = || splitmix64(&mut s);
        let n = 20_000;
        let xs: Vec<f64> = (0..n).map(|_| src.gaussian()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.03, "{mean}");
        assert!((var - 1.0).abs() < 0.05, "{var}");
    }

    #[test]
    fn unit_open_is_in_range_and_reproducible() {
        let (mut a, mut b) = (7_u64, 7_u64);
        for _ in 0..1000 {
            let x = (|| splitmix64(&mut a)).unit_open();
            assert!(x > 0.0 && x <= 1.0);
            assert_eq!(x, (|| splitmix64(&mut b)).unit_open());
        }
    }
}
