//! Fragmentation and reassembly (docs/PROTOCOL.md §7). OWNER: codec helper. Signatures fixed.
use crate::frame::Frame;
use crate::time::Nanos;

/// Most frames in one message (7-bit count-down counter).
pub const MAX_FRAGMENTS: usize = 128;
/// Largest payload: 128 frames x 8 bytes minus the 2-byte CRC of multi-frame messages.
pub const MAX_PAYLOAD: usize = MAX_FRAGMENTS * 8 - 2;

/// Bytes on the wire for a payload: multi-frame messages carry a CRC-16 at the end.
pub const fn wire_len(payload: usize) -> usize {
    if payload > 8 {
        payload + 2
    } else {
        payload
    }
}

/// Number of frames for a payload (at least 1).
pub const fn fragment_count(payload: usize) -> u8 {
    let _ = payload;
    todo!()
}

/// Transfer CRC of multi-frame messages (see PROTOCOL.md for polynomial and init).
pub fn crc16(data: &[u8]) -> u16 {
    let _ = data;
    todo!()
}

/// Writes the data of fragment `counter` (count-down: first = fragment_count-1, last = 0)
/// of `payload` (whose transfer CRC is `crc`) into `out`; returns the DLC.
pub fn fragment_data(payload: &[u8], crc: u16, counter: u8, out: &mut [u8; 8]) -> u8 {
    let _ = (payload, crc, counter, out);
    todo!()
}

/// Why a received frame was dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RxDrop {
    /// DLC does not match the position of the fragment in a message of this size.
    BadDlc,
    /// Counter not the expected one (lost or out-of-order frame); transfer discarded.
    OutOfOrder,
    /// Reassembled bytes fail the transfer CRC (frames of two transmissions mixed).
    Crc,
}

/// Reassembly state of one receive topic.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RxState {
    next: Option<u8>,
    first_sof: Nanos,
}

/// Result of feeding one frame.
#[derive(Debug, PartialEq, Eq)]
pub enum RxStep<'b> {
    /// More fragments expected.
    Pending,
    /// Message complete: payload (CRC checked and stripped) and the first frame's SOF.
    Complete(&'b [u8], Nanos),
    /// Frame dropped (and any partial transfer discarded).
    Dropped(RxDrop),
}

impl RxState {
    /// Feeds `frame` (already matched to this topic) into `buf`, which has room for
    /// `wire_len(size)` bytes.
    pub fn step<'b>(&mut self, buf: &'b mut [u8], size: usize, frame: &Frame, sof: Nanos) -> RxStep<'b> {
        let _ = (buf, size, frame, sof, self.next, self.first_sof);
        todo!()
    }
}
