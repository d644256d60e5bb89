//! Frame durations on the wire (docs/PROTOCOL.md §4). OWNER: codec helper. Signatures fixed.
//!
//! Two answers to "how long is this frame": `worst_case_bits` is the bound the schedule is
//! built on (slot length, window fitting), `exact_bits` is what one concrete frame takes
//! (simulator, tests that the bound holds).
use crate::frame::Frame;
use crate::time::Nanos;

/// Inter-frame space (intermission) in bits.
pub const INTERMISSION_BITS: u32 = 3;

/// Bits of an extended data frame exposed to stuffing, without data: SOF 1, base ID 11,
/// SRR 1, IDE 1, extended ID 18, RTR 1, r1 1, r0 1, DLC 4, CRC 15.
pub const STUFFED_OVERHEAD_BITS: u32 = 54;

/// Bits after the CRC sequence that are never stuffed: CRC delimiter 1, ACK slot 1,
/// ACK delimiter 1, EOF 7, plus the intermission 3.
pub const TAIL_BITS: u32 = 1 + 2 + 7 + INTERMISSION_BITS;

/// CAN CRC-15 generator (x^15 + x^14 + x^10 + x^8 + x^7 + x^4 + x^3 + 1).
pub const CRC15_POLY: u16 = 0x4599;

/// Worst-case length in bits of an extended data frame with `dlc` data bytes, with the
/// maximum number of stuff bits, including the 3-bit intermission. dlc > 8 counts as 8.
///
/// `g = 54 + 8*dlc` bits are stuffed; at most `floor((g - 1) / 4)` stuff bits fit in them
/// (the first run needs 5 equal bits, every later one 4 more because the stuff bit starts
/// the next run; Davis, Burns, Bril, Lukkien 2007).
pub const fn worst_case_bits(dlc: u8) -> u32 {
    let dlc = if dlc > 8 { 8 } else { dlc };
    let g = STUFFED_OVERHEAD_BITS + 8 * dlc as u32;
    g + (g - 1) / 4 + TAIL_BITS
}

/// Worst-case duration of a frame with `dlc` data bytes at `bitrate` bit/s, ns rounded up.
pub const fn worst_case_ns(dlc: u8, bitrate: u32) -> Nanos {
    bits_to_ns(worst_case_bits(dlc), bitrate)
}

/// Exact length in bits of this concrete frame (real stuff bits over SOF..CRC computed on
/// the actual ID, DLC, data and CRC-15), including EOF and the 3-bit intermission.
pub fn exact_bits(frame: &Frame) -> u32 {
    // Header SOF..DLC, 39 bits MSB first: SOF(0), ID[28:18], SRR(1), IDE(1), ID[17:0],
    // RTR(0), r1(0), r0(0), DLC.
    let id = u64::from(frame.id().raw());
    let header: u64 =
        ((id >> 18) << 27) | (0b11 << 25) | ((id & 0x3FFFF) << 7) | u64::from(frame.dlc());
    let data = frame.data();
    // Two independent table walks, interleaved so that their load chains overlap:
    //
    // CRC-15 over header and data, a byte at a time: the header padded to 40 bits with a
    // leading 0 (a 0 into a zero register leaves it zero), in the top 5 bytes of a word.
    //
    // Stuffing over header, data and CRC sequence (stuffed too, but not part of its own
    // computation), a byte at a time. Two leading recessive bits make the 54 + 8·dlc
    // stuffed bits a whole number of bytes without changing the count: from the state
    // "last 0, run 1" they stuff nothing, and the dominant SOF after them starts a fresh
    // run, as the first bit of a frame does. The 41-bit padded header is 5 bytes and one
    // bit carried into the next byte.
    let crc_header = (header << 24).to_be_bytes();
    let padded = (0b11 << 39) | header;
    let mut crc: u16 = 0;
    let mut state: StuffState = 0;
    let mut stuffed = 0u32;
    let mut feed = |byte: u8| {
        let e = stuff_byte(state, byte);
        state = e & 7;
        stuffed += u32::from(e >> 3);
    };
    for (&byte, shift) in crc_header.iter().zip([33, 25, 17, 9, 1]) {
        crc = crc15_byte(crc, byte);
        feed((padded >> shift) as u8);
    }
    let mut carry = (padded & 1) as u8;
    for &byte in data {
        crc = crc15_byte(crc, byte);
        feed((carry << 7) | (byte >> 1));
        carry = byte & 1;
    }
    let tail = (u16::from(carry) << 15) | crc;
    feed((tail >> 8) as u8);
    feed(tail as u8);
    let n = 39 + 8 * data.len() as u32 + 15;
    n + stuffed + TAIL_BITS
}

/// One byte through the CRC-15/CAN register (MSB first).
fn crc15_byte(crc: u16, byte: u8) -> u16 {
    let idx = ((crc >> 7) as u8 ^ byte) as usize;
    ((crc << 8) ^ CRC15_TABLE.get(idx).copied().unwrap_or(0)) & 0x7FFF
}

/// Byte-at-a-time table for CRC-15/CAN (MSB first).
// `static`, not `const`: see fragment.rs CRC16_TABLE. Built at compile time: an index
// out of range would be a build error, never a run-time panic.
#[allow(clippy::indexing_slicing)]
static CRC15_TABLE: [u16; 256] = {
    let mut t = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = (i as u16) << 7;
        let mut k = 0;
        while k < 8 {
            c = if c & 0x4000 != 0 {
                (c << 1) ^ CRC15_POLY
            } else {
                c << 1
            } & 0x7FFF;
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
};

/// Stuffing state between bits: `last << 2 | (run - 1)`, where `run` (1..=4) counts the
/// equal bits ending with `last` (a run of 5 is never a state: the stuff bit ends it).
type StuffState = u8;

/// One bit through the stuffing rule: after five equal bits a complementary stuff bit,
/// which itself starts the next run. Returns the new state and the stuff bits added.
const fn stuff_step(state: StuffState, bit: bool) -> (StuffState, u8) {
    let last = state >> 2 == 1;
    let run = (state & 3) + 1;
    if bit == last {
        if run == 4 {
            // Fifth equal bit: the stuff bit (!bit) starts a run of one.
            ((!bit as u8) << 2, 1)
        } else {
            (state + 1, 0)
        }
    } else {
        ((bit as u8) << 2, 0)
    }
}

/// One byte (MSB first) through the stuffing rule from `state`: the new state in bits
/// 0..3, the stuff bits added (at most 2) in bits 3..5. On the host (the simulator calls
/// this for every frame) a 2 KiB table; on a microcontroller, whose receive path needs it
/// once per frame and whose flash is budgeted, eight steps of the same rule.
#[cfg(not(target_os = "none"))]
fn stuff_byte(state: StuffState, byte: u8) -> u8 {
    STUFF_TABLE
        .get((usize::from(state) << 8) | usize::from(byte))
        .copied()
        .unwrap_or(0)
}

#[cfg(target_os = "none")]
fn stuff_byte(state: StuffState, byte: u8) -> u8 {
    stuff_byte_steps(state, byte)
}

#[cfg(any(test, target_os = "none"))]
fn stuff_byte_steps(mut state: StuffState, byte: u8) -> u8 {
    let mut added = 0;
    for k in (0..8).rev() {
        let (s, a) = stuff_step(state, (byte >> k) & 1 == 1);
        state = s;
        added += a;
    }
    state | (added << 3)
}

/// `stuff_byte` for every state and byte: entry `state << 8 | byte`.
// Built at compile time: an index out of range would be a build error.
#[allow(clippy::indexing_slicing)]
#[cfg(not(target_os = "none"))]
static STUFF_TABLE: [u8; 8 * 256] = {
    let mut t = [0u8; 8 * 256];
    let mut i = 0;
    while i < 8 * 256 {
        let mut state = (i >> 8) as StuffState;
        let mut added = 0;
        let mut k = 8;
        while k > 0 {
            k -= 1;
            let (s, a) = stuff_step(state, (i >> k) & 1 == 1);
            state = s;
            added += a;
        }
        t[i] = state | (added << 3);
        i += 1;
    }
    t
};

/// Exact frame duration at `bitrate` bit/s, ns rounded up.
pub fn exact_ns(frame: &Frame, bitrate: u32) -> Nanos {
    bits_to_ns(exact_bits(frame), bitrate)
}

/// `bits` at `bitrate` bit/s, in ns, rounded up.
pub const fn bits_to_ns(bits: u32, bitrate: u32) -> Nanos {
    (bits as u64 * 1_000_000_000).div_ceil(bitrate as u64)
}

/// Shortest slot that holds a worst-case 8-byte frame plus `guard_ns` (PROTOCOL.md §4.3).
pub const fn min_slot_ns(bitrate: u32, guard_ns: Nanos) -> Nanos {
    worst_case_ns(8, bitrate) + guard_ns
}

#[cfg(test)]
/// Reference model for the tests: serialises the stuffed part of a frame bit by bit, keeping the CRC-15 and the stuff
/// state; counts bits on the wire (stuff bits included).
struct BitWriter {
    crc: u16,
    bits: u32,
    last: bool,
    run: u32,
}

#[cfg(test)]
impl BitWriter {
    const fn new() -> Self {
        // `run = 0` so the SOF starts the first run whatever `last` says.
        BitWriter {
            crc: 0,
            bits: 0,
            last: true,
            run: 0,
        }
    }

    /// A bit covered by the CRC (SOF..data).
    fn push(&mut self, bit: bool) {
        let top = (self.crc >> 14) & 1 == 1;
        self.crc = (self.crc << 1) & 0x7FFF;
        if bit ^ top {
            self.crc ^= CRC15_POLY;
        }
        self.stuff(bit);
    }

    /// `n` low bits of `v`, most significant first.
    fn push_field(&mut self, v: u32, n: u32) {
        for i in (0..n).rev() {
            self.push((v >> i) & 1 == 1);
        }
    }

    /// Puts `bit` on the wire, inserting a complementary stuff bit after 5 equal bits.
    /// The stuff bit itself starts the next run (it may be the first of 5 equal bits).
    fn stuff(&mut self, bit: bool) {
        self.bits += 1;
        if self.run > 0 && bit == self.last {
            self.run += 1;
        } else {
            self.last = bit;
            self.run = 1;
        }
        if self.run == 5 {
            self.bits += 1;
            self.last = !bit;
            self.run = 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::id::CanId;

    /// The firmware's step-by-step byte stuffing equals the host's table everywhere.
    #[test]
    fn stuff_table_equals_the_step_rule() {
        for state in 0..8u8 {
            for byte in 0..=255u8 {
                assert_eq!(
                    stuff_byte(state, byte),
                    stuff_byte_steps(state, byte),
                    "{state} {byte:02X}"
                );
            }
        }
    }

    /// The bit-by-bit reference (`BitWriter`) and the fast path agree on every frame.
    #[test]
    fn fast_exact_bits_matches_the_bitwise_reference() {
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        for k in 0..20_000u32 {
            let r = next();
            // Mix random IDs with all-zero / all-one ones (maximal stuffing).
            let raw = match k % 4 {
                0 => 0,
                1 => CanId::MAX_RAW,
                _ => (r as u32) & CanId::MAX_RAW,
            };
            let dlc = (k % 9) as usize;
            let data = if k % 3 == 0 {
                [0u8; 8]
            } else {
                next().to_le_bytes()
            };
            let frame = Frame::new(CanId::from_raw(raw).unwrap(), &data[..dlc]).unwrap();
            let mut w = BitWriter::new();
            w.push(false);
            w.push_field(raw >> 18, 11);
            w.push(true);
            w.push(true);
            w.push_field(raw, 18);
            w.push(false);
            w.push(false);
            w.push(false);
            w.push_field(dlc as u32, 4);
            for &b in frame.data() {
                w.push_field(u32::from(b), 8);
            }
            let crc = w.crc;
            for i in (0..15).rev() {
                w.stuff((crc >> i) & 1 == 1);
            }
            assert_eq!(
                exact_bits(&frame),
                w.bits + TAIL_BITS,
                "frame {raw:08X} dlc {dlc}"
            );
        }
    }
}
