//! SRT laxity encoding (docs/PROTOCOL.md §6). OWNER: codec helper. Signatures fixed.
use crate::time::SNanos;

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
        let _ = laxity_ns;
        todo!()
    }
}
