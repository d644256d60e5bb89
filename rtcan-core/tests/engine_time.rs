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
    let (master, slave) = tables(slot_ns, deadline_ns);
    let mut b = Bus::new(1_000_000);
    b.add(master, 0.0, 0.0);
    b.add(slave, slave_ppm, 12_345.0);
    b
}

/// Tables of `two_nodes`: (master, slave).
fn tables(slot_ns: Nanos, deadline_ns: Nanos) -> (NodeTables<'static>, NodeTables<'static>) {
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
    (master, slave)
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

/// 10 slots of 1 ms: a 10 ms cycle.
const SLOT: Nanos = 1_000_000;
const CYCLE: Nanos = SLOT * SPC as u64;
const HOUR: Nanos = 3_600_000_000_000;

/// Runs `f` on another thread and fails (instead of hanging) if it takes over 20 s.
fn within_20s<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(std::time::Duration::from_secs(20))
        .expect("poll returned within 20 s")
}

fn cycle_starts(b: &Bus) -> usize {
    b.nodes
        .iter()
        .map(|n| {
            n.host
                .events
                .iter()
                .filter(|e| **e == Event::CycleStart)
                .count()
        })
        .sum()
}

#[test]
fn master_clock_jump_of_one_hour_listens_first_then_syncs_on() {
    within_20s(|| {
        let mut b = two_nodes(SLOT, 50_000_000, 0.0);
        b.nodes[1].alive = false; // the master alone: its own clock defines bus time
                                  // Cycle 5, 3.5 slots in (cycle 0 starts at one slot).
        let t0 = SLOT + 5 * CYCLE + 3 * SLOT + SLOT / 2;
        b.run(t0);
        assert_eq!(cycle_starts(&b), 6);
        // The master's clock jumps one hour (360 000 cycles) forward. To the master this
        // is a stall of a whole cycle and more: another module may have taken over the
        // sync meanwhile, so it steps down and listens first (PROTOCOL §5.6 rule 1), in
        // O(1) whatever the jump (§5.8): no walk over the 360 000 cycles.
        b.nodes[0].offset += HOUR as f64;
        b.nodes[0].wake = b.now;
        b.run(t0 + SLOT);
        let e = &b.nodes[0].engine;
        assert!(!e.is_master(), "listens first after the stall");
        assert_eq!(b.nodes[0].host.events.last(), Some(&Event::SyncLost));
        assert_eq!(e.counters().hrt_late, 0);
        // Nobody else syncs: after takeover_cycles(0) = 4 silent cycles it takes the sync
        // back. Its cycle position follows its (jumped) clock: the stall landed in cycle
        // 360 005, it listened through 360 006..=360 009 and syncs from 360 010 on,
        // numbered on (§5.8: the master numbers cycles on its own clock).
        b.run(t0 + 7 * CYCLE);
        assert!(b.nodes[0].engine.is_master());
        let syncs: Vec<u32> = b
            .log
            .iter()
            .filter(|w| w.frame.id().is_sync() && w.sof > t0)
            .map(|w| w.frame.id().raw() & 0x7fff)
            .collect();
        assert!(!syncs.is_empty(), "syncs again after listening");
        assert!(syncs.len() <= 3, "silent for 4 of the 7 cycles: {syncs:?}");
        for w in syncs.windows(2) {
            assert_eq!(w[1], w[0] + 1, "numbered on: {syncs:?}");
        }
        assert_eq!(
            syncs[0],
            (360_010 % (1 << 15)) as u32,
            "cycle of the jumped clock"
        );
    });
}

#[test]
fn slave_clock_jump_of_one_hour_reports_sync_loss_and_relocks() {
    within_20s(|| {
        let mut b = two_nodes(SLOT, 50_000_000, 0.0);
        let t0 = SLOT + 5 * CYCLE + 3 * SLOT + SLOT / 2;
        b.run(t0);
        assert!(b.nodes[1].engine.is_synced());
        b.nodes[1].offset += HOUR as f64;
        b.nodes[1].wake = b.now;
        b.run(t0 + SLOT);
        let e = &b.nodes[1].engine;
        // Lands 3.5 slots into the cycle after 360 000 more: 359 999 never started.
        assert_eq!(e.counters().cycles_skipped, 359_999);
        assert!(!e.is_synced());
        assert_eq!(
            b.nodes[1].host.events.last(),
            Some(&Event::SyncLost),
            "the landing cycle is far past the last sync"
        );
        // The master's next syncs relock it (offset, then rate): synced again.
        b.run(t0 + 4 * CYCLE);
        assert!(b.nodes[1].engine.is_synced());
        assert_eq!(
            b.nodes[1]
                .host
                .events
                .iter()
                .filter(|e| **e == Event::Synced)
                .count(),
            2
        );
    });
}

#[test]
fn poll_near_the_end_of_time_returns_and_stops_for_good() {
    within_20s(|| {
        let (master, _) = tables(SLOT, 50_000_000);
        for now in [
            1u64 << 63,
            (1 << 63) + 12_345_678_901,
            u64::MAX - 5 * CYCLE,
            u64::MAX - 12_345,
            u64::MAX - 3 * SLOT / 2,
            u64::MAX,
        ] {
            let mut engine = TestEngine::new(master, 0);
            let (mut can, mut host) = (TestCan::default(), TestHost::default());
            // Created at 0, first polled at `now`: a stall of more than a cycle, so it
            // steps down and listens first (PROTOCOL §5.6 rule 1), then takes the sync
            // back after 4 silent cycles, or, within a few cycles of the end of u64 time
            // where boundaries would saturate and never pass, stops for good (§5.8).
            let mut t = engine.poll(now, &mut can, &mut host);
            assert!(t >= now, "now {now}: woke at {t}");
            assert!(!engine.is_master(), "listens first");
            let mut polls = 0;
            while t < u64::MAX && !engine.is_master() && polls < 1_000 {
                let n = engine.poll(t, &mut can, &mut host);
                assert!(n >= t, "{t} -> {n}");
                t = n;
                polls += 1;
            }
            if now > u64::MAX - 8 * CYCLE {
                // Whether or not it took the sync back first, polling at the end of time
                // stops it for good.
                let end = engine.poll(u64::MAX, &mut can, &mut host);
                assert_eq!(end, u64::MAX, "now {now}");
                assert_eq!(engine.poll(u64::MAX, &mut can, &mut host), u64::MAX);
                continue;
            }
            assert!(engine.is_master(), "now {now}: took the sync back");
            assert!(polls <= 4 * SPC as u32 + 8, "{polls} polls");
            // Then on as usual, one slot at a time.
            for _ in 0..40 {
                let n = engine.poll(t, &mut can, &mut host);
                assert!(n > t && n - t <= SLOT, "{t} -> {n}");
                t = n;
            }
        }
    });
}

#[test]
fn zero_slot_length_in_unchecked_tables_does_not_hang() {
    within_20s(|| {
        let (mut master, _) = tables(SLOT, 50_000_000);
        master.bus.slot_ns = 0;
        let mut engine = TestEngine::new(master, 0);
        let (mut can, mut host) = (TestCan::default(), TestHost::default());
        for now in [0, 5, 1_000, 3_600_000_000_000] {
            engine.poll(now, &mut can, &mut host);
        }
    });
}
