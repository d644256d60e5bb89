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
    // `i < 8` is the loop bound: the index cannot panic (const fn cannot use get_mut).
    #[allow(clippy::indexing_slicing)]
    pub const fn from_parts(id: CanId, dlc: u8, mut data: [u8; 8]) -> Option<Self> {
        if dlc > 8 {
            return None;
        }
        let mut i = dlc as usize;
        while i < 8 {
            data[i] = 0;
            i += 1;
        }
        Some(Frame { id, dlc, data })
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
