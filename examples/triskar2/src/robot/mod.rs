//! What `rtcan::robot!("robot.toml")` provides, per module of /robot.toml: the engine
//! tables and acceptance filters (copied from the rtcan-model plan of robot.toml,
//! fingerprint 0x734e658e, so a module built from another robot.toml is caught by the
//! fingerprint check in the heartbeats), the typed topics with their pools, the
//! engine-facing port lists and `host()`. Stand-in until rtcan-codegen lands; the
//! firmware uses only the names below, so switching is a change of this module.
use rtcan_core::id::{Class, MsgId};
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::tables::{BusConfig, CalEntry, RxTopic, TxTopic};
use rtcan_core::time::Nanos;

pub mod types;
pub use types::*;

pub mod gateway;
pub mod motor1;
pub mod motor2;
pub mod motor3;
pub mod proximity;
pub mod psu;

/// `[bus]` of robot.toml after planning: 1 Mbit/s, 60 slots of 166.666 µs, hyperperiod
/// 4 cycles (the 40 ms proximity topic).
pub const BUS: BusConfig = BusConfig {
    bitrate: 1_000_000,
    slots_per_cycle: 60,
    slot_ns: 166_666,
    hyperperiod_cycles: 4,
    cycle_counter_wrap: 32_768,
    laxity: LaxityEncoding::Linear { unit_ns: 200_000 },
    guard_ns: 5_000,
    fingerprint: 0x734e_658e,
};

/// Module index of the bus master (`gateway`).
pub const MASTER: u8 = 0;
/// Cycles without a master heartbeat before the safe state is required: three
/// heartbeat periods.
pub const MAX_MISSED_CYCLES: u16 = (3 * rtcan_core::engine::HEARTBEAT_CYCLES) as u16;

const fn tx(id: u16, class: Class, size: u16, deadline_ns: Nanos) -> TxTopic {
    TxTopic {
        msg_id: MsgId(id),
        class,
        size,
        deadline_ns,
    }
}

const fn rx(id: u16, size: u16, arena_offset: u16) -> RxTopic {
    RxTopic {
        msg_id: MsgId(id),
        size,
        arena_offset,
    }
}

const fn cal(slot: u32, tx: u8, fragment: u8) -> CalEntry {
    CalEntry { slot, tx, fragment }
}
