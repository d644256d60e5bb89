//! A CAN 2.0B data frame with an extended identifier (RTCAN uses no standard IDs
//! and no remote frames).
use crate::id::CanId;

/// One data frame: identifier, DLC (0..=8) and up to 8 data bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame {
    id: CanId,
    dlc: u8,
    data: [u8; 8],
}

impl Frame {
    /// `None` if `data` is longer than 8 bytes.
    pub fn new(id: CanId, data: &[u8]) -> Option<Self> {
        let mut buf = [0u8; 8];
        buf.get_mut(..data.len())?.copy_from_slice(data);
        Some(Frame {
            id,
            dlc: data.len() as u8,
            data: buf,
        })
    }
    /// `None` if `dlc > 8`. Bytes past `dlc` are zeroed.
    // `dlc <= 8` is checked first: the index cannot panic (const fn cannot use `get`).
    #[allow(clippy::indexing_slicing)]
    pub const fn from_parts(id: CanId, dlc: u8, data: [u8; 8]) -> Option<Self> {
        if dlc > 8 {
            return None;
        }
        // One AND with the mask of the first `dlc` bytes (a byte loop cost up to 30
        // instructions on every received frame, issue 10).
        let word = u64::from_le_bytes(data) & KEEP_BYTES[dlc as usize];
        Some(Frame {
            id,
            dlc,
            data: word.to_le_bytes(),
        })
    }
    /// Identifier.
    pub const fn id(&self) -> CanId {
        self.id
    }
    /// Data length code, 0..=8.
    pub const fn dlc(&self) -> u8 {
        self.dlc
    }
    /// The `dlc` data bytes.
    pub fn data(&self) -> &[u8] {
        // dlc <= 8 is an invariant of every constructor.
        self.data.get(..self.dlc as usize).unwrap_or(&[])
    }
    /// All 8 data bytes (those past `dlc` are zero).
    pub const fn raw_data(&self) -> &[u8; 8] {
        &self.data
    }
}

/// Little-endian mask of the first `n` data bytes, `n` = 0..=8.
const KEEP_BYTES: [u64; 9] = [
    0,
    0xFF,
    0xFFFF,
    0xFF_FFFF,
    0xFFFF_FFFF,
    0xFF_FFFF_FFFF,
    0xFFFF_FFFF_FFFF,
    0xFF_FFFF_FFFF_FFFF,
    u64::MAX,
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_parts_zeroes_exactly_the_bytes_past_the_dlc() {
        let id = CanId::from_raw(0x1234).unwrap();
        let data = [1, 2, 3, 4, 5, 6, 7, 8];
        for dlc in 0..=8u8 {
            let f = Frame::from_parts(id, dlc, data).unwrap();
            assert_eq!(f.data(), &data[..dlc as usize]);
            for (k, b) in f.raw_data().iter().enumerate() {
                assert_eq!(*b, if k < dlc as usize { data[k] } else { 0 }, "{dlc} {k}");
            }
        }
        assert_eq!(Frame::from_parts(id, 9, data), None);
    }
}
