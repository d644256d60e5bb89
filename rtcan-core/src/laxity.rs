//! SRT laxity encoding (docs/PROTOCOL.md §6). OWNER: codec helper. Signatures fixed.
//!
//! The code sits in `ID[28:23]`, so a smaller code wins arbitration: the encoding must be
//! monotone non-decreasing in laxity or EDF order on the bus breaks.
use crate::id::{LAXITY_SRT_MAX, LAXITY_SRT_MIN};
use crate::time::{Nanos, SNanos};

/// Number of SRT codes (1..=62).
const SRT_CODES: u64 = (LAXITY_SRT_MAX - LAXITY_SRT_MIN + 1) as u64;
/// Log encoding: units below this get one code each.
const LOG_EXACT: u64 = 16;
/// Log encoding: mantissa bits per octave.
const LOG_MANTISSA_BITS: u32 = 3;

/// How remaining laxity maps to the 6-bit priority field, chosen per bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LaxityEncoding {
    /// code = 1 + laxity / unit, saturating at 62.
    Linear { unit_ns: u32 },
    /// Finer near the deadline (exponent/mantissa), saturating at 62.
    Log { unit_ns: u32 },
}

impl LaxityEncoding {
    /// Laxity field (1..=62) for `laxity_ns` remaining; `None` when the deadline has
    /// passed (laxity < 0): the message is dropped and reported.
    pub const fn encode(self, laxity_ns: SNanos) -> Option<u8> {
        if laxity_ns < 0 {
            return None;
        }
        let unit = self.unit();
        // Cortex-M3 divides 32-bit integers in hardware but 64-bit ones in a library
        // routine; laxities that matter (below ~4.3 s) take the 32-bit path.
        let v = if laxity_ns <= u32::MAX as SNanos && unit <= u32::MAX as u64 {
            (laxity_ns as u32 / unit as u32) as u64
        } else {
            laxity_ns as u64 / unit
        };
        let offset = match self {
            LaxityEncoding::Linear { .. } => v,
            LaxityEncoding::Log { .. } => log_offset(v),
        };
        let offset = if offset > SRT_CODES - 1 {
            SRT_CODES - 1
        } else {
            offset
        };
        Some(LAXITY_SRT_MIN + offset as u8)
    }

    /// Smallest laxity that saturates (encodes to 62): every laxity from here on is
    /// indistinguishable on the bus. Linear: 61 units; Log: 832 units.
    pub const fn max_laxity_ns(self) -> Nanos {
        match self.lower_bound_ns(LAXITY_SRT_MAX) {
            Some(ns) => ns,
            None => 0, // unreachable: LAXITY_SRT_MAX is a valid code
        }
    }

    /// Smallest laxity (ns) that encodes to `code`; `None` if `code` is not 1..=62.
    /// Laxities in `[lower_bound_ns(c), lower_bound_ns(c + 1))` all encode to `c`.
    pub const fn lower_bound_ns(self, code: u8) -> Option<Nanos> {
        if code < LAXITY_SRT_MIN || code > LAXITY_SRT_MAX {
            return None;
        }
        let k = (code - LAXITY_SRT_MIN) as u64;
        let units = match self {
            LaxityEncoding::Linear { .. } => k,
            LaxityEncoding::Log { .. } => {
                if k < LOG_EXACT {
                    k
                } else {
                    let k = k - LOG_EXACT;
                    let e = (k >> LOG_MANTISSA_BITS) as u32 + 1;
                    let m = k & ((1 << LOG_MANTISSA_BITS) - 1);
                    ((1 << LOG_MANTISSA_BITS) + m) << e
                }
            }
        };
        Some(units * self.unit())
    }

    /// Unit in ns; a unit of 0 is read as 1 ns so that no input can divide by zero.
    const fn unit(self) -> u64 {
        let (LaxityEncoding::Linear { unit_ns } | LaxityEncoding::Log { unit_ns }) = self;
        if unit_ns == 0 {
            1
        } else {
            unit_ns as u64
        }
    }
}

/// Log encoding of `v` units, before saturation: `v` itself below 16, then 8 codes per
/// octave (3-bit mantissa below the leading one).
const fn log_offset(v: u64) -> u64 {
    if v < LOG_EXACT {
        return v;
    }
    // v >= 16, so msb >= 4 and e >= 1.
    let msb = 63 - v.leading_zeros();
    let e = msb - LOG_MANTISSA_BITS;
    let mantissa = (v >> e) & ((1 << LOG_MANTISSA_BITS) - 1);
    LOG_EXACT + 8 * (e as u64 - 1) + mantissa
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIN: LaxityEncoding = LaxityEncoding::Linear { unit_ns: 100_000 };
    const LOG: LaxityEncoding = LaxityEncoding::Log { unit_ns: 10_000 };

    #[test]
    fn negative_laxity_is_none() {
        assert_eq!(LIN.encode(-1), None);
        assert_eq!(LOG.encode(SNanos::MIN), None);
        assert_eq!(LIN.encode(0), Some(1));
        assert_eq!(LOG.encode(0), Some(1));
    }

    #[test]
    fn linear_boundaries() {
        assert_eq!(LIN.encode(99_999), Some(1));
        assert_eq!(LIN.encode(100_000), Some(2));
        assert_eq!(LIN.encode(6_099_999), Some(61));
        assert_eq!(LIN.encode(6_100_000), Some(62));
        assert_eq!(LIN.encode(SNanos::MAX), Some(62));
        assert_eq!(LIN.max_laxity_ns(), 6_100_000);
    }

    #[test]
    fn log_boundaries() {
        // v = laxity / 10 us.
        assert_eq!(LOG.encode(159_999), Some(16)); // v = 15: last exact code
        assert_eq!(LOG.encode(160_000), Some(17)); // v = 16: e = 1, m = 0
        assert_eq!(LOG.encode(179_999), Some(17)); // v = 17: same code (step 2)
        assert_eq!(LOG.encode(180_000), Some(18)); // v = 18
        assert_eq!(LOG.encode(319_999), Some(24)); // v = 31: e = 1, m = 7
        assert_eq!(LOG.encode(320_000), Some(25)); // v = 32: e = 2, m = 0
        assert_eq!(LOG.encode(8_319_999), Some(61)); // v = 831: e = 6, m = 4
        assert_eq!(LOG.encode(8_320_000), Some(62)); // v = 832: e = 6, m = 5
        assert_eq!(LOG.encode(SNanos::MAX), Some(62));
        assert_eq!(LOG.max_laxity_ns(), 8_320_000);
    }

    #[test]
    fn zero_unit_does_not_divide_by_zero() {
        let z = LaxityEncoding::Log { unit_ns: 0 };
        assert_eq!(z.encode(15), Some(16));
        assert_eq!(z.max_laxity_ns(), 832);
    }

    #[test]
    fn lower_bounds_invert_encode() {
        for enc in [
            LIN,
            LOG,
            LaxityEncoding::Log { unit_ns: 1 },
            LaxityEncoding::Linear { unit_ns: 7 },
        ] {
            assert_eq!(enc.lower_bound_ns(0), None);
            assert_eq!(enc.lower_bound_ns(63), None);
            for code in LAXITY_SRT_MIN..=LAXITY_SRT_MAX {
                let lb = enc.lower_bound_ns(code).unwrap();
                assert_eq!(enc.encode(lb as SNanos), Some(code), "{enc:?} code {code}");
                if lb > 0 {
                    assert_eq!(
                        enc.encode(lb as SNanos - 1),
                        Some(code - 1),
                        "{enc:?} code {code}"
                    );
                }
            }
        }
    }

    #[test]
    fn monotone_exhaustive() {
        // Every ns from 0 to past saturation, unit 1 ns (Log saturates at 832, Linear at 61)
        // and a coarser unit; codes never decrease and every code 1..=62 is used.
        for enc in [
            LaxityEncoding::Log { unit_ns: 1 },
            LaxityEncoding::Linear { unit_ns: 1 },
            LaxityEncoding::Log { unit_ns: 3 },
            LaxityEncoding::Linear { unit_ns: 13 },
        ] {
            let mut prev = 0u8;
            let mut seen = [false; 64];
            for l in 0..4_000 {
                let c = enc.encode(l).unwrap();
                assert!(c >= prev, "{enc:?}: code fell at {l}");
                assert!((1..=62).contains(&c));
                seen[c as usize] = true;
                prev = c;
            }
            assert!(seen[1..=62].iter().all(|&s| s), "{enc:?} skips a code");
        }
    }
}
