//! Per-module constant tables. `rtcan-codegen` generates them from robot.toml (after
//! admission), so a node carries exactly its own schedule, topics and filters.
use crate::id::{Class, MsgId};
use crate::laxity::LaxityEncoding;
use crate::time::Nanos;

/// Bus-wide parameters (identical in every module of a robot).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BusConfig {
    /// Bit rate in bit/s.
    pub bitrate: u32,
    /// Slots per cycle, 2..=64 (slot 0 is the sync slot).
    pub slots_per_cycle: u8,
    /// Slot length in ns (cycle period / slots_per_cycle).
    pub slot_ns: Nanos,
    /// Cycles in one hyperperiod of the HRT schedule (the calendar repeats after it).
    pub hyperperiod_cycles: u32,
    /// The master's cycle counter wraps at this value, a multiple of
    /// `hyperperiod_cycles` that fits the 15-bit counter of the sync frame.
    pub cycle_counter_wrap: u32,
    /// SRT laxity encoding of this bus.
    pub laxity: LaxityEncoding,
    /// Guard subtracted from every window end (ISR latency, clock error), ns.
    pub guard_ns: Nanos,
    /// Robot-description fingerprint carried in heartbeats.
    pub fingerprint: u32,
}

impl BusConfig {
    /// Cycle length in ns.
    pub const fn cycle_ns(&self) -> Nanos {
        self.slot_ns * self.slots_per_cycle as Nanos
    }
    /// Bit time in ns (rounded down).
    pub const fn bit_ns(&self) -> Nanos {
        1_000_000_000 / self.bitrate as Nanos
    }
}

/// One topic this module transmits. Index in `NodeTables::tx` = `TxIndex`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TxTopic {
    /// Message ID on the wire.
    pub msg_id: MsgId,
    /// Class.
    pub class: Class,
    /// Payload size in bytes (fixed at compile time).
    pub size: u16,
    /// Relative deadline for SRT (ns); ignored for HRT and NRT.
    pub deadline_ns: Nanos,
}

/// One topic this module receives. Index in `NodeTables::rx` = `RxIndex`.
/// `NodeTables::rx` is sorted by `msg_id` (binary search on receive).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RxTopic {
    /// Message ID on the wire.
    pub msg_id: MsgId,
    /// Payload size in bytes.
    pub size: u16,
    /// Offset of this topic's reassembly buffer in the RX arena (bytes).
    pub arena_offset: u16,
}

/// One reserved slot of this module in the hyperperiod calendar.
/// `NodeTables::calendar` is sorted by `slot`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CalEntry {
    /// Slot index from slot 0 of cycle 0 of the hyperperiod.
    pub slot: u32,
    /// Which transmitted topic (index into `NodeTables::tx`).
    pub tx: u8,
    /// Fragment counter sent in this slot (counts down; 0 = last).
    pub fragment: u8,
}

/// Everything the engine of one module needs, all `'static` constants in firmware.
#[derive(Clone, Copy, Debug)]
pub struct NodeTables<'a> {
    /// Bus parameters.
    pub bus: BusConfig,
    /// Module index in the robot (heartbeat message ID = HEARTBEAT_BASE + module).
    pub module: u8,
    /// Topics this module transmits.
    pub tx: &'a [TxTopic],
    /// Topics this module receives, sorted by msg_id.
    pub rx: &'a [RxTopic],
    /// This module's HRT slots, sorted by slot.
    pub calendar: &'a [CalEntry],
    /// Master only: the reservation mask of every cycle of the hyperperiod (bit k = slot k).
    /// Empty on slaves.
    pub master_masks: &'a [u64],
}
