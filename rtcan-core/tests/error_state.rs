#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! Error-passive and bus-off reported by the driver (`Engine::on_error_state`,
//! docs/PROTOCOL.md §5.7) on the ideal bus of tests/common with the paper's schedule.
mod common;
mod paper_bus;

use common::*;
use paper_bus::*;
use rtcan_core::confinement::ErrorState;
use rtcan_core::driver::Event;
use rtcan_core::Nanos;

fn frames_of(bus: &Bus, n: usize, from: Nanos, to: Nanos) -> usize {
    bus.log
        .iter()
        .filter(|w| w.node == n && w.sof >= from && w.sof < to)
        .count()
}

const PASSIVE: ErrorState = ErrorState {
    tec: 130,
    rec: 3,
    bus_off: false,
};
const BUS_OFF: ErrorState = ErrorState {
    tec: 255,
    rec: 3,
    bus_off: true,
};
const RECOVERED: ErrorState = ErrorState {
    tec: 0,
    rec: 0,
    bus_off: false,
};

#[test]
fn error_passive_is_counted_and_the_module_keeps_its_slots() {
    let (mut bus, p) = paper_bus_with_backups();
    bus.run(10 * CYCLE_NS);
    report(&mut bus, 2, PASSIVE);
    report(&mut bus, 2, PASSIVE); // no new entry
    assert_eq!(bus.nodes[2].engine.counters().error_passive, 1);
    assert_eq!(bus.nodes[2].engine.error_state(), PASSIVE);
    assert_eq!(bus.nodes[2].engine.counters().bus_off, 0);
    let t = bus.now;
    bus.run(t + 10 * CYCLE_NS);
    assert!(bus.nodes[2].engine.is_synced());
    hrt_on_time(&bus, &p, 0, &[0, 1, 2], 8);
    // Back to active and passive again: a second entry.
    report(&mut bus, 2, RECOVERED);
    report(&mut bus, 2, PASSIVE);
    assert_eq!(bus.nodes[2].engine.counters().error_passive, 2);
}

#[test]
fn bus_off_slave_goes_silent_and_rejoins_only_after_resync() {
    let (mut bus, p) = paper_bus_with_backups();
    bus.run(10 * CYCLE_NS);
    let off = bus.now;
    report(&mut bus, 2, BUS_OFF);
    assert_eq!(bus.nodes[2].engine.counters().bus_off, 1);
    assert!(!bus.nodes[2].engine.is_synced());
    assert!(
        bus.nodes[2].can.mailboxes.iter().all(|m| m.is_none()),
        "mailboxes withdrawn"
    );
    assert_eq!(bus.nodes[2].host.events.last(), Some(&Event::SyncLost));
    // Bus-off for 20 cycles: longer than backup 2's takeover countdown, which must not run.
    bus.run(off + 20 * CYCLE_NS);
    assert_eq!(
        frames_of(&bus, 2, off + 1_000, bus.now),
        0,
        "silent while bus-off"
    );
    assert!(!bus.nodes[2].engine.is_master());
    let back = bus.now;
    report(&mut bus, 2, RECOVERED);
    bus.run(back + 20 * CYCLE_NS);
    assert!(bus.nodes[2].engine.is_synced());
    assert!(!bus.nodes[2].engine.is_master());
    // Nothing sent before the second sync after recovery (offset and rate known again).
    let second_sync = bus
        .log
        .iter()
        .filter(|w| w.sof > back && w.frame.id().is_sync())
        .nth(1)
        .unwrap()
        .sof;
    assert_eq!(frames_of(&bus, 2, back, second_sync), 0);
    assert!(frames_of(&bus, 2, second_sync, bus.now) > 0);
    hrt_on_time(&bus, &p, 0, &[0, 1, 2], 10);
    // Entries are counted, not states: a second bus-off is a second entry.
    report(&mut bus, 2, BUS_OFF);
    report(&mut bus, 2, BUS_OFF);
    assert_eq!(bus.nodes[2].engine.counters().bus_off, 2);
}

#[test]
fn bus_off_master_steps_down_and_defers_after_recovery() {
    let (mut bus, p) = paper_bus_with_backups();
    bus.run(10 * CYCLE_NS);
    let off = bus.now;
    report(&mut bus, 0, BUS_OFF);
    assert!(!bus.nodes[0].engine.is_master());
    bus.run(off + 30 * CYCLE_NS);
    assert!(bus.nodes[1].engine.is_master(), "backup 1 took over");
    assert_eq!(frames_of(&bus, 0, off + 1_000, bus.now), 0);
    let back = bus.now;
    report(&mut bus, 0, RECOVERED);
    bus.run(back + 30 * CYCLE_NS);
    let s = syncs(&bus, back);
    assert!(
        s.iter().all(|(n, _)| *n == 1),
        "the recovered master defers"
    );
    assert_eq!(two_sync_cycles(&s), Vec::<Nanos>::new());
    assert!(bus.nodes[0].engine.is_synced());
    hrt_on_time(&bus, &p, 1, &[0, 1, 2], 10);
}
