//! The sync frame (docs/PROTOCOL.md §3). OWNER: codec helper. Signatures fixed.
//!
//! Identifier = cycle counter (laxity 0, message ID high byte 0): recognisable by ID
//! alone and it wins arbitration against every other frame. Payload = the reservation
//! mask of the cycle it starts, little-endian.
use crate::frame::Frame;
use crate::id::CanId;

/// Cycle counter modulus: 15 bits (message ID low byte + fragment field).
pub const CYCLE_COUNTER_MODULUS: u32 = 1 << 15;

/// Most slots per cycle: the mask is at most 8 bytes.
pub const MAX_SLOTS: u8 = 64;

/// Contents of a sync frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sync {
    /// Cycle counter (< 2^15).
    pub cycle: u16,
    /// Reservation mask of the cycle this frame starts (bit k = slot k reserved).
    pub mask: u64,
}

/// DLC of the sync frame for `slots` slots per cycle: ceil(slots / 8), slots capped at 64.
pub const fn sync_dlc(slots: u8) -> u8 {
    let slots = if slots > MAX_SLOTS { MAX_SLOTS } else { slots };
    slots.div_ceil(8)
}

/// Mask of the bits a cycle of `slots` slots may use (bits `0..slots`).
pub const fn slots_mask(slots: u8) -> u64 {
    // In 32-bit halves: a 64-bit shift by a variable amount is a library call on the
    // Cortex-M3 at opt-level z (every sync frame parses this, issue 10).
    if slots >= MAX_SLOTS {
        u64::MAX
    } else if slots >= 32 {
        ((((1u32 << (slots - 32)) - 1) as u64) << 32) | u32::MAX as u64
    } else {
        ((1u32 << slots) - 1) as u64
    }
}

/// Largest multiple of `hyperperiod_cycles` that is <= 2^15: the master's cycle counter
/// wraps there so that `counter % hyperperiod` never jumps. `None` for a hyperperiod of 0
/// or above 2^15 cycles (such a bus is rejected by the model).
pub const fn cycle_counter_wrap(hyperperiod_cycles: u32) -> Option<u32> {
    if hyperperiod_cycles == 0 || hyperperiod_cycles > CYCLE_COUNTER_MODULUS {
        return None;
    }
    Some(CYCLE_COUNTER_MODULUS / hyperperiod_cycles * hyperperiod_cycles)
}

/// Builds the sync frame; `slots` is slots per cycle (DLC = ceil(slots/8)).
/// The frame is normalised so that it always parses: cycle taken mod 2^15, bit 0 (the sync
/// slot) set, bits >= `slots` cleared.
pub fn sync_frame(sync: Sync, slots: u8) -> Frame {
    let id = CanId::from_raw(u32::from(sync.cycle) % CYCLE_COUNTER_MODULUS).unwrap_or(SYNC_ID_0);
    let mask = (sync.mask | 1) & slots_mask(slots);
    Frame::from_parts(id, sync_dlc(slots), mask.to_le_bytes()).unwrap_or(EMPTY_SYNC)
}

/// Parses a frame whose ID `is_sync()`; `None` for garbage (wrong DLC, mask bits past
/// `slots`, slot 0 not reserved).
pub fn parse_sync(frame: &Frame, slots: u8) -> Option<Sync> {
    SyncFormat::new(slots).parse(frame)
}

/// The checks of `parse_sync` for a bus of `slots` slots, precomputed once (the engine
/// keeps one): the DLC and the mask bits a sync may not carry, so that a slave's sync
/// parses with two compares (issue 10: the sync's CPU time).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SyncFormat {
    /// `sync_dlc(slots)`; 0xFF (no frame has it) for an invalid slot count.
    dlc: u8,
    /// Bits checked in the mask: slot 0 (must be set) and every bit past `slots` (must
    /// be clear); the masked value must be exactly 1.
    checked: u64,
}

impl SyncFormat {
    /// For `slots` slots per cycle (1..=64; other counts parse nothing).
    pub const fn new(slots: u8) -> Self {
        if slots == 0 || slots > MAX_SLOTS {
            return SyncFormat {
                dlc: 0xFF,
                checked: u64::MAX,
            };
        }
        SyncFormat {
            dlc: sync_dlc(slots),
            checked: !slots_mask(slots) | 1,
        }
    }

    /// `parse_sync(frame, slots)`.
    pub fn parse(&self, frame: &Frame) -> Option<Sync> {
        let id = frame.id();
        if !id.is_sync() || frame.dlc() != self.dlc {
            return None;
        }
        // Bytes past the DLC are zero (a `Frame` invariant), so all 8 can be read.
        let mask = u64::from_le_bytes(*frame.raw_data());
        if mask & self.checked != 1 {
            return None;
        }
        Some(Sync {
            cycle: (id.raw() % CYCLE_COUNTER_MODULUS) as u16,
            mask,
        })
    }
}

/// Fallbacks for the two constructors `sync_frame` calls with arguments that are always in
/// range (raw ID < 2^15, DLC <= 8); built at compile time, so they cannot fail at run time.
#[allow(clippy::panic)]
const SYNC_ID_0: CanId = match CanId::from_raw(0) {
    Some(id) => id,
    None => panic!("0 is a valid identifier"),
};
#[allow(clippy::panic)]
const EMPTY_SYNC: Frame = match Frame::from_parts(SYNC_ID_0, 1, [1, 0, 0, 0, 0, 0, 0, 0]) {
    Some(f) => f,
    None => panic!("DLC 1 is valid"),
};

#[cfg(test)]
mod tests {
    #[test]
    fn slots_mask_in_halves_equals_the_64_bit_shift() {
        for slots in 0..=70u8 {
            let expect = if slots >= 64 {
                u64::MAX
            } else {
                (1u64 << slots) - 1
            };
            assert_eq!(super::slots_mask(slots), expect, "{slots}");
        }
    }

    use super::*;
    use crate::id::MsgId;

    /// `parse_sync` as specified (docs/PROTOCOL.md §3), check by check: the reference
    /// for the precomputed `SyncFormat`.
    fn parse_reference(frame: &Frame, slots: u8) -> Option<Sync> {
        let id = frame.id();
        if !id.is_sync() || slots == 0 || slots > MAX_SLOTS || frame.dlc() != sync_dlc(slots) {
            return None;
        }
        let mask = u64::from_le_bytes(*frame.raw_data());
        if mask & 1 == 0 || mask & !slots_mask(slots) != 0 {
            return None;
        }
        Some(Sync {
            cycle: (id.raw() % CYCLE_COUNTER_MODULUS) as u16,
            mask,
        })
    }

    #[test]
    fn precomputed_format_parses_as_the_reference() {
        let masks = [
            0u64,
            1,
            2,
            3,
            0xFF,
            0x1FF,
            0xFFFF_FFFF,
            0x1_FFFF_FFFF,
            u64::MAX,
            u64::MAX - 1,
            1 << 63 | 1,
            0x8000_0001,
        ];
        let ids = [
            CanId::from_raw(0),
            CanId::from_raw(12_345),
            CanId::from_raw(CYCLE_COUNTER_MODULUS - 1),
            CanId::new(1, MsgId(3), 0),
            CanId::new(0, MsgId(0x300), 5),
        ];
        let mut parsed = 0;
        for slots in 0..=70u8 {
            let format = SyncFormat::new(slots);
            for id in ids.into_iter().flatten() {
                for dlc in 0..=8u8 {
                    for mask in masks {
                        let Some(frame) = Frame::from_parts(id, dlc, mask.to_le_bytes()) else {
                            continue;
                        };
                        let want = parse_reference(&frame, slots);
                        parsed += usize::from(want.is_some());
                        assert_eq!(format.parse(&frame), want, "{slots} {id:?} {dlc} {mask:x}");
                        assert_eq!(parse_sync(&frame, slots), want);
                    }
                }
            }
        }
        assert!(parsed > 100, "only {parsed} valid syncs");
    }

    #[test]
    fn wrap_is_multiple_of_hyperperiod() {
        assert_eq!(cycle_counter_wrap(1), Some(32_768));
        assert_eq!(cycle_counter_wrap(3), Some(32_766));
        assert_eq!(cycle_counter_wrap(100), Some(32_700));
        assert_eq!(cycle_counter_wrap(32_768), Some(32_768));
        assert_eq!(cycle_counter_wrap(32_769), None);
        assert_eq!(cycle_counter_wrap(0), None);
    }

    #[test]
    fn round_trip_and_normalisation() {
        for slots in [1u8, 2, 8, 9, 40, 60, 63, 64] {
            let s = Sync {
                cycle: 0x7FFF,
                mask: 0x8000_0000_0000_0002,
            };
            let f = sync_frame(s, slots);
            assert_eq!(f.dlc(), slots.div_ceil(8));
            let p = parse_sync(&f, slots).unwrap();
            assert_eq!(p.cycle, 0x7FFF);
            assert_eq!(p.mask, (0x8000_0000_0000_0003) & slots_mask(slots));
        }
        // Cycle counter taken mod 2^15.
        assert_eq!(
            sync_frame(
                Sync {
                    cycle: 0x8005,
                    mask: 1
                },
                8
            )
            .id()
            .raw(),
            5
        );
    }

    #[test]
    fn garbage_is_rejected() {
        let id = CanId::from_raw(3).unwrap();
        // Slot 0 not reserved.
        assert_eq!(parse_sync(&Frame::new(id, &[0x02]).unwrap(), 8), None);
        // Bit 8 set with 8 slots would need DLC 2: wrong DLC.
        assert_eq!(parse_sync(&Frame::new(id, &[1, 1]).unwrap(), 8), None);
        // Bit 9 with 9 slots: past the cycle.
        assert_eq!(parse_sync(&Frame::new(id, &[1, 2]).unwrap(), 9), None);
        assert_eq!(
            parse_sync(&Frame::new(id, &[1, 1]).unwrap(), 9).map(|s| s.mask),
            Some(0x101)
        );
        // Not a sync ID (message ID 0x0100 = heartbeat of module 0).
        let hb = CanId::new(0, MsgId(0x100), 0).unwrap();
        assert_eq!(parse_sync(&Frame::new(hb, &[1]).unwrap(), 8), None);
        // Slot counts out of range.
        assert_eq!(parse_sync(&Frame::new(id, &[1]).unwrap(), 0), None);
        assert_eq!(parse_sync(&Frame::new(id, &[1; 8]).unwrap(), 65), None);
    }
}
