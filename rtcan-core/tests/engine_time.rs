#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! Engine time arithmetic at the extremes: cycles longer than 2^32 ns (the slave's
//! cycle map and rate estimate) and forward clock jumps (poll must not walk the
//! elapsed slots one by one).
mod common;

use common::*;
use rtcan_core::driver::Event;
use rtcan_core::id::{Class, MsgId};
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::tables::{BusConfig, NodeTables, RxTopic, TxTopic};
use rtcan_core::Nanos;

const SPC: u8 = 10;
const LAX_UNIT: u64 = 100_000_000;
const SRT_ID: MsgId = MsgId(0x0150);

/// A bus of `SPC` slots of `slot_ns`; linear laxity in 100 ms units.
fn bus(slot_ns: Nanos) -> BusConfig {
    BusConfig {
        bitrate: 1_000_000,
        slots_per_cycle: SPC,
        slot_ns,
        hyperperiod_cycles: 1,
        cycle_counter_wrap: 1 << 15,
        laxity: LaxityEncoding::Linear {
            unit_ns: LAX_UNIT as u32,
        },
        guard_ns: 5_000,
        fingerprint: 7,
    }
}

/// Master (reserves slots 1 and 2 of every cycle for nobody: the free window opens at
/// slot 3) and a slave with one SRT topic of relative deadline `deadline_ns`.
fn two_nodes(slot_ns: Nanos, deadline_ns: Nanos, slave_ppm: f64) -> Bus {
    let masks: &'static [u64] = Box::leak(Box::new([0b111u64]));
    let master = NodeTables {
        bus: bus(slot_ns),
        module: 0,
        tx: &[],
        rx: Box::leak(Box::new([RxTopic {
            msg_id: SRT_ID,
            size: 4,
            arena_offset: 0,
        }])),
        calendar: &[],
        master_masks: masks,
    };
    let slave = NodeTables {
        bus: bus(slot_ns),
        module: 1,
        tx: Box::leak(Box::new([TxTopic {
            msg_id: SRT_ID,
            class: Class::Srt,
            size: 4,
            deadline_ns,
        }])),
        rx: &[],
        calendar: &[],
        master_masks: &[],
    };
    let mut b = Bus::new(1_000_000);
    b.add(master, 0.0, 0.0);
    b.add(slave, slave_ppm, 12_345.0);
    b
}

/// Submits on the slave 0.3 s into cycle `cycle` (slot 0: no window, so the frame is
/// loaded at the slot-3 boundary, 3 slots into the cycle) and returns the laxity code
/// of the frame on the wire.
fn laxity_code_on_wire(b: &mut Bus, slot_ns: Nanos, cycle: u64) -> u8 {
    let cycle_ns = slot_ns * SPC as u64;
    let start = slot_ns + cycle * cycle_ns; // master's cycle 0 starts one slot after t=0
    b.run(start + 300_000_000);
    assert!(
        b.nodes[1].engine.is_synced(),
        "slave synced by cycle {cycle}"
    );
    b.submit(1, 0, &[1, 2, 3, 4]).expect("queued");
    b.run(start + 3 * slot_ns + 10_000_000);
    let f: Vec<_> = b
        .log
        .iter()
        .filter(|w| w.frame.id().msg_id() == SRT_ID)
        .collect();
    assert_eq!(f.len(), 1, "one SRT frame");
    assert!(
        f[0].sof.abs_diff(start + 3 * slot_ns) < 20_000,
        "loaded at the slot-3 boundary: {} vs {}",
        f[0].sof,
        start + 3 * slot_ns
    );
    f[0].frame.id().laxity()
}

#[test]
fn five_second_cycle_gives_the_exact_laxity_code() {
    // 10 slots of 0.5 s. Submitted at 0.3 s with a 3.05 s deadline, loaded at 1.5 s:
    // 1.85 s left, code 1 + 18 = 19. (With the cycle map overflowing at cycles over
    // 2^32 ns the slave ran its bus time 7x slow inside the cycle and sent code 16.)
    let slot = 500_000_000;
    let mut b = two_nodes(slot, 3_050_000_000, 0.0);
    assert_eq!(laxity_code_on_wire(&mut b, slot, 2), 19);
    let mut b = two_nodes(slot, 3_050_000_000, 800.0);
    assert_eq!(laxity_code_on_wire(&mut b, slot, 3), 19, "drifting slave");
}

#[test]
fn longest_cycle_the_model_admits_syncs_and_gives_the_exact_laxity_code() {
    // `cycle_us` up to 10^9: 1000 s, 10 slots of 100 s. Submitted at 0.3 s with a
    // 304.75 s deadline (305.05 s into the cycle), loaded at 300 s: 5.05 s left, code
    // 1 + 50 = 51. The slave must measure its rate across 1000 s between syncs (it
    // relocked at every sync more than 8.6 s apart and never synced).
    let slot = 100_000_000_000;
    let mut b = two_nodes(slot, 304_750_000_000, 300.0);
    assert_eq!(laxity_code_on_wire(&mut b, slot, 2), 51);
    assert!(b.nodes[1].host.events.contains(&Event::Synced));
    assert_eq!(b.nodes[1].engine.counters().sync_missed, 0);
}
