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

use common::*;
use rtcan_core::admission::{admit, build_masks, HrtRequest, Placement};
use rtcan_core::arbiter::takeover_cycles;
use rtcan_core::fragment::wire_len;
use rtcan_core::id::{Class, MsgId};
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::tables::{BusConfig, CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_core::Nanos;

const SPC: u8 = 60;
const SLOT_NS: u64 = 166_666;
const FP: u32 = 0xC0FF_EE01;
/// Per node: H_A 1 ms (6 slots), H_B 5 ms (30), H_C 10 ms (60), then S (SRT, 20 B,
/// 10 ms deadline) and N (NRT, 8 B).
const PERIODS: [u32; 3] = [6, 30, 60];
const S_SIZE: u16 = 20;

fn msg_id(node: usize, topic: usize) -> MsgId {
    MsgId(0x0140 + (node as u16) * 16 + topic as u16)
}

fn bus() -> BusConfig {
    BusConfig {
        bitrate: 1_000_000,
        slots_per_cycle: SPC,
        slot_ns: SLOT_NS,
        hyperperiod_cycles: 1,
        cycle_counter_wrap: 1 << 15,
        laxity: LaxityEncoding::Linear {
            unit_ns: SLOT_NS as u32,
        },
        guard_ns: 2_000,
        fingerprint: FP,
    }
}

struct Paper {
    tables: Vec<NodeTables<'static>>,
    placements: Vec<Placement>,
}

fn paper(nodes: usize) -> Paper {
    let reqs: Vec<HrtRequest> = (0..nodes)
        .flat_map(|_| {
            PERIODS.iter().map(|&p| HrtRequest {
                period_slots: p,
                fragments: 1,
            })
        })
        .collect();
    let mut placements = vec![Placement::default(); reqs.len()];
    admit(SPC as u32, &reqs, &mut placements, 1_000_000).expect("paper set is admissible");
    let mut masks = vec![0u64; 1];
    let cycles = build_masks(SPC as u32, &reqs, &placements, &mut masks).expect("masks");
    assert_eq!(cycles, 1);
    let masks: &'static [u64] = Box::leak(masks.into_boxed_slice());
    let mut tables = Vec::new();
    for n in 0..nodes {
        let mut tx = Vec::new();
        for (k, _) in PERIODS.iter().enumerate() {
            tx.push(TxTopic {
                msg_id: msg_id(n, k),
                class: Class::Hrt,
                size: 8,
                deadline_ns: 0,
            });
        }
        tx.push(TxTopic {
            msg_id: msg_id(n, 3),
            class: Class::Srt,
            size: S_SIZE,
            deadline_ns: 10_000_000,
        });
        tx.push(TxTopic {
            msg_id: msg_id(n, 4),
            class: Class::Nrt,
            size: 8,
            deadline_ns: 0,
        });
        let mut cal = Vec::new();
        for k in 0..PERIODS.len() {
            let pl = placements[n * 3 + k];
            let mut s = pl.phase_slot;
            while s < SPC as u32 {
                cal.push(CalEntry {
                    slot: s,
                    tx: k as u8,
                    fragment: 0,
                });
                s += PERIODS[k];
            }
        }
        cal.sort_by_key(|c| c.slot);
        let mut rx = Vec::new();
        let mut off = 0u16;
        for m in (0..nodes).filter(|&m| m != n) {
            for k in 0..5 {
                let size = if k == 3 { S_SIZE } else { 8 };
                rx.push(RxTopic {
                    msg_id: msg_id(m, k),
                    size,
                    arena_offset: 0,
                });
            }
        }
        rx.sort_by_key(|r| r.msg_id);
        for r in rx.iter_mut() {
            r.arena_offset = off;
            off += wire_len(r.size as usize) as u16;
        }
        tables.push(NodeTables {
            bus: bus(),
            module: n as u8,
            tx: Box::leak(tx.into_boxed_slice()),
            rx: Box::leak(rx.into_boxed_slice()),
            calendar: Box::leak(cal.into_boxed_slice()),
            master_masks: if n == 0 { masks } else { &[] },
        });
    }
    Paper { tables, placements }
}

const CYCLE_NS: u64 = SLOT_NS * SPC as u64;

fn arm_backups(bus: &mut Bus, p: &Paper) {
    let masks = p.tables[0].master_masks;
    for (n, rank) in [(1, 1), (2, 2)] {
        bus.nodes[n].engine.set_backup(rank, masks);
        let w = bus.nodes[n].engine.next_wakeup();
        bus.nodes[n].wake = bus.nodes[n].global(w);
    }
}

/// Sync frames on the wire after `from`: (node, SOF).
fn syncs(bus: &Bus, from: Nanos) -> Vec<(usize, Nanos)> {
    bus.log
        .iter()
        .filter(|w| w.sof >= from && w.frame.id().is_sync())
        .map(|w| (w.node, w.sof))
        .collect()
}

/// Cycles (of the bus's cycle length) in which two different modules sent a sync.
fn two_sync_cycles(s: &[(usize, Nanos)]) -> Vec<Nanos> {
    s.windows(2)
        .filter(|w| w[0].0 != w[1].0 && w[1].1 - w[0].1 < CYCLE_NS * 9 / 10)
        .map(|w| w[1].1)
        .collect()
}

/// Over the last `cycles` cycles of `master`'s syncs, every node in `nodes` sends its 3
/// HRT frames per 6 slots... exactly in the slots of its calendar relative to the master's
/// cycle starts.
fn hrt_on_time(bus: &Bus, p: &Paper, master: usize, nodes: &[usize], cycles: usize) {
    let ms: Vec<Nanos> = bus
        .log
        .iter()
        .filter(|w| w.node == master && w.frame.id().is_sync())
        .map(|w| w.sof)
        .collect();
    assert!(
        ms.len() > cycles,
        "only {} syncs from node {master}",
        ms.len()
    );
    for pair in ms[ms.len() - cycles - 1..].windows(2) {
        let (start, end) = (pair[0], pair[1]);
        let slot_of = |t: u64| (t - start) * SPC as u64 / (end - start);
        for &n in nodes {
            let hrt: Vec<_> = bus
                .log
                .iter()
                .filter(|w| {
                    w.node == n
                        && w.sof >= start
                        && w.sof < end
                        && w.frame.id().laxity() == 0
                        && !w.frame.id().is_sync()
                })
                .collect();
            assert_eq!(hrt.len(), 13, "node {n} HRT frames in cycle at {start}");
            for w in hrt {
                let k = ((w.frame.id().msg_id().0 - 0x140) % 16) as usize;
                let slot = slot_of(w.sof + 1_000);
                let phase = p.placements[n * 3 + k].phase_slot as u64;
                assert_eq!(
                    slot % PERIODS[k] as u64,
                    phase % PERIODS[k] as u64,
                    "node {n} topic {k} at {}",
                    w.sof
                );
            }
        }
    }
}

fn paper_bus_with_backups() -> (Bus, Paper) {
    let p = paper(3);
    let mut bus = Bus::new(1_000_000);
    let drift = [0.0, 1000.0, -1000.0];
    let offset = [0.0, 3_333_333.0, 17_000.0];
    for (n, t) in p.tables.iter().enumerate() {
        bus.add(*t, drift[n], offset[n]);
        bus.nodes[n].host.hrt = (0..3)
            .map(|k| Some(vec![n as u8, k as u8, 0, 0, 0, 0, 0, 0xAA]))
            .collect();
    }
    arm_backups(&mut bus, &p);
    (bus, p)
}

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
