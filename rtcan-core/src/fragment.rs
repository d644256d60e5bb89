//! Fragmentation and reassembly (docs/PROTOCOL.md §7). OWNER: codec helper. Signatures fixed.
//!
//! A message of `n` bytes travels as `fragment_count(n)` frames with a count-down counter in
//! `ID[6:0]`; messages longer than one frame end with a CRC-16 of the payload so that a
//! receiver never delivers frames of two transmissions glued together.
use crate::frame::Frame;
use crate::time::Nanos;

/// Most frames in one message (7-bit count-down counter).
pub const MAX_FRAGMENTS: usize = 128;
/// Largest payload: 128 frames x 8 bytes minus the 2-byte CRC of multi-frame messages.
pub const MAX_PAYLOAD: usize = MAX_FRAGMENTS * 8 - 2;
/// Bytes of the transfer CRC appended to multi-frame messages.
pub const CRC_LEN: usize = 2;

/// Bytes on the wire for a payload: multi-frame messages carry a CRC-16 at the end.
pub const fn wire_len(payload: usize) -> usize {
    if payload > 8 {
        payload + CRC_LEN
    } else {
        payload
    }
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

/// Initial value of the transfer CRC register.
pub const CRC16_INIT: u16 = 0xFFFF;

/// Transfer CRC of multi-frame messages: CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF,
/// no reflection, xorout 0; check value 0x29B1 for "123456789"). Sent little-endian.
pub fn crc16(data: &[u8]) -> u16 {
    crc16_update(CRC16_INIT, data)
}

/// Continues a CRC-16/CCITT-FALSE over `data` (start from `CRC16_INIT`). Lets a sender or
/// receiver spread the CRC over the fragments (8 bytes per frame) instead of one pass over
/// up to 1022 bytes in an interrupt handler: a sender that updates the CRC with each
/// fragment's payload bytes before building that fragment has the complete CRC by the
/// time a fragment carries CRC bytes.
pub fn crc16_update(mut crc: u16, data: &[u8]) -> u16 {
    for &byte in data {
        let idx = usize::from((crc >> 8) as u8 ^ byte);
        // idx < 256: the lookup cannot miss.
        crc = (crc << 8) ^ CRC16_TABLE.get(idx).copied().unwrap_or(0);
    }
    crc
}

/// Byte-wise table of the CRC-16 generator 0x1021 (512 bytes of flash, built at compile
/// time): 8 times fewer steps than the bitwise loop.
// `static`, not `const`: a const array indexed at run time may be copied to the stack on
// every call. Immutable data, not state.
static CRC16_TABLE: [u16; 256] = crc16_table();

// `i < 256` is the loop bound: the index cannot panic (const fn cannot use get_mut).
#[allow(clippy::indexing_slicing)]
const fn crc16_table() -> [u16; 256] {
    let mut table = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = (i as u16) << 8;
        let mut k = 0;
        while k < 8 {
            c = if c & 0x8000 != 0 {
                (c << 1) ^ 0x1021
            } else {
                c << 1
            };
            k += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
}

/// Writes the data of fragment `counter` (count-down: first = fragment_count-1, last = 0)
/// of `payload` (whose transfer CRC is `crc`) into `out`; returns the DLC.
/// A counter the message does not have, or a payload above `MAX_PAYLOAD`, gives DLC 0 and
/// zeroed `out` (the engine only asks for fragments of its own topics).
pub fn fragment_data(payload: &[u8], crc: u16, counter: u8, out: &mut [u8; 8]) -> u8 {
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
    // Tail: what is left of the payload, then (multi-frame messages) the CRC,
    // little-endian; a fragment may also start inside the CRC.
    let rest = payload.get(start..).unwrap_or(&[]);
    let mut word = pack_le(rest);
    if len > 8 {
        word |= match start.checked_sub(len) {
            None => u64::from(crc)
                .checked_shl(8 * rest.len() as u32)
                .unwrap_or(0),
            Some(k) => u64::from(crc) >> (8 * k.min(2)),
        };
    }
    *out = word.to_le_bytes();
    (wire_len(len) - start).min(8) as u8
}

/// Up to 8 bytes as a little-endian word (bytes past the slice are zero).
fn pack_le(bytes: &[u8]) -> u64 {
    bytes
        .iter()
        .take(8)
        .enumerate()
        .fold(0, |w, (k, b)| w | (*b as u64) << (8 * k))
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
    /// Configuration error, not a bus error: topic size above `MAX_PAYLOAD` or buffer
    /// shorter than `wire_len(size)`.
    BadSize,
}

/// Reassembly state of one receive topic.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RxState {
    next: Option<u8>,
    first_sof: Nanos,
    /// CRC of the payload bytes received so far (updated per fragment, so the last
    /// fragment costs 8 bytes of CRC, not the whole message).
    crc: u16,
}

/// Result of feeding one frame.
#[derive(Debug, PartialEq, Eq)]
pub enum RxStep<'b> {
    /// More fragments expected.
    Pending,
    /// More fragments expected, and this first fragment discarded an unfinished transfer
    /// (its tail was lost, e.g. the sender dropped it at its deadline).
    Restarted,
    /// Message complete: payload (CRC checked and stripped) and the first frame's SOF.
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
        let wire = wire_len(size);
        if size > MAX_PAYLOAD || buf.len() < wire {
            return RxStep::Dropped(RxDrop::BadSize);
        }
        let count = fragment_count(size);
        let counter = frame.id().fragment();
        let first = counter == count - 1;
        if !first && partial != Some(counter) {
            return RxStep::Dropped(RxDrop::OutOfOrder);
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
                let w = pack_le(data).to_le_bytes();
                for (d, b) in dst.iter_mut().zip(w) {
                    *d = b;
                }
            }
            None => return RxStep::Dropped(RxDrop::BadSize), // unreachable: size checked above
        }
        if first {
            self.first_sof = sof;
            self.crc = CRC16_INIT;
        }
        // Payload bytes of this fragment (the CRC bytes at the end are not covered);
        // single-frame messages carry no CRC, so they skip it.
        let payload_end = (start + data.len()).min(size);
        if size > 8 {
            if let Some(part) = buf.get(start..payload_end) {
                self.crc = crc16_update(self.crc, part);
            }
        }
        if counter > 0 {
            self.next = Some(counter - 1);
            return if first && partial.is_some() {
                RxStep::Restarted
            } else {
                RxStep::Pending
            };
        }
        let Some((payload, tail)) = buf.split_at_mut_checked(size) else {
            return RxStep::Dropped(RxDrop::BadSize); // unreachable: size checked above
        };
        if count > 1 {
            let sent = match tail {
                [lo, hi, ..] => u16::from_le_bytes([*lo, *hi]),
                _ => return RxStep::Dropped(RxDrop::BadSize), // unreachable: size checked above
            };
            if self.crc != sent {
                return RxStep::Dropped(RxDrop::Crc);
            }
        }
        RxStep::Complete(payload, self.first_sof)
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

    fn frames(payload: &[u8]) -> Vec<Frame> {
        let crc = crc16(payload);
        (0..fragment_count(payload.len()))
            .rev()
            .map(|c| {
                let mut out = [0; 8];
                let dlc = fragment_data(payload, crc, c, &mut out);
                Frame::from_parts(CanId::new(0, MsgId(0x140), c).unwrap(), dlc, out).unwrap()
            })
            .collect()
    }

    /// The bitwise definition, to check the table.
    fn crc16_bitwise(data: &[u8]) -> u16 {
        let mut crc: u16 = 0xFFFF;
        for &byte in data {
            crc ^= u16::from(byte) << 8;
            for _ in 0..8 {
                crc = if crc & 0x8000 != 0 {
                    (crc << 1) ^ 0x1021
                } else {
                    crc << 1
                };
            }
        }
        crc
    }

    #[test]
    fn crc16_check_value() {
        assert_eq!(crc16(b"123456789"), 0x29B1);
        assert_eq!(crc16_bitwise(b"123456789"), 0x29B1);
        assert_eq!(crc16(&[]), 0xFFFF);
        let data: Vec<u8> = (0..=255u8).chain((0..=255u8).rev()).collect();
        assert_eq!(crc16(&data), crc16_bitwise(&data));
        for b in 0..=255u8 {
            assert_eq!(crc16(&[b]), crc16_bitwise(&[b]));
        }
        // Incremental = one pass, wherever the split.
        for cut in 0..data.len() {
            assert_eq!(
                crc16_update(crc16(&data[..cut]), &data[cut..]),
                crc16(&data)
            );
        }
    }

    #[test]
    fn counts_and_dlcs() {
        assert_eq!(fragment_count(0), 1);
        assert_eq!(fragment_count(8), 1);
        assert_eq!(fragment_count(9), 2); // 11 wire bytes
        assert_eq!(fragment_count(14), 2); // 16 wire bytes
        assert_eq!(fragment_count(15), 3); // 17 wire bytes
        assert_eq!(fragment_count(MAX_PAYLOAD), 128);
        assert_eq!(fragment_count(MAX_PAYLOAD + 1), 129);
        assert_eq!(fragment_dlc(0, 0), Some(0));
        assert_eq!(fragment_dlc(9, 1), Some(8));
        assert_eq!(fragment_dlc(9, 0), Some(3));
        assert_eq!(fragment_dlc(9, 2), None);
        assert_eq!(fragment_dlc(MAX_PAYLOAD + 1, 0), None);
    }

    #[test]
    fn fragment_data_out_of_range_counter_is_empty() {
        let mut out = [0xAA; 8];
        assert_eq!(fragment_data(&[1, 2, 3], 0, 1, &mut out), 0);
        assert_eq!(out, [0; 8]);
    }

    #[test]
    fn lost_middle_fragment_is_out_of_order() {
        let p: Vec<u8> = (0..20).collect();
        let f = frames(&p);
        let mut buf = [0u8; 22];
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
        let mut buf = [0u8; 22];
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
        let mut buf = [0u8; 22];
        let mut rx = RxState::default();
        let short = Frame::new(f[0].id(), &[7; 7]).unwrap();
        assert_eq!(
            rx.step(&mut buf, 20, &short, 0),
            RxStep::Dropped(RxDrop::BadDlc)
        );
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
    }

    #[test]
    fn bad_crc_is_dropped() {
        let p: Vec<u8> = (0..20).collect();
        let mut f = frames(&p);
        let mut d = *f[1].raw_data();
        d[0] ^= 1;
        f[1] = Frame::from_parts(f[1].id(), 8, d).unwrap();
        let mut buf = [0u8; 22];
        let mut rx = RxState::default();
        for fr in &f[..2] {
            assert_eq!(rx.step(&mut buf, 20, fr, 0), RxStep::Pending);
        }
        assert_eq!(
            rx.step(&mut buf, 20, &f[2], 0),
            RxStep::Dropped(RxDrop::Crc)
        );
    }

    #[test]
    fn short_buffer_and_oversize_are_dropped() {
        let f = frames(&[0; 20]);
        let mut rx = RxState::default();
        assert_eq!(
            rx.step(&mut [0u8; 21], 20, &f[0], 0),
            RxStep::Dropped(RxDrop::BadSize)
        );
        assert_eq!(
            rx.step(&mut [0u8; 2000], MAX_PAYLOAD + 1, &f[0], 0),
            RxStep::Dropped(RxDrop::BadSize)
        );
    }
}
