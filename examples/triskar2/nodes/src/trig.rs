//! `sin` and `cos` for the odometry: short polynomials in `f32`. libm's `sinf`/`cosf`
//! reduce the argument in `f64` and pull about 4.6 KiB (range reduction plus soft-float
//! `f64`) into a motor image that has a 32 KiB budget; odometry angles are small
//! (already wrapped to ±π plus one step), so a quadrant reduction and Taylor terms up to
//! x⁷/x⁸ on ±π/4 are accurate to about 3e-7.
use core::f32::consts::FRAC_PI_2;

/// `(sin x, cos x)` for any finite `x` (accurate for |x| up to a few thousand radians;
/// odometry calls it with |x| < 4).
pub fn sin_cos(x: f32) -> (f32, f32) {
    // Nearest multiple of π/2, then r in [-π/4, π/4].
    let k = x * core::f32::consts::FRAC_2_PI;
    let q = if k >= 0.0 {
        (k + 0.5) as i32
    } else {
        (k - 0.5) as i32
    };
    let r = x - q as f32 * FRAC_PI_2;
    let r2 = r * r;
    let s = r * (1.0 - r2 / 6.0 * (1.0 - r2 / 20.0 * (1.0 - r2 / 42.0)));
    let c = 1.0 - r2 / 2.0 * (1.0 - r2 / 12.0 * (1.0 - r2 / 30.0 * (1.0 - r2 / 56.0)));
    match q.rem_euclid(4) {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_std_over_several_turns() {
        let mut worst = 0.0f32;
        let mut x = -20.0f32;
        while x <= 20.0 {
            let (s, c) = sin_cos(x);
            worst = worst.max((s - x.sin()).abs()).max((c - x.cos()).abs());
            x += 0.0007;
        }
        assert!(worst < 2e-6, "worst error {worst}");
    }

    #[test]
    fn exact_at_quadrant_points() {
        for (x, s, c) in [
            (0.0f32, 0.0f32, 1.0f32),
            (FRAC_PI_2, 1.0, 0.0),
            (-FRAC_PI_2, -1.0, 0.0),
        ] {
            let (ss, cc) = sin_cos(x);
            assert!(
                (ss - s).abs() < 1e-6 && (cc - c).abs() < 1e-6,
                "{x}: {ss} {cc}"
            );
        }
    }
}
