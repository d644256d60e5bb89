//! The sync frame (docs/PROTOCOL.md §3). OWNER: codec helper. Signatures fixed.
use crate::frame::Frame;

/// Cycle counter modulus: 15 bits (message ID low byte + fragment field).
pub const CYCLE_COUNTER_MODULUS: u32 = 1 << 15;

/// Contents of a sync frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sync {
    /// Cycle counter (< 2^15).
    pub cycle: u16,
    /// Reservation mask of the cycle this frame starts (bit k = slot k reserved).
    pub mask: u64,
}

/// Builds the sync frame; `slots` is slots per cycle (DLC = ceil(slots/8)).
pub fn sync_frame(sync: Sync, slots: u8) -> Frame {
    let _ = (sync, slots);
    todo!()
}

/// Parses a frame whose ID `is_sync()`; `None` for garbage (wrong DLC, mask bits past
/// `slots`, slot 0 not reserved).
pub fn parse_sync(frame: &Frame, slots: u8) -> Option<Sync> {
    let _ = (frame, slots);
    todo!()
}
