//! Frame durations on the wire (docs/PROTOCOL.md §4). OWNER: codec helper. Signatures fixed.
use crate::frame::Frame;
use crate::time::Nanos;

/// Inter-frame space (intermission) in bits.
pub const INTERMISSION_BITS: u32 = 3;

/// Worst-case length in bits of an extended data frame with `dlc` data bytes, with the
/// maximum number of stuff bits, including the 3-bit intermission. dlc > 8 counts as 8.
pub const fn worst_case_bits(dlc: u8) -> u32 {
    let _ = dlc;
    todo!()
}

/// Exact length in bits of this concrete frame (real stuff bits over SOF..CRC computed on
/// the actual ID, DLC, data and CRC-15), including EOF and the 3-bit intermission.
pub fn exact_bits(frame: &Frame) -> u32 {
    let _ = frame;
    todo!()
}

/// `bits` at `bitrate` bit/s, in ns, rounded up.
pub const fn bits_to_ns(bits: u32, bitrate: u32) -> Nanos {
    (bits as u64 * 1_000_000_000).div_ceil(bitrate as u64)
}
