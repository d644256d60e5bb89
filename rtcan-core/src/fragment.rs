//! Fragmentation and reassembly (docs/PROTOCOL.md §7). OWNER: codec helper.
//!
//! A message of `n` bytes travels as `fragment_count(n)` frames. The 7-bit fragment field
//! `ID[6:0]` of a multi-frame message holds a count-down counter in its low
//! `counter_bits(count)` bits and, in the bits above, a transfer ID that the sender
//! increments for every transfer of the topic: every fragment names its transfer, so a
//! receiver never glues frames of two transfers together (docs/PROTOCOL.md §7.4 — by
//! construction, not by CRC chance; there is no transfer CRC).
use crate::frame::Frame;
use crate::time::Nanos;

/// Most frames in one message: a 5-bit counter leaves at least 2 transfer-ID bits.
pub const MAX_FRAGMENTS: usize = 32;
/// Largest payload: 32 frames x 8 bytes.
pub const MAX_PAYLOAD: usize = MAX_FRAGMENTS * 8;
/// Width of the fragment field `ID[6:0]`.
pub const FIELD_BITS: u8 = 7;

/// Bytes on the wire for a payload: the payload itself (no transfer CRC). The one place
/// that says so: the model sizes reassembly buffers and bus load from it.
pub const fn wire_len(payload: usize) -> usize {
    payload
}

/// Number of frames for a payload (at least 1). Payloads above `MAX_PAYLOAD` give a count
/// above `MAX_FRAGMENTS` (saturating at 255): the model rejects such topics.
pub const fn fragment_count(payload: usize) -> u8 {
    let n = wire_len(payload).div_ceil(8);
    if n == 0 {
        1
    } else if n > u8::MAX as usize {
        u8::MAX
    } else {
        n as u8
    }
}

/// Bits of the fragment field that hold the counter for a message of `count` frames:
/// 0 for a single frame, else `ceil(log2(count))` (2 frames: 1 bit, 3-4: 2, 5-8: 3,
/// 9-16: 4, 17-32: 5). Above `MAX_FRAGMENTS` the whole field.
pub const fn counter_bits(count: u8) -> u8 {
    if count <= 1 {
        return 0;
    }
    if count as usize > MAX_FRAGMENTS {
        return FIELD_BITS;
    }
    (u8::BITS - (count - 1).leading_zeros()) as u8
}

/// Transfer-ID bits of a message of `count` frames: the field bits the counter leaves
/// (6 for 2 frames … 2 for 17-32 frames); 0 for a single frame, which cannot be mixed.
pub const fn transfer_id_bits(count: u8) -> u8 {
    if count <= 1 {
        0
    } else {
        FIELD_BITS - counter_bits(count)
    }
}

/// The fragment field `ID[6:0]` of fragment `counter` of transfer `tid` (taken modulo
/// `2^transfer_id_bits(count)`) of a message of `count` frames.
pub const fn fragment_field(count: u8, tid: u8, counter: u8) -> u8 {
    let k = counter_bits(count);
    let t = transfer_id_bits(count);
    let tid = tid & ((1u8 << t) - 1);
    ((tid << k) | counter) & 0x7F
}

/// Splits a received fragment field into (transfer ID, counter) for a message of `count`
/// frames. The counter may be `>= count` (garbage the receiver drops).
pub const fn split_field(count: u8, field: u8) -> (u8, u8) {
    let field = field & 0x7F;
    let k = counter_bits(count);
    // A single frame carries no transfer ID: its whole field is the counter (0).
    if count <= 1 || k >= FIELD_BITS {
        return (0, field);
    }
    (field >> k, field & ((1u8 << k) - 1))
}

/// The count-down counter carried by fragment field `field` of a message of `size` bytes
/// (for tools that read frames off the wire: the last fragment has counter 0).
pub const fn counter_of(size: usize, field: u8) -> u8 {
    split_field(fragment_count(size), field).1
}

/// DLC of the fragment with count-down `counter` in a message of `payload` bytes; `None`
/// if the message has no such fragment.
pub const fn fragment_dlc(payload: usize, counter: u8) -> Option<u8> {
    let count = fragment_count(payload);
    if payload > MAX_PAYLOAD || counter >= count {
        return None;
    }
    let start = 8 * (count - 1 - counter) as usize;
    let left = wire_len(payload) - start;
    Some(if left > 8 { 8 } else { left as u8 })
}

/// Writes the data of fragment `counter` (count-down: first = fragment_count-1, last = 0)
/// of `payload` into `out`; returns the DLC. A counter the message does not have, or a
/// payload above `MAX_PAYLOAD`, gives DLC 0 and zeroed `out` (the engine only asks for
/// fragments of its own topics).
pub fn fragment_data(payload: &[u8], counter: u8, out: &mut [u8; 8]) -> u8 {
    // This runs on every frame the engine loads (slot handler, TX interrupt): whole
    // chunks are one 8-byte move, the tail is packed into a word; no variable-size copy
    // (a `memcpy` call costs more than the rest of this function on Cortex-M3).
    let len = payload.len();
    let count = fragment_count(len);
    if len > MAX_PAYLOAD || counter >= count {
        *out = [0; 8];
        return 0;
    }
    let start = 8 * usize::from(count - 1 - counter);
    if let Some(chunk) = payload
        .get(start..start + 8)
        .and_then(|c| <&[u8; 8]>::try_from(c).ok())
    {
        *out = *chunk;
        return 8;
    }
    let rest = payload.get(start..).unwrap_or(&[]);
    // The tail (under 8 bytes): a short byte loop into a zeroed array (packing it into a
    // word cost a 64-bit shift library call per byte at opt-level z, issue 10).
    let mut w = [0u8; 8];
    for (d, b) in w.iter_mut().zip(rest) {
        *d = *b;
    }
    *out = w;
    rest.len().min(8) as u8
}

/// Why a received frame was dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RxDrop {
    /// DLC does not match the position of the fragment in a message of this size.
    BadDlc,
    /// Counter not the expected one (lost or out-of-order frame); transfer discarded.
    OutOfOrder,
    /// The expected counter, but the transfer ID of another transfer (the rest of this
    /// transfer and the start of that one were lost): transfer discarded, nothing mixed.
    OtherTransfer,
    /// Configuration error, not a bus error: topic size above `MAX_PAYLOAD` or buffer
    /// shorter than `wire_len(size)`.
    BadSize,
}

/// Reassembly state of one receive topic.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RxState {
    next: Option<u8>,
    /// Transfer ID of the transfer in progress.
    tid: u8,
    first_sof: Nanos,
}

/// Result of feeding one frame.
#[derive(Debug, PartialEq, Eq)]
pub enum RxStep<'b> {
    /// More fragments expected.
    Pending,
    /// More fragments expected, and this first fragment discarded an unfinished transfer
    /// (its tail was lost, e.g. the sender dropped it at its deadline).
    Restarted,
    /// Message complete: payload and the first frame's SOF.
    Complete(&'b [u8], Nanos),
    /// Frame dropped (and any partial transfer discarded).
    Dropped(RxDrop),
}

impl RxState {
    /// Feeds `frame` (already matched to this topic) into `buf`, which has room for
    /// `wire_len(size)` bytes. A topic size above `MAX_PAYLOAD` or a shorter `buf` (a
    /// configuration error the model rules out) drops every frame as `BadSize`.
    /// Never panics, whatever the frame.
    pub fn step<'b>(
        &mut self,
        buf: &'b mut [u8],
        size: usize,
        frame: &Frame,
        sof: Nanos,
    ) -> RxStep<'b> {
        let partial = self.next.take();
        if size > MAX_PAYLOAD || buf.len() < wire_len(size) {
            return RxStep::Dropped(RxDrop::BadSize);
        }
        let count = fragment_count(size);
        let (tid, counter) = split_field(count, frame.id().fragment());
        let first = counter == count - 1;
        if !first {
            if partial != Some(counter) {
                return RxStep::Dropped(RxDrop::OutOfOrder);
            }
            if tid != self.tid {
                return RxStep::Dropped(RxDrop::OtherTransfer);
            }
        }
        if fragment_dlc(size, counter) != Some(frame.dlc()) {
            return RxStep::Dropped(RxDrop::BadDlc);
        }
        let start = 8 * usize::from(count - 1 - counter);
        let data = frame.data();
        match buf.get_mut(start..start + data.len()) {
            // At most 8 bytes: a constant-size copy for a full frame (two word moves), a
            // short loop otherwise (a variable-size `memcpy` call costs more on Cortex-M3).
            Some(dst) if data.len() == 8 => {
                if let (Ok(d), Ok(b)) = (<&mut [u8; 8]>::try_from(dst), <&[u8; 8]>::try_from(data))
                {
                    *d = *b;
                }
            }
            Some(dst) => {
                // `dst` is `data.len()` long: the frame's first bytes, straight from its
                // 8-byte array (packing them into a word first cost a 64-bit shift
                // library call per byte at opt-level z, issue 10).
                for (d, b) in dst.iter_mut().zip(frame.raw_data()) {
                    *d = *b;
                }
            }
            None => return RxStep::Dropped(RxDrop::BadSize), // unreachable: size checked above
        }
        if first {
            self.first_sof = sof;
            self.tid = tid;
        }
        if counter > 0 {
            self.next = Some(counter - 1);
            return if first && partial.is_some() {
                RxStep::Restarted
            } else {
                RxStep::Pending
            };
        }
        match buf.get(..size) {
            Some(payload) => RxStep::Complete(payload, self.first_sof),
            None => RxStep::Dropped(RxDrop::BadSize), // unreachable: size checked above
        }
    }

    /// True while a multi-frame transfer is partly received.
    pub const fn in_progress(&self) -> bool {
        self.next.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::id::{CanId, MsgId};

    fn frames_tid(payload: &[u8], tid: u8) -> Vec<Frame> {
        let count = fragment_count(payload.len());
        (0..count)
            .rev()
            .map(|c| {
                let mut out = [0; 8];
                let dlc = fragment_data(payload, c, &mut out);
                let field = fragment_field(count, tid, c);
                Frame::from_parts(CanId::new(0, MsgId(0x140), field).unwrap(), dlc, out).unwrap()
            })
            .collect()
    }

    fn frames(payload: &[u8]) -> Vec<Frame> {
        frames_tid(payload, 0)
    }

    #[test]
    fn field_layout() {
        let bits: Vec<(u8, u8)> = [1u8, 2, 3, 4, 5, 8, 9, 16, 17, 32]
            .iter()
            .map(|&c| (counter_bits(c), transfer_id_bits(c)))
            .collect();
        assert_eq!(
            bits,
            [
                (0, 0),
                (1, 6),
                (2, 5),
                (2, 5),
                (3, 4),
                (3, 4),
                (4, 3),
                (4, 3),
                (5, 2),
                (5, 2)
            ]
        );
        assert_eq!(counter_bits(33), 7);
        assert_eq!(transfer_id_bits(33), 0);
        // 3 frames, transfer 5: 5 << 2 | counter.
        assert_eq!(fragment_field(3, 5, 2), 0x16);
        assert_eq!(fragment_field(3, 5, 0), 0x14);
        assert_eq!(split_field(3, 0x16), (5, 2));
        // Transfer IDs wrap at 2^bits; single frames carry none.
        assert_eq!(fragment_field(3, 32 + 5, 1), fragment_field(3, 5, 1));
        assert_eq!(fragment_field(1, 9, 0), 0);
        assert_eq!(split_field(1, 3), (0, 3));
        assert_eq!(counter_of(20, 0x14), 0);
        for count in 1..=MAX_FRAGMENTS as u8 {
            for tid in 0..=255u8 {
                for c in 0..count {
                    let f = fragment_field(count, tid, c);
                    let t = tid & ((1u16 << transfer_id_bits(count)) - 1) as u8;
                    assert_eq!(split_field(count, f), (t, c));
                }
            }
        }
    }

    #[test]
    fn counts_and_dlcs() {
        assert_eq!(fragment_count(0), 1);
        assert_eq!(fragment_count(8), 1);
        assert_eq!(fragment_count(9), 2);
        assert_eq!(fragment_count(16), 2);
        assert_eq!(fragment_count(17), 3);
        assert_eq!(fragment_count(MAX_PAYLOAD), 32);
        assert_eq!(fragment_count(MAX_PAYLOAD + 1), 33);
        assert_eq!(fragment_dlc(0, 0), Some(0));
        assert_eq!(fragment_dlc(9, 1), Some(8));
        assert_eq!(fragment_dlc(9, 0), Some(1));
        assert_eq!(fragment_dlc(9, 2), None);
        assert_eq!(fragment_dlc(MAX_PAYLOAD + 1, 0), None);
    }

    #[test]
    fn fragment_data_out_of_range_counter_is_empty() {
        let mut out = [0xAA; 8];
        assert_eq!(fragment_data(&[1, 2, 3], 1, &mut out), 0);
        assert_eq!(out, [0; 8]);
    }

    #[test]
    fn lost_middle_fragment_is_out_of_order() {
        let p: Vec<u8> = (0..20).collect();
        let f = frames(&p);
        let mut buf = [0u8; 20];
        let mut rx = RxState::default();
        assert_eq!(rx.step(&mut buf, 20, &f[0], 1), RxStep::Pending);
        assert_eq!(
            rx.step(&mut buf, 20, &f[2], 2),
            RxStep::Dropped(RxDrop::OutOfOrder)
        );
        assert!(!rx.in_progress());
        // A new first fragment restarts cleanly; SOF is the first fragment's.
        assert_eq!(rx.step(&mut buf, 20, &f[0], 10), RxStep::Pending);
        assert_eq!(rx.step(&mut buf, 20, &f[1], 11), RxStep::Pending);
        assert_eq!(
            rx.step(&mut buf, 20, &f[2], 12),
            RxStep::Complete(&p[..], 10)
        );
    }

    #[test]
    fn restart_discards_partial() {
        let p: Vec<u8> = (0..20).collect();
        let f = frames(&p);
        let mut buf = [0u8; 20];
        let mut rx = RxState::default();
        assert_eq!(rx.step(&mut buf, 20, &f[0], 1), RxStep::Pending);
        assert_eq!(rx.step(&mut buf, 20, &f[0], 5), RxStep::Restarted);
        assert_eq!(rx.step(&mut buf, 20, &f[1], 6), RxStep::Pending);
        assert_eq!(rx.step(&mut buf, 20, &f[2], 7), RxStep::Complete(&p[..], 5));
    }

    #[test]
    fn wrong_dlc_and_counter_beyond_count() {
        let p = [7u8; 20];
        let f = frames(&p);
        let mut buf = [0u8; 20];
        let mut rx = RxState::default();
        let short = Frame::new(f[0].id(), &[7; 7]).unwrap();
        assert_eq!(
            rx.step(&mut buf, 20, &short, 0),
            RxStep::Dropped(RxDrop::BadDlc)
        );
        // 3 frames use a 2-bit counter: counter 3 does not exist.
        let beyond = Frame::new(CanId::new(0, MsgId(0x140), 3).unwrap(), &[7; 8]).unwrap();
        assert_eq!(
            rx.step(&mut buf, 20, &beyond, 0),
            RxStep::Dropped(RxDrop::OutOfOrder)
        );
        let single = Frame::new(CanId::new(0, MsgId(0x140), 0).unwrap(), &[1, 2]).unwrap();
        assert_eq!(
            rx.step(&mut buf, 3, &single, 0),
            RxStep::Dropped(RxDrop::BadDlc)
        );
        assert_eq!(
            rx.step(&mut buf, 2, &single, 4),
            RxStep::Complete(&[1, 2][..], 4)
        );
        // A single frame with a non-zero field is garbage.
        let odd = Frame::new(CanId::new(0, MsgId(0x140), 1).unwrap(), &[1, 2]).unwrap();
        assert_eq!(
            rx.step(&mut buf, 2, &odd, 4),
            RxStep::Dropped(RxDrop::OutOfOrder)
        );
    }

    #[test]
    fn other_transfer_is_dropped() {
        let a: Vec<u8> = (0..20).collect();
        let b: Vec<u8> = (100..120).collect();
        let fa = frames_tid(&a, 0);
        let fb = frames_tid(&b, 1);
        let mut buf = [0u8; 20];
        let mut rx = RxState::default();
        assert_eq!(rx.step(&mut buf, 20, &fa[0], 0), RxStep::Pending);
        assert_eq!(
            rx.step(&mut buf, 20, &fb[1], 0),
            RxStep::Dropped(RxDrop::OtherTransfer)
        );
        assert!(!rx.in_progress());
        assert_eq!(
            rx.step(&mut buf, 20, &fb[2], 0),
            RxStep::Dropped(RxDrop::OutOfOrder)
        );
    }

    #[test]
    fn short_buffer_and_oversize_are_dropped() {
        let f = frames(&[0; 20]);
        let mut rx = RxState::default();
        assert_eq!(
            rx.step(&mut [0u8; 19], 20, &f[0], 0),
            RxStep::Dropped(RxDrop::BadSize)
        );
        assert_eq!(
            rx.step(&mut [0u8; 2000], MAX_PAYLOAD + 1, &f[0], 0),
            RxStep::Dropped(RxDrop::BadSize)
        );
    }
}
