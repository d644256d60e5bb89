#![allow(dead_code)]
//! The RTCAN paper's benchmark (3 nodes, 60 slots, H_A/H_B/H_C HRT + SRT + NRT) on the
//! ideal bus of tests/common, with backups 1 and 2 armed, and the checks the arbitration
//! and fault tests share: syncs on the wire, cycles with two syncs, HRT in its slots.
use crate::common::*;
use rtcan_core::admission::{admit, build_masks, HrtRequest, Placement};
use rtcan_core::confinement::ErrorState;
use rtcan_core::fragment::wire_len;
use rtcan_core::id::{Class, MsgId};
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::tables::{BusConfig, CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_core::Nanos;

pub const SPC: u8 = 60;
pub const SLOT_NS: u64 = 166_666;
pub const FP: u32 = 0xC0FF_EE01;
/// Per node: H_A 1 ms (6 slots), H_B 5 ms (30), H_C 10 ms (60), then S (SRT, 20 B,
/// 10 ms deadline) and N (NRT, 8 B).
pub const PERIODS: [u32; 3] = [6, 30, 60];
pub const S_SIZE: u16 = 20;

pub fn msg_id(node: usize, topic: usize) -> MsgId {
    MsgId(0x0140 + (node as u16) * 16 + topic as u16)
}

pub fn bus() -> BusConfig {
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

pub struct Paper {
    pub tables: Vec<NodeTables<'static>>,
    pub placements: Vec<Placement>,
}

pub fn paper(nodes: usize) -> Paper {
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

pub const CYCLE_NS: u64 = SLOT_NS * SPC as u64;

pub fn arm_backups(bus: &mut Bus, p: &Paper) {
    let masks = p.tables[0].master_masks;
    for (n, rank) in [(1, 1), (2, 2)] {
        bus.nodes[n].engine.set_backup(rank, masks);
        let w = bus.nodes[n].engine.next_wakeup();
        bus.nodes[n].wake = bus.nodes[n].global(w);
    }
}

/// Sync frames on the wire after `from`: (node, SOF).
pub fn syncs(bus: &Bus, from: Nanos) -> Vec<(usize, Nanos)> {
    bus.log
        .iter()
        .filter(|w| w.sof >= from && w.frame.id().is_sync())
        .map(|w| (w.node, w.sof))
        .collect()
}

/// Cycles (of the bus's cycle length) in which two different modules sent a sync.
pub fn two_sync_cycles(s: &[(usize, Nanos)]) -> Vec<Nanos> {
    s.windows(2)
        .filter(|w| w[0].0 != w[1].0 && w[1].1 - w[0].1 < CYCLE_NS * 9 / 10)
        .map(|w| w[1].1)
        .collect()
}

/// Over the last `cycles` cycles of `master`'s syncs, every node in `nodes` sends its 3
/// HRT frames per 6 slots... exactly in the slots of its calendar relative to the master's
/// cycle starts.
pub fn hrt_on_time(bus: &Bus, p: &Paper, master: usize, nodes: &[usize], cycles: usize) {
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

pub fn paper_bus_with_backups() -> (Bus, Paper) {
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

/// The driver reports a fault-confinement state of node `n` now; aborts it requests are
/// resolved at once (a controller drops those frames).
pub fn report(bus: &mut Bus, n: usize, state: ErrorState) {
    let now = bus.now;
    let node = &mut bus.nodes[n];
    let local = node.local(now);
    node.engine
        .on_error_state(local, state, &mut node.can, &mut node.host);
    // Aborts requested by the engine: the controller drops those frames.
    for mb in node.can.abort_requests.drain(..).collect::<Vec<_>>() {
        if node.can.mailboxes[mb].take().is_some() {
            node.engine.on_tx_done(
                rtcan_core::driver::Mailbox(mb as u8),
                rtcan_core::driver::TxResult::Aborted,
                local,
                &mut node.can,
                &mut node.host,
            );
        }
    }
    node.wake = node.global(node.engine.next_wakeup());
}
