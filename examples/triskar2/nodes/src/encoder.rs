//! Wheel speed from a quadrature encoder counter.

use crate::Nanos;

/// Converts successive readings of a free-running 16-bit encoder counter (an STM32 timer
/// in encoder mode, or the simulator's encoder) into wheel speed.
///
/// The counter wraps; the difference between two readings is taken modulo 2^16 and read
/// as signed, which is exact as long as the wheel turns less than 32767 counts between
/// samples (at 200 Hz and 4096 counts per wheel revolution: 1600 rad/s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EncoderSpeed {
    counts_per_wheel_rev: f32,
    last: Option<(Nanos, u16)>,
    ticks: i32,
}

impl EncoderSpeed {
    /// `counts_per_wheel_rev`: counter increments per wheel revolution (encoder CPR ×
    /// quadrature factor × gear ratio).
    pub const fn new(counts_per_wheel_rev: f32) -> Self {
        Self {
            counts_per_wheel_rev,
            last: None,
            ticks: 0,
        }
    }

    /// Counts accumulated since the first reading (robot.toml `Encoder.ticks`); wraps
    /// like the 32-bit counter it models (after 2^31 counts: hours at full speed).
    pub const fn ticks(&self) -> i32 {
        self.ticks
    }

    /// Wheel speed in rad/s over the interval since the previous reading, or `None` on
    /// the first reading or when no time has passed.
    pub fn step(&mut self, now_ns: Nanos, count: u16) -> Option<f32> {
        let previous = self.last.replace((now_ns, count));
        let (then_ns, then_count) = previous?;
        let dt_ns = now_ns.checked_sub(then_ns).filter(|&dt| dt > 0)?;
        let delta = count.wrapping_sub(then_count) as i16;
        self.ticks = self.ticks.wrapping_add(i32::from(delta));
        let revs = f32::from(delta) / self.counts_per_wheel_rev;
        Some(revs * core::f32::consts::TAU / (dt_ns as f32 * 1e-9))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_reading_has_no_speed() {
        let mut e = EncoderSpeed::new(1000.0);
        assert_eq!(e.step(0, 123), None);
    }

    #[test]
    fn quarter_turn_in_5ms_is_100pi_rad_s() {
        let mut e = EncoderSpeed::new(1000.0);
        e.step(0, 0);
        let w = e.step(5_000_000, 250).unwrap();
        assert!((w - 100.0 * core::f32::consts::PI).abs() < 1e-3, "{w}");
    }

    #[test]
    fn counter_wrap_both_directions() {
        let mut e = EncoderSpeed::new(1000.0);
        e.step(0, 65_500);
        // +100 counts across the wrap.
        let fwd = e.step(10_000_000, 64).unwrap();
        assert!(
            (fwd - 0.1 * core::f32::consts::TAU / 0.01).abs() < 1e-3,
            "{fwd}"
        );
        // -100 counts back across the wrap.
        let back = e.step(20_000_000, 65_500).unwrap();
        assert!(
            (back + 0.1 * core::f32::consts::TAU / 0.01).abs() < 1e-3,
            "{back}"
        );
    }

    #[test]
    fn repeated_timestamp_gives_none() {
        let mut e = EncoderSpeed::new(1000.0);
        e.step(7, 0);
        assert_eq!(e.step(7, 10), None);
    }
}
