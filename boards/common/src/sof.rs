//! Start-of-frame timestamps from bxCAN's time-triggered communication mode (TTCM).
//!
//! In TTCM the controller runs a 16-bit counter that advances once per CAN bit time and
//! captures it at the sample point of each frame's SOF bit into the RX mailbox
//! (`CAN_RDTxR.TIME`). Resolution: one bit time (1 µs at 1 Mbit/s); the counter wraps
//! every 65 536 bits. The counter itself cannot be read, so its relation to the local
//! clock (`offset`: local ns at counter value 0, unwrapped) is estimated from the RX
//! interrupts: the frame-valid event that raises the interrupt happens at least
//! `valid_bits_min(dlc)` bits after SOF (the frame without stuff bits), so
//! `now - (sof + valid_bits_min) * bit_ns` is an upper bound of the offset, too high by
//! the interrupt latency plus the frame's stuff bits. The smallest bound seen
//! (minimum-latency filter, as in NTP) is kept; it may rise by the allowed drift between
//! frames so that a CAN bit clock slower than the local clock is followed.
//!
//! Widening the 16-bit stamp needs bounds, not the exact frame length: the stamp is
//! unwrapped to the value *nearest* to the SOF estimated from the current offset, which
//! is right as long as that estimate is within ±32 767 bits (±32.7 ms at 1 Mbit/s) of the
//! truth. The estimate is low by the offset's error (the best latency seen so far, e.g.
//! the first frame's, which may have waited in the FIFO while the firmware started) and
//! high by this frame's latency and stuff bits; both are far below 32 ms. (Unwrapping to
//! the latest value not after the estimated counter, as before, failed as soon as the
//! first frame's latency exceeded a later frame's length: 65 536 bits early, for ever.)
//! No CRC or bit-stuffing computation runs on the receive path.

/// Bits from a frame's SOF to its frame-valid point (the last-but-one EOF bit, where the
/// RX interrupt is raised) of an extended data frame with `dlc` data bytes, without stuff
/// bits: SOF 1, arbitration 32, control 6, data 8·dlc, CRC 15, CRC delimiter 1, ACK 2,
/// EOF 6. A lower bound of the real distance (which adds 0 … 24 stuff bits).
pub const fn valid_bits_min(dlc: u8) -> u32 {
    let dlc = if dlc > 8 { 8 } else { dlc };
    63 + 8 * dlc as u32
}

/// Maps TTCM timestamps to local nanoseconds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SofClock {
    bit_ns: i64,
    /// 2^32 / bit_ns, rounded up: ns → bits by multiply and shift (a 64-bit division is a
    /// library call of a few hundred instructions on the Cortex-M3).
    inv_bit_q32: u32,
    /// Drift bound, ppm × 2^20 / 10^6, rounded up.
    drift_q20: u32,
    /// Local ns at unwrapped counter value 0 (`None` until the first frame). The counter's
    /// absolute value is never needed: a whole number of wraps picked at the first frame
    /// is absorbed by the offset.
    offset: Option<i64>,
    /// Local time of the last offset update.
    updated: i64,
    /// Estimated counter value (unwrapped) at `updated`, and its local time under the
    /// current offset (`offset + anchor_bits * bit_ns`, kept to avoid the multiply).
    anchor_bits: u32,
    anchor_local: i64,
    /// `bit_ns` in 4 … 2^31 − 1 (every CAN rate): frames close together take the
    /// 32-bit `sof_near`.
    narrow: bool,
}

/// Gaps between frames below this many ns take the 32-bit path (multiply and shift);
/// longer silences (over 2 s) take the 64-bit one with a division.
const FAST_GAP_NS: i64 = 1 << 31;

impl SofClock {
    /// Bit time `bit_ns` (a whole number of ns at every standard rate) and the bound of
    /// the drift between the local and the bus bit clock, `drift_ppm`.
    pub const fn new(bit_ns: u32, drift_ppm: u32) -> Self {
        let bit_ns = if bit_ns == 0 { 1 } else { bit_ns as u64 };
        SofClock {
            bit_ns: bit_ns as i64,
            inv_bit_q32: {
                let inv = (1u64 << 32).div_ceil(bit_ns);
                // 1 ns bits (not a CAN rate) round to 2^32 - 1: off by one bit, harmless.
                if inv > u32::MAX as u64 {
                    u32::MAX
                } else {
                    inv as u32
                }
            },
            drift_q20: {
                let q = ((drift_ppm as u64) << 20).div_ceil(1_000_000);
                if q > u32::MAX as u64 {
                    u32::MAX
                } else {
                    q as u32
                }
            },
            offset: None,
            updated: 0,
            anchor_bits: 0,
            anchor_local: 0,
            narrow: bit_ns >= 4 && bit_ns <= i32::MAX as u64,
        }
    }

    /// Local ns of the SOF of a frame with TTCM stamp `time16`, whose RX interrupt was
    /// handled at local `now`, at least `min_bits_sof_to_irq` bits after its SOF (use
    /// `valid_bits_min(dlc)`). Also refines the offset estimate.
    pub fn sof(&mut self, time16: u16, min_bits_sof_to_irq: u32, now: u64) -> u64 {
        let now = now.min(i64::MAX as u64 >> 1) as i64;
        let bits = (min_bits_sof_to_irq & 0xFFFF) as i64;
        let bit = self.bit_ns;
        let Some(offset) = self.offset else {
            // First frame: anchor the counter at this stamp (its wraps are absorbed).
            self.offset = Some(now - (time16 as i64 + bits) * bit);
            self.updated = now;
            self.anchor_bits = time16 as u32 + bits as u32;
            self.anchor_local = now;
            return (now - bits * bit).max(0) as u64;
        };
        // Drift since the last update may make the offset too high and so the estimated
        // counter too low: estimate against an offset lowered by the drift bound. The
        // estimate only needs to be within ±32 767 bits: a bit of rounding is harmless.
        let elapsed = now - self.updated;
        if self.narrow && (0..FAST_GAP_NS).contains(&elapsed) {
            return self.sof_near(time16, bits as u32, now, elapsed as u32, offset);
        }
        let (drift, gap_bits) = if (0..FAST_GAP_NS).contains(&elapsed) {
            let e = elapsed as u32;
            let drift = ((e as u64 * self.drift_q20 as u64 + (1 << 20) - 1) >> 20) as u32;
            let gap = e.saturating_add(drift);
            let gap_bits = (gap as u64 * self.inv_bit_q32 as u64) >> 32;
            (drift as i64, gap_bits as i64)
        } else {
            let e = elapsed.clamp(0, 1 << 40);
            let drift = (e * self.drift_q20 as i64 + (1 << 20) - 1) >> 20;
            (drift, (e + drift) / bit)
        };
        // The counter is only ever needed modulo 2^16: `anchor_bits` wraps.
        let est16 = (self.anchor_bits as i64 + gap_bits - bits) as u16;
        // Nearest value congruent to the stamp (mod 2^16), relative to the anchor.
        let rel = gap_bits - bits + time16.wrapping_sub(est16) as i16 as i64;
        let sof_local = self.anchor_local + rel * bit;
        // This frame's offset bound minus the current offset (≥ 0 unless it is better).
        let excess = now - sof_local - bits * bit;
        let d = excess.min(drift);
        self.offset = Some(offset + d);
        // New anchor: the counter at `now` per the new offset.
        let k = self.bits_in(excess - d);
        self.anchor_bits = (self.anchor_bits as i64).wrapping_add(rel + bits + k) as u32;
        self.anchor_local = sof_local + d + (bits + k) * bit;
        self.updated = now;
        (sof_local + d).max(0) as u64
    }

    /// `sof` for a frame less than 2^31 ns (2.1 s) after the last (`elapsed`), on a clock
    /// built `narrow`: the same arithmetic as the general path with 32-bit operands and
    /// 32 × 32 → 64 products (issue 10: every received frame runs this; the test
    /// `near_path_equals_the_general_path` compares both). The bounds, with `bit_ns` in
    /// 4 … 2^31 − 1 (`narrow`):
    /// - `drift` and `gap` are the general path's 32-bit values (`gap` <= 2^32 − 1);
    /// - gap_bits = gap · ceil(2^32 / bit_ns) / 2^32 < 2^30 (bit_ns >= 4);
    /// - rel = gap_bits − bits + (−2^15 … 2^15 − 1) lies in −2^17 … 2^30 + 2^15: an i32;
    /// - `excess − d` is checked against the 32-bit range like `bits_in` does.
    fn sof_near(&mut self, time16: u16, bits: u32, now: i64, e: u32, offset: i64) -> u64 {
        let bit = self.bit_ns as u32;
        let drift = ((e as u64 * self.drift_q20 as u64 + (1 << 20) - 1) >> 20) as u32;
        let gap = e.saturating_add(drift);
        let gap_bits = ((gap as u64 * self.inv_bit_q32 as u64) >> 32) as u32;
        let est16 = self.anchor_bits.wrapping_add(gap_bits).wrapping_sub(bits) as u16;
        let rel = gap_bits as i32 - bits as i32 + time16.wrapping_sub(est16) as i16 as i32;
        let sof_local = self.anchor_local + rel as i64 * bit as i64;
        let excess = now - sof_local - (bits as u64 * bit as u64) as i64;
        let d = excess.min(drift as i64);
        self.offset = Some(offset + d);
        let rest = excess - d;
        let k = if (0..FAST_GAP_NS).contains(&rest) {
            ((rest as u64 * self.inv_bit_q32 as u64) >> 32) as u32
        } else {
            // A better frame than any before by over 2 s: not on a working bus.
            return self.sof_far(rel, bits, excess, d, sof_local, now);
        };
        self.anchor_bits = self
            .anchor_bits
            .wrapping_add(rel as u32)
            .wrapping_add(bits)
            .wrapping_add(k);
        // bits + k <= 2^16 + 2^31 / 4: a u32, and the product a 32 × 32 → 64 multiply.
        self.anchor_local = sof_local + d + (bits + k) as u64 as i64 * bit as i64;
        self.updated = now;
        (sof_local + d).max(0) as u64
    }

    /// The end of `sof_near` when the new anchor is more than 2^31 ns off (the general
    /// path's arithmetic).
    #[cold]
    fn sof_far(
        &mut self,
        rel: i32,
        bits: u32,
        excess: i64,
        d: i64,
        sof_local: i64,
        now: i64,
    ) -> u64 {
        let (rel, bits, bit) = (rel as i64, bits as i64, self.bit_ns);
        let k = self.bits_in(excess - d);
        self.anchor_bits = (self.anchor_bits as i64).wrapping_add(rel + bits + k) as u32;
        self.anchor_local = sof_local + d + (bits + k) * bit;
        self.updated = now;
        (sof_local + d).max(0) as u64
    }

    /// `ns` (≥ 0) in bits, rounded down (± 1 bit).
    fn bits_in(&self, ns: i64) -> i64 {
        if (0..FAST_GAP_NS).contains(&ns) {
            ((ns as u64 * self.inv_bit_q32 as u64) >> 32) as i64
        } else {
            ns / self.bit_ns
        }
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
    /// Deterministic pseudo-random numbers (xorshift32) for the traffic below.
    struct Rng(u32);
    impl Rng {
        fn next(&mut self) -> u32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 17;
            self.0 ^= self.0 << 5;
            self.0
        }
    }

    /// Runs `queued` frames waiting in the FIFO at start (all handled at once, the first
    /// `first_latency` ns after its frame-valid point) and then 2 000 frames every
    /// ~1 ms with 0 … 24 stuff bits and 0 … 20 µs latency; the counter starts at
    /// `counter0`. Returns the worst error of the later frames beyond what their own
    /// latency and stuff bits allow (0 when correct), and checks no SOF is ever early.
    fn run(first_latency: u64, queued: u64, counter0: u64, seed: u32) -> u64 {
        let bit = BIT;
        // Local ns at (unwrapped) counter value 0: the local clock is 3 s ahead.
        let origin = 3_000_000_000u64;
        let mut c = SofClock::new(bit as u32, 200);
        let mut rng = Rng(seed);
        let mut sof_bits = counter0;
        // The queued frames: back to back, all read by the first RX interrupt.
        let mut frames = [(0u64, 0u8, 0u32); 3];
        for f in frames.iter_mut().take(queued as usize) {
            let dlc = (rng.next() % 9) as u8;
            let stuff = rng.next() % 25;
            *f = (sof_bits, dlc, stuff);
            sof_bits += (valid_bits_min(dlc) + stuff) as u64 + 4;
        }
        if queued > 0 {
            let (last_sof, dlc, stuff) = frames[queued as usize - 1];
            let now =
                origin + (last_sof + (valid_bits_min(dlc) + stuff) as u64) * bit + first_latency;
            for &(s, dlc, _) in frames.iter().take(queued as usize) {
                let got = c.sof(s as u16, valid_bits_min(dlc), now);
                // Never before the true SOF, and not later than the wait in the FIFO.
                assert!(got >= origin + s * bit, "queued frame early");
                assert!(got <= now, "queued frame after its interrupt");
            }
        }
        let mut worst_excess = 0u64;
        for _ in 0..2_000 {
            sof_bits += 900 + (rng.next() % 200) as u64;
            let dlc = (rng.next() % 9) as u8;
            let stuff = (rng.next() % 25) as u64;
            let latency = (rng.next() % 20_000) as u64;
            let truth = origin + sof_bits * bit;
            let now = truth + (valid_bits_min(dlc) as u64 + stuff) * bit + latency;
            let got = c.sof(sof_bits as u16, valid_bits_min(dlc), now);
            assert!(got >= truth, "SOF {} ns early", truth - got);
            let allowed = stuff * bit + latency;
            worst_excess = worst_excess.max((got - truth).saturating_sub(allowed));
        }
        worst_excess
    }

    /// Regression (issue 10): the first frame's RX latency E (a module booting into a
    /// live bus, frames queued in its FIFO before the firmware reads them) made the
    /// unwrap land 65 536 bits early for every later frame whose length was below E.
    #[test]
    fn first_frame_latency_up_to_10_ms_does_not_break_the_unwrap() {
        let mut e = 0;
        while e <= 10_000_000 {
            for counter0 in [0u64, 40_000, 65_500] {
                let excess = run(e, 1, counter0, 0x1234_5678 ^ e as u32);
                assert_eq!(excess, 0, "first latency {e} ns, counter {counter0}");
            }
            e += if e < 1_000_000 { 25_000 } else { 250_000 };
        }
    }

    #[test]
    fn frames_queued_at_start_do_not_break_the_unwrap() {
        for queued in 1..=3 {
            for e in [0u64, 250_000, 3_000_000, 10_000_000] {
                let excess = run(e, queued, 65_000, 0xDEAD_BEEF ^ e as u32);
                assert_eq!(excess, 0, "{queued} queued, latency {e} ns");
            }
        }
    }

    #[test]
    fn converges_to_the_best_frame() {
        // First frame 5 ms late, later frames 1 µs late without stuff bits: from the
        // second frame on the error is that frame's latency, not the first's.
        let mut c = SofClock::new(BIT as u32, 0);
        let origin = 1_000_000_000u64;
        let n = valid_bits_min(8) as u64;
        assert_eq!(
            c.sof(100, n as u32, origin + (100 + n) * BIT + 5_000_000),
            origin + 100 * BIT + 5_000_000
        );
        for k in 1..100u64 {
            let s = 100 + k * 1_000;
            let got = c.sof(s as u16, n as u32, origin + (s + n) * BIT + 1_000);
            assert_eq!(got, origin + s * BIT + 1_000, "frame {k}");
        }
    }

    #[test]
    fn long_silences_take_the_exact_path() {
        // 10 s and 100 s without a frame (beyond the multiply-shift range), no latency.
        let mut c = SofClock::new(BIT as u32, 200);
        let origin = 7_000_000u64;
        for s in [5u64, 10_000_005, 110_000_005, 110_001_005] {
            let now = origin + (s + 100) * BIT;
            assert_eq!(
                c.sof(s as u16, 100, now),
                origin + s * BIT,
                "frame at {s} bits"
            );
        }
    }

    /// The 32-bit `sof_near` against the general path (a clock with `narrow` off) over
    /// random traffic: every result and the state after each frame are the same.
    #[test]
    fn near_path_equals_the_general_path() {
        for (bit, ppm, seed) in [
            (1_000u32, 200u32, 1u32),
            (4, 100, 2),
            (2_000, 5_000, 3),
            (100_000, 50, 4),
            (1_000, 1_000_000, 5),
        ] {
            let mut near = SofClock::new(bit, ppm);
            let mut general = near;
            general.narrow = false;
            assert!(near.narrow);
            let mut rng = Rng(seed);
            let mut now = 5_000_000u64;
            let mut sof_bits = 12_345u64;
            for k in 0..3_000 {
                // Gaps from back to back to ~3 s (beyond the 32-bit range), latencies up
                // to 100 µs, and now and then a frame with a smaller latency than before.
                let gap = match rng.next() % 16 {
                    0 => 2_000_000_000 + u64::from(rng.next() % 1_500_000_000),
                    1 => 0,
                    _ => u64::from(rng.next() % 2_000_000),
                };
                sof_bits += gap / u64::from(bit) + 1;
                let dlc = (rng.next() % 9) as u8;
                let latency = u64::from(rng.next() % 100_000);
                now = now.max(
                    5_000_000
                        + (sof_bits + u64::from(valid_bits_min(dlc))) * u64::from(bit)
                        + latency,
                );
                let t16 = sof_bits as u16;
                let (a, b) = (
                    near.sof(t16, valid_bits_min(dlc), now),
                    general.sof(t16, valid_bits_min(dlc), now),
                );
                assert_eq!(a, b, "bit {bit} frame {k}");
                assert_eq!(
                    (
                        near.offset,
                        near.updated,
                        near.anchor_local,
                        near.anchor_bits as u16
                    ),
                    (
                        general.offset,
                        general.updated,
                        general.anchor_local,
                        general.anchor_bits as u16
                    ),
                    "bit {bit} frame {k}"
                );
            }
        }
        // Not narrow: 1-ns and 2-ns bits (not CAN rates) and bits beyond 2^31 ns.
        for bit in [1u32, 2, 3, 1 << 31, u32::MAX] {
            assert!(!SofClock::new(bit, 100).narrow, "{bit}");
        }
    }

    #[test]
    fn valid_bits_min_is_the_unstuffed_frame_to_its_valid_point() {
        assert_eq!(valid_bits_min(0), 63);
        assert_eq!(valid_bits_min(8), 127);
        assert_eq!(valid_bits_min(15), 127);
    }
}
