//! CAN bit timing for bxCAN-style controllers (BRP 1..=1024, TS1 1..=16 tq, TS2 1..=8 tq),
//! computed by a `const fn`. One computation for everybody: the firmware's `can_btr!`
//! (boards/common, which re-exports this module) evaluates it at compile time so an
//! unreachable bit rate stops the build, and `rtcan check` (rtcan-model) runs it for
//! the CAN clock of every module's board, so it refuses the same bit rates first.

/// Sample point aimed at, per mille (CiA 301 recommends 87.5 %).
pub const TARGET_SAMPLE_POINT_PERMILLE: u32 = 875;

/// One bit timing: time quanta per segment and the prescaler.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BitTiming {
    /// Baud-rate prescaler, 1..=1024 (one tq = brp / f_pclk).
    pub brp: u16,
    /// Time segment 1 (propagation + phase 1), 1..=16 tq.
    pub ts1: u8,
    /// Time segment 2 (phase 2), 1..=8 tq.
    pub ts2: u8,
    /// Resynchronisation jump width, 1..=4 tq.
    pub sjw: u8,
}

/// Why no bit timing exists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BitTimingError {
    /// Bit rate zero or above clock / 8.
    OutOfRange,
    /// No prescaler divides the clock into a whole number (8..=25) of quanta per bit.
    NoExactPrescaler,
}

impl BitTiming {
    /// Bit timing for `bitrate` from a controller clock of `clock_hz`: the exact
    /// (zero-error) setting whose sample point is nearest to 87.5 %, preferring more
    /// quanta per bit (finer resynchronisation) on ties. SJW is 1 tq.
    pub const fn compute(clock_hz: u32, bitrate: u32) -> Result<BitTiming, BitTimingError> {
        if bitrate == 0 || clock_hz / 8 < bitrate {
            return Err(BitTimingError::OutOfRange);
        }
        let mut best: Option<BitTiming> = None;
        let mut best_err = u32::MAX;
        let mut n: u32 = 25;
        while n >= 8 {
            let per_brp = bitrate as u64 * n as u64;
            if (clock_hz as u64).is_multiple_of(per_brp) {
                let brp = clock_hz as u64 / per_brp;
                if brp >= 1 && brp <= 1024 {
                    // ts2 nearest to (1 - 0.875) * n, within what ts1 <= 16 and ts2 <= 8 allow.
                    let mut ts2 = (n * (1000 - TARGET_SAMPLE_POINT_PERMILLE) + 500) / 1000;
                    let min_ts2 = if n > 17 { n - 17 } else { 1 };
                    if ts2 < min_ts2 {
                        ts2 = min_ts2;
                    }
                    if ts2 > 8 {
                        ts2 = 8;
                    }
                    let ts1 = n - 1 - ts2;
                    if ts1 >= 1 && ts1 <= 16 {
                        let sp = (1 + ts1) * 1000 / n;
                        let err = sp.abs_diff(TARGET_SAMPLE_POINT_PERMILLE);
                        if err < best_err {
                            best_err = err;
                            best = Some(BitTiming {
                                brp: brp as u16,
                                ts1: ts1 as u8,
                                ts2: ts2 as u8,
                                sjw: 1,
                            });
                        }
                    }
                }
            }
            n -= 1;
        }
        match best {
            Some(t) => Ok(t),
            None => Err(BitTimingError::NoExactPrescaler),
        }
    }

    /// Quanta per bit.
    pub const fn quanta(&self) -> u32 {
        1 + self.ts1 as u32 + self.ts2 as u32
    }

    /// Sample point, per mille of the bit.
    pub const fn sample_point_permille(&self) -> u32 {
        (1 + self.ts1 as u32) * 1000 / self.quanta()
    }

    /// The bxCAN `CAN_BTR` value (`SJW[25:24]`, `TS2[22:20]`, `TS1[19:16]`, `BRP[9:0]`, each minus one).
    pub const fn btr(&self) -> u32 {
        ((self.sjw as u32 - 1) << 24)
            | ((self.ts2 as u32 - 1) << 20)
            | ((self.ts1 as u32 - 1) << 16)
            | (self.brp as u32 - 1)
    }
}

/// `CAN_BTR` for `bitrate` at `clock_hz`; evaluated in a const context (`can_btr!`)
/// an unreachable bit rate is a compile-time error naming the cause.
#[allow(clippy::panic)] // only ever evaluated at compile time through `can_btr!` (boards/common)
pub const fn btr_or_fail(clock_hz: u32, bitrate: u32) -> u32 {
    match BitTiming::compute(clock_hz, bitrate) {
        Ok(t) => t.btr(),
        Err(BitTimingError::OutOfRange) => panic!("CAN bit rate is zero or above clock/8"),
        Err(BitTimingError::NoExactPrescaler) => {
            panic!("CAN bit rate not reachable exactly from this clock (no prescaler gives 8..=25 quanta)")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_megabit_from_36_mhz_matches_the_measured_register() {
        let t = BitTiming::compute(36_000_000, 1_000_000).unwrap();
        assert_eq!(
            t,
            BitTiming {
                brp: 2,
                ts1: 15,
                ts2: 2,
                sjw: 1
            }
        );
        assert_eq!(t.btr(), 0x001E_0001);
        assert_eq!(t.sample_point_permille(), 888);
        assert_eq!(btr_or_fail(36_000_000, 1_000_000), 0x001E_0001);
    }

    #[test]
    fn common_rates_are_exact_with_sample_point_near_87_5() {
        for rate in [
            1_000_000u32,
            800_000,
            500_000,
            250_000,
            125_000,
            50_000,
            20_000,
            10_000,
        ] {
            let t = BitTiming::compute(36_000_000, rate).unwrap();
            assert_eq!(36_000_000 / (t.brp as u32 * t.quanta()), rate, "{rate}");
            assert_eq!(36_000_000 % (t.brp as u32 * t.quanta()), 0, "{rate}");
            assert!(
                t.sample_point_permille().abs_diff(875) <= 40,
                "{rate}: {t:?}"
            );
            assert!((1..=16).contains(&t.ts1) && (1..=8).contains(&t.ts2));
        }
        // 500 kbit/s: BRP x quanta = 72; 8 tq (BRP 9) hits 87.5 % exactly, 24 tq cannot
        // (TS1 <= 16 forces 70.8 %), 18 tq gives 88.9 %.
        assert_eq!(
            BitTiming::compute(36_000_000, 500_000).unwrap(),
            BitTiming {
                brp: 9,
                ts1: 6,
                ts2: 1,
                sjw: 1
            }
        );
    }

    #[test]
    fn unreachable_rates_are_errors() {
        assert_eq!(
            BitTiming::compute(36_000_000, 700_000),
            Err(BitTimingError::NoExactPrescaler)
        );
        assert_eq!(
            BitTiming::compute(36_000_000, 5_000_000),
            Err(BitTimingError::OutOfRange)
        );
        assert_eq!(
            BitTiming::compute(36_000_000, 0),
            Err(BitTimingError::OutOfRange)
        );
        // Needs BRP > 1024.
        assert_eq!(
            BitTiming::compute(36_000_000, 1_000),
            Err(BitTimingError::NoExactPrescaler)
        );
    }
}
