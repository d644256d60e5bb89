//! Start-of-frame timestamps from bxCAN's time-triggered communication mode (TTCM).
//!
//! In TTCM the controller runs a 16-bit counter that advances once per CAN bit time and
//! captures it at the sample point of each frame's SOF bit into the RX mailbox
//! (`CAN_RDTxR.TIME`). Resolution: one bit time (1 µs at 1 Mbit/s); the counter wraps
//! every 65 536 bits. The counter itself cannot be read, so its relation to the local
//! clock (`offset`: local ns at counter value 0, unwrapped) is estimated from the RX
//! interrupts: the frame-valid event that raises the interrupt happens a known number of
//! bits after SOF (from the frame's exact length), so `now - (sof + bits) * bit_ns` is an
//! upper bound of the offset, too high by the interrupt latency. The smallest bound seen
//! (minimum-latency filter, as in NTP) is kept; it may rise by the allowed drift between
//! frames so that a CAN bit clock slower than the local clock is followed.

/// Maps TTCM timestamps to local nanoseconds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SofClock {
    bit_ns: i64,
    drift_ppm: i64,
    /// Local ns at unwrapped counter value 0 (`None` until the first frame). The counter's
    /// absolute value is never needed: a whole number of wraps picked at the first frame
    /// is absorbed by the offset.
    offset: Option<i64>,
    /// Local time of the last offset update.
    updated: i64,
}

impl SofClock {
    /// Bit time `bit_ns` (a whole number of ns at every standard rate) and the bound of
    /// the drift between the local and the bus bit clock, `drift_ppm`.
    pub const fn new(bit_ns: u32, drift_ppm: u32) -> Self {
        let bit_ns = if bit_ns == 0 { 1 } else { bit_ns as i64 };
        SofClock {
            bit_ns,
            drift_ppm: drift_ppm as i64,
            offset: None,
            updated: 0,
        }
    }

    /// Local ns of the SOF of a frame with TTCM stamp `time16`, whose RX interrupt was
    /// handled at local `now`, `bits_sof_to_irq` bits after its SOF (frame length up to
    /// the frame-valid point). Also refines the offset estimate.
    pub fn sof(&mut self, time16: u16, bits_sof_to_irq: u32, now: u64) -> u64 {
        let now = now.min(i64::MAX as u64) as i64;
        let bits = bits_sof_to_irq as i64;
        let bit = self.bit_ns;
        let (sof_bits, offset) = match self.offset {
            None => {
                let sof_bits = time16 as i64;
                (sof_bits, now - (sof_bits + bits) * bit)
            }
            Some(offset) => {
                // Drift since the last update may make the stored offset too high and so
                // the estimated counter too low: unwrap against an estimate raised by it.
                let drift_ns =
                    (now - self.updated).max(0).saturating_mul(self.drift_ppm) / 1_000_000;
                let est_now = (now - offset) / bit + drift_ns / bit + 1;
                let back = (est_now as u16).wrapping_sub(time16) as i64;
                let sof_bits = est_now - back;
                let candidate = now - (sof_bits + bits) * bit;
                (sof_bits, candidate.min(offset.saturating_add(drift_ns)))
            }
        };
        self.offset = Some(offset);
        self.updated = now;
        (offset + sof_bits * bit).max(0) as u64
    }

    /// Current offset estimate (local ns at the counter value taken as 0).
    pub const fn offset(&self) -> Option<i64> {
        self.offset
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BIT: u64 = 1_000; // 1 Mbit/s

    #[test]
    fn first_frame_anchors_at_any_counter_value() {
        let mut c = SofClock::new(1_000, 100);
        // Counter at 60 000 when the first frame comes, 1 s after boot.
        assert_eq!(c.sof(60_000, 100, 1_000_000_000), 1_000_000_000 - 100_000);
        // Next frame 70 000 bits later: the counter wrapped once.
        let t16 = (60_000u32 + 70_000) as u16;
        assert_eq!(
            c.sof(t16, 100, 1_000_000_000 + 70_000_000),
            1_000_000_000 - 100_000 + 70_000_000
        );
    }

    #[test]
    fn exact_when_latency_is_zero_and_unwraps_across_many_wraps() {
        let start = 5_000_000;
        let mut c = SofClock::new(BIT as u32, 100);
        // Frames every 10 ms for 2 s (30 counter wraps), 130 bits long, zero latency.
        for k in 1..200u64 {
            let sof_bits = k * 10_000;
            let now = start + (sof_bits + 130) * BIT;
            assert_eq!(
                c.sof(sof_bits as u16, 130, now),
                start + sof_bits * BIT,
                "frame {k}"
            );
        }
    }

    #[test]
    fn latency_is_filtered_to_the_minimum() {
        let start = 0;
        let mut c = SofClock::new(BIT as u32, 0);
        let lat = [30_000u64, 7_000, 12_000, 2_000, 9_000, 25_000];
        let mut last_err = 0;
        for (k, l) in lat.iter().enumerate() {
            let sof_bits = (k as u64 + 1) * 3_000;
            let now = start + (sof_bits + 100) * BIT + l;
            let got = c.sof(sof_bits as u16, 100, now);
            last_err = got - (start + sof_bits * BIT);
        }
        // Error is the smallest latency seen so far.
        assert_eq!(last_err, 2_000);
        assert_eq!(c.offset(), Some(2_000));
    }

    #[test]
    fn follows_a_slow_bus_clock_within_the_drift_bound() {
        // Bus bit clock 50 ppm slow: counter value b happens at local b * 1000.05 ns.
        let mut c = SofClock::new(BIT as u32, 100);
        let mut worst = 0i64;
        for k in 1..2_000u64 {
            let sof_bits = k * 997; // ~1 ms apart
            let true_sof = sof_bits * BIT + sof_bits * BIT * 50 / 1_000_000;
            let now = true_sof + 120 * BIT + 1_500;
            let got = c.sof(sof_bits as u16, 120, now);
            worst = worst.max((got as i64 - true_sof as i64).abs());
        }
        // Within the 1.5 µs latency plus one bit of tracking lag.
        assert!(worst <= 2_500, "worst {worst}");
    }
}
