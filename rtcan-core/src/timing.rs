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
    let mut w = BitWriter::new();
    let id = frame.id().raw();
    w.push(false); // SOF, dominant
    w.push_field(id >> 18, 11); // base ID = ID[28:18]
    w.push(true); // SRR, recessive
    w.push(true); // IDE, recessive (extended frame)
    w.push_field(id, 18); // extension = ID[17:0]
    w.push(false); // RTR: data frame
    w.push(false); // r1
    w.push(false); // r0
    w.push_field(u32::from(frame.dlc()), 4);
    for &byte in frame.data() {
        w.push_field(u32::from(byte), 8);
    }
    let crc = w.crc;
    // The CRC sequence is stuffed but not part of its own computation.
    for i in (0..15).rev() {
        w.stuff((crc >> i) & 1 == 1);
    }
    w.bits + TAIL_BITS
}

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

/// Serialises the stuffed part of a frame bit by bit, keeping the CRC-15 and the stuff
/// state; counts bits on the wire (stuff bits included).
struct BitWriter {
    crc: u16,
    bits: u32,
    last: bool,
    run: u32,
}

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
