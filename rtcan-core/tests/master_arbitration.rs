#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! Sync-master arbitration in the engine (docs/PROTOCOL.md §5.6) on the ideal bus of
//! tests/common, with the RTCAN paper's benchmark schedule: a master that comes back after
//! a backup took over, a master absent from start-up, a cold-restarted master meeting a
//! running backup (split brain), a master restarted with `listen_first`.
mod common;
mod paper_bus;

use common::*;
use paper_bus::*;
use rtcan_core::arbiter::takeover_cycles;
use rtcan_core::confinement::ErrorState;
use rtcan_core::Nanos;

#[test]
fn returning_master_defers_to_the_backup_that_took_over() {
    let (mut bus, p) = paper_bus_with_backups();
    bus.run(10 * CYCLE_NS);
    bus.nodes[0].alive = false;
    let cut = bus.now;
    bus.run(cut + 30 * CYCLE_NS);
    assert!(bus.nodes[1].engine.is_master(), "backup 1 took over");
    // The master comes back (resumed with its stale state: a stall or a healed partition).
    bus.nodes[0].alive = true;
    let back = bus.now;
    bus.run(back + 40 * CYCLE_NS);
    let s = syncs(&bus, back);
    assert_eq!(
        two_sync_cycles(&s),
        Vec::<Nanos>::new(),
        "cycles with two syncs"
    );
    assert!(s.iter().all(|(n, _)| *n == 1), "only backup 1 sends syncs");
    assert!(s.len() >= 39, "{} syncs", s.len());
    assert!(!bus.nodes[0].engine.is_master(), "the old master deferred");
    assert!(bus.nodes[1].engine.is_master());
    assert!(
        bus.nodes[0].engine.is_synced(),
        "the old master follows the backup"
    );
    assert_eq!(bus.nodes[0].engine.counters().master_yields, 0);
    // TDMA intact for everyone, the returned master included.
    hrt_on_time(&bus, &p, 1, &[0, 1, 2], 20);
}

#[test]
fn backup_takes_over_when_the_master_is_absent_from_start_up() {
    let (mut bus, p) = paper_bus_with_backups();
    bus.nodes[0].alive = false;
    bus.run(30 * CYCLE_NS);
    assert!(bus.nodes[1].engine.is_master(), "backup 1 took over");
    assert!(
        !bus.nodes[2].engine.is_master(),
        "backup 2 follows backup 1"
    );
    assert!(bus.nodes[2].engine.is_synced());
    let s = syncs(&bus, 0);
    assert!(s.iter().all(|(n, _)| *n == 1));
    // The first sync comes takeover_cycles(1) cycles after backup 1 started (its local
    // time 0 is global -3.33 ms: offset 3 333 333 ns at +1000 ppm), plus one slot.
    let start = bus.nodes[1].global(bus.nodes[1].local(0) - 3_333_333);
    let expect = start + u64::from(takeover_cycles(1)) * CYCLE_NS + SLOT_NS;
    let first = s[0].1;
    assert!(
        first.abs_diff(expect) < CYCLE_NS / 100,
        "first sync at {first}, expected about {expect}"
    );
    assert!(
        s.len() >= 30 - takeover_cycles(1) as usize - 2,
        "{} syncs",
        s.len()
    );
    hrt_on_time(&bus, &p, 1, &[1, 2], 15);
}

#[test]
fn cold_restarted_master_and_running_backup_resolve_split_brain_within_two_cycles() {
    let (mut bus, p) = paper_bus_with_backups();
    bus.run(10 * CYCLE_NS);
    bus.nodes[0].alive = false;
    let cut = bus.now;
    bus.run(cut + 30 * CYCLE_NS);
    assert!(bus.nodes[1].engine.is_master());
    // The master is power-cycled: a fresh engine that starts as master at once, restarted
    // just after a sync of the backup, so that its own first sync (one slot later) comes
    // before the backup's next one: two syncs within one cycle.
    let seen = syncs(&bus, cut).len();
    while syncs(&bus, cut).len() == seen {
        let t = bus.now + SLOT_NS / 4;
        bus.run(t);
    }
    let back = bus.now;
    let n = &mut bus.nodes[0];
    n.engine = TestEngine::new(p.tables[0], n.local(back));
    n.can = TestCan::default();
    n.wake = n.global(n.engine.next_wakeup());
    n.alive = true;
    bus.run(back + 60 * CYCLE_NS);
    // From the backup's sync just before the restart.
    let s = syncs(&bus, back - 2 * SLOT_NS);
    let twos = two_sync_cycles(&s);
    assert!(!twos.is_empty(), "the cold start did collide");
    assert!(
        twos.iter().all(|t| *t < back + 2 * CYCLE_NS),
        "split brain lasted past 2 cycles: {twos:?}"
    );
    let masters: Vec<usize> = (0..3)
        .filter(|&i| bus.nodes[i].engine.is_master())
        .collect();
    assert_eq!(masters.len(), 1, "exactly one master: {masters:?}");
    let yields: u32 = (0..3)
        .map(|i| bus.nodes[i].engine.counters().master_yields)
        .sum();
    assert!(yields >= 1);
    // After the re-election the bus runs normally again.
    hrt_on_time(&bus, &p, masters[0], &[0, 1, 2], 20);
}

#[test]
fn master_restarted_with_listen_first_never_collides() {
    let (mut bus, p) = paper_bus_with_backups();
    bus.run(10 * CYCLE_NS);
    bus.nodes[0].alive = false;
    let cut = bus.now;
    bus.run(cut + 30 * CYCLE_NS);
    let back = bus.now;
    let n = &mut bus.nodes[0];
    n.engine = TestEngine::new(p.tables[0], n.local(back));
    n.engine.listen_first();
    assert!(!n.engine.is_master());
    n.can = TestCan::default();
    n.wake = n.global(n.engine.next_wakeup());
    n.alive = true;
    bus.run(back + 30 * CYCLE_NS);
    let s = syncs(&bus, back);
    assert_eq!(two_sync_cycles(&s), Vec::<Nanos>::new());
    assert!(s.iter().all(|(n, _)| *n == 1));
    assert!(bus.nodes[0].engine.is_synced());
    hrt_on_time(&bus, &p, 1, &[0, 1, 2], 20);
    // And if the backup dies now, the restarted master (rank 0) takes over again first.
    bus.nodes[1].alive = false;
    let cut = bus.now;
    bus.run(cut + 30 * CYCLE_NS);
    assert!(bus.nodes[0].engine.is_master());
    assert!(!bus.nodes[2].engine.is_master());
    let s = syncs(&bus, cut);
    assert_eq!(two_sync_cycles(&s), Vec::<Nanos>::new());
    hrt_on_time(&bus, &p, 0, &[0, 2], 15);
}

#[test]
fn returning_backup_follows_the_running_master() {
    let (mut bus, p) = paper_bus_with_backups();
    bus.run(10 * CYCLE_NS);
    bus.nodes[2].alive = false;
    let cut = bus.now;
    bus.run(cut + 30 * CYCLE_NS);
    bus.nodes[2].alive = true;
    let back = bus.now;
    bus.run(back + 30 * CYCLE_NS);
    let s = syncs(&bus, cut);
    assert!(
        s.iter().all(|(n, _)| *n == 0),
        "only the master sends syncs"
    );
    assert_eq!(two_sync_cycles(&s), Vec::<Nanos>::new());
    assert!(bus.nodes[2].engine.is_synced() && !bus.nodes[2].engine.is_master());
    hrt_on_time(&bus, &p, 0, &[0, 1, 2], 20);
}

#[test]
fn chain_of_failures_and_returns_keeps_one_master() {
    let (mut bus, p) = paper_bus_with_backups();
    bus.run(10 * CYCLE_NS);
    // Master dies: backup 1 takes over. Backup 1 dies: backup 2 takes over.
    bus.nodes[0].alive = false;
    let t = bus.now;
    bus.run(t + 20 * CYCLE_NS);
    assert!(bus.nodes[1].engine.is_master());
    bus.nodes[1].alive = false;
    let t = bus.now;
    bus.run(t + 20 * CYCLE_NS);
    assert!(bus.nodes[2].engine.is_master());
    // Both come back (resumed): they defer to backup 2.
    bus.nodes[0].alive = true;
    let t = bus.now;
    bus.run(t + 3 * CYCLE_NS);
    bus.nodes[1].alive = true;
    let back = bus.now;
    bus.run(back + 30 * CYCLE_NS);
    let s = syncs(&bus, 0);
    assert_eq!(
        two_sync_cycles(&s),
        Vec::<Nanos>::new(),
        "no cycle with two syncs, ever"
    );
    assert!(syncs(&bus, t).iter().all(|(n, _)| *n == 2));
    let masters: Vec<usize> = (0..3)
        .filter(|&i| bus.nodes[i].engine.is_master())
        .collect();
    assert_eq!(masters, vec![2]);
    hrt_on_time(&bus, &p, 2, &[0, 1, 2], 20);
}

/// A fail/return event of the randomised engine-level check.
#[derive(Clone, Copy, Debug)]
enum Fault {
    /// Node dies (stops polling and receiving).
    Die(usize),
    /// Node comes back with its stale state (stall, healed partition).
    Resume(usize),
    /// Node is reset: a fresh engine (node 0: cold master, or listening first).
    Reset(usize, bool),
    /// Node's controller goes bus-off.
    BusOff(usize),
    /// Node's controller recovers (error-active, counters 0).
    Recover(usize),
}

fn fault() -> impl proptest::strategy::Strategy<Value = (u64, Fault)> {
    use proptest::prelude::*;
    (
        0u64..12,
        prop_oneof![
            (0usize..3).prop_map(Fault::Die),
            (0usize..3).prop_map(Fault::Resume),
            (0usize..3, any::<bool>()).prop_map(|(n, c)| Fault::Reset(n, c)),
            (0usize..3).prop_map(Fault::BusOff),
            (0usize..3).prop_map(Fault::Recover),
        ],
    )
}

proptest::proptest! {
    #![proptest_config(proptest::test_runner::Config {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x4D41_5354_4552),
        failure_persistence: None,
        ..proptest::test_runner::Config::default()
    })]

    /// The engine under random fail/return/reset/bus-off sequences (gaps in cycles): split brains
    /// last at most 2 cycles, and `CONVERGE` cycles after the last event exactly one live
    /// module is master, alone on the bus, and everyone alive follows it.
    #[test]
    fn engine_converges_after_any_fault_sequence(faults in proptest::collection::vec(fault(), 1..5)) {
        const CONVERGE: u64 = 2 * (takeover_cycles(2) as u64 + 1) + 1;
        let (mut bus, p) = paper_bus_with_backups();
        bus.run(8 * CYCLE_NS);
        for (gap, f) in faults {
            let t = bus.now + gap * CYCLE_NS;
            bus.run(t);
            match f {
                Fault::Die(n) => bus.nodes[n].alive = false,
                Fault::Resume(n) => bus.nodes[n].alive = true,
                Fault::BusOff(n) => report(&mut bus, n, ErrorState { tec: 256, rec: 0, bus_off: true }),
                Fault::Recover(n) => report(&mut bus, n, ErrorState::default()),
                Fault::Reset(n, cold) => {
                    let now = bus.now;
                    let node = &mut bus.nodes[n];
                    node.engine = TestEngine::new(p.tables[n], node.local(now));
                    if n > 0 {
                        node.engine.set_backup(n as u8, p.tables[0].master_masks);
                    } else if !cold {
                        node.engine.listen_first();
                    }
                    // The controller is reset too, except a frame already on the wire.
                    for (m, slot) in node.can.mailboxes.iter_mut().enumerate() {
                        if node.can.on_wire != Some(m) {
                            *slot = None;
                        }
                    }
                    node.can.abort_requests.clear();
                    node.wake = node.global(node.engine.next_wakeup());
                    node.alive = true;
                }
            }
        }
        let last = bus.now;
        bus.run(last + (CONVERGE + 10) * CYCLE_NS);
        // Split brains: runs of cycles with two syncs, at most 2 cycles long.
        let s = syncs(&bus, 0);
        let twos = two_sync_cycles(&s);
        for w in twos.windows(3) {
            proptest::prop_assert!(w[2] - w[0] > 2 * CYCLE_NS + CYCLE_NS / 2, "split brain over 3 cycles at {w:?}");
        }
        // Bus-off nodes are off the bus: they count as dead.
        let alive: Vec<usize> = (0..3)
            .filter(|&i| bus.nodes[i].alive && !bus.nodes[i].engine.error_state().bus_off)
            .collect();
        if alive.is_empty() {
            return Ok(());
        }
        let masters: Vec<usize> = alive.iter().copied().filter(|&i| bus.nodes[i].engine.is_master()).collect();
        proptest::prop_assert_eq!(masters.len(), 1, "masters {:?}", masters);
        let tail = syncs(&bus, last + CONVERGE * CYCLE_NS);
        proptest::prop_assert!(tail.len() >= 9, "{} syncs in the last 10 cycles", tail.len());
        proptest::prop_assert!(tail.iter().all(|(n, _)| *n == masters[0]));
        proptest::prop_assert!(two_sync_cycles(&tail).is_empty());
        for &i in &alive {
            proptest::prop_assert!(bus.nodes[i].engine.is_synced(), "node {} not synced", i);
        }
    }
}

/// A backup stalled while still listening (it had not heard a sync yet) is past its
/// takeover time when it comes back: it must listen again, not take over at once.
#[test]
fn backup_stalled_while_listening_listens_again() {
    let (mut bus, p) = paper_bus_with_backups();
    bus.nodes[2].alive = false;
    bus.run(30 * CYCLE_NS);
    // Back just after a sync of the master: a module that did not listen would send its
    // own sync long before the master's next one.
    let seen = syncs(&bus, 0).len();
    while syncs(&bus, 0).len() == seen {
        let t = bus.now + SLOT_NS / 4;
        bus.run(t);
    }
    bus.nodes[2].alive = true;
    let back = bus.now;
    bus.run(back + 20 * CYCLE_NS);
    assert_eq!(bus.nodes[2].engine.counters().master_yields, 0);
    let s = syncs(&bus, 0);
    assert!(
        s.iter().all(|(n, _)| *n == 0),
        "only the master sends syncs"
    );
    assert_eq!(two_sync_cycles(&s), Vec::<Nanos>::new());
    assert!(bus.nodes[2].engine.is_synced() && !bus.nodes[2].engine.is_master());
    hrt_on_time(&bus, &p, 0, &[0, 1, 2], 10);
}
