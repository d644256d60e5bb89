//! The RTCAN paper's §4 benchmark, built by hand: 1 Mbit/s, 10 ms cycle of 60 slots,
//! three nodes, each with HRT H_A (1 ms), H_B (5 ms), H_C (10 ms) of 8 bytes in the
//! calendar of the paper's Fig. 3, and SRT 5 × S_A (deadline 10 ms, events every
//! 10–20 ms, 8 B), 5 × S_B (10 ms, 20–50 ms, 16 B), 5 × S_C (50 ms, 50–100 ms, 20 B).
use rtcan_core::id::FIRST_TOPIC_MSG_ID;
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::sync::cycle_counter_wrap;
use rtcan_core::tables::{BusConfig, CalEntry, RxTopic, TxTopic};
use rtcan_core::{Class, MsgId, Nanos};

use crate::tables::OwnedTables;
use crate::traffic::Gen;

/// Nodes of the benchmark.
pub const NODES: usize = 3;
/// Slots per cycle.
pub const SLOTS: u8 = 60;
/// Cycle length asked for, ns (the slot is rounded down to whole ns).
pub const CYCLE_NS: Nanos = 10_000_000;
const MS: Nanos = 1_000_000;

/// One SRT class of Table 2.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SrtClass {
    /// Name (S_A, S_B, S_C).
    pub name: &'static str,
    /// Relative deadline, ns.
    pub deadline_ns: Nanos,
    /// Event inter-arrival range, ns.
    pub every_ns: (Nanos, Nanos),
    /// Payload bytes.
    pub size: u16,
}

/// Table 2.
pub const SRT_CLASSES: [SrtClass; 3] = [
    SrtClass {
        name: "S_A",
        deadline_ns: 10 * MS,
        every_ns: (10 * MS, 20 * MS),
        size: 8,
    },
    SrtClass {
        name: "S_B",
        deadline_ns: 10 * MS,
        every_ns: (20 * MS, 50 * MS),
        size: 16,
    },
    SrtClass {
        name: "S_C",
        deadline_ns: 50 * MS,
        every_ns: (50 * MS, 100 * MS),
        size: 20,
    },
];
/// Messages per class per node.
pub const PER_CLASS: usize = 5;
/// HRT names and periods in slots (Table 1 on 60 slots of 1/6 ms): 1 ms, 5 ms, 10 ms.
pub const HRT: [(&str, u32); 3] = [("H_A", 6), ("H_B", 30), ("H_C", 60)];
/// First slot of H_A, H_B, H_C of node 0 (Fig. 3); node n is n slots later.
const HRT_PHASE: [u32; 3] = [1, 4, 10];
/// Guard before each reserved slot, ns (the paper's 5 µs slot separation).
pub const GUARD_NS: Nanos = 5_000;

/// Bus parameters with the given laxity encoding.
pub fn bus_config(laxity: LaxityEncoding) -> BusConfig {
    BusConfig {
        bitrate: 1_000_000,
        slots_per_cycle: SLOTS,
        slot_ns: CYCLE_NS / Nanos::from(SLOTS),
        hyperperiod_cycles: 1,
        cycle_counter_wrap: cycle_counter_wrap(1).unwrap_or(1 << 15),
        laxity,
        guard_ns: GUARD_NS,
        fingerprint: 0x5A5A_2014,
    }
}

/// Our encoding: logarithmic, unit chosen so that the longest deadline (50 ms) still
/// has distinct codes (the plan would choose it the same way from the topics).
pub fn our_laxity() -> LaxityEncoding {
    let mut unit = 1_000u32;
    while (LaxityEncoding::Log { unit_ns: unit }).max_laxity_ns() < 50 * MS && unit < 1_000_000 {
        unit += 1_000;
    }
    LaxityEncoding::Log { unit_ns: unit }
}

/// The paper's encoding as published by the 2014 code: linear, 1 ms per code.
pub const PAPER_LAXITY: LaxityEncoding = LaxityEncoding::Linear { unit_ns: 1_000_000 };

/// Message ID of topic `t` of node `n`.
pub fn msg_id(node: usize, topic: usize) -> MsgId {
    MsgId(FIRST_TOPIC_MSG_ID + (node * 32 + topic) as u16)
}

/// Topic layout of one node: 3 HRT then 5 S_A, 5 S_B, 5 S_C.
pub fn tx_topics(node: usize) -> Vec<TxTopic> {
    let mut tx = Vec::new();
    for (i, _) in HRT.iter().enumerate() {
        tx.push(TxTopic {
            msg_id: msg_id(node, i),
            class: Class::Hrt,
            size: 8,
            deadline_ns: 0,
        });
    }
    for c in SRT_CLASSES.iter() {
        for _ in 0..PER_CLASS {
            let t = tx.len();
            tx.push(TxTopic {
                msg_id: msg_id(node, t),
                class: Class::Srt,
                size: c.size,
                deadline_ns: c.deadline_ns,
            });
        }
    }
    tx
}

/// Class name of transmit topic index `t` (same layout on every node).
pub fn topic_class(t: usize) -> &'static str {
    match t {
        0..=2 => HRT.get(t).map_or("?", |h| h.0),
        _ => SRT_CLASSES.get((t - 3) / PER_CLASS).map_or("?", |c| c.name),
    }
}

/// Reservation mask of every cycle (Fig. 3): sync slot plus every node's HRT slots.
pub fn mask() -> u64 {
    let mut m = 1u64;
    for n in 0..NODES {
        for e in calendar(n) {
            m |= 1 << (e.slot % u32::from(SLOTS));
        }
    }
    m
}

/// Calendar of node `n` over the one-cycle hyperperiod.
pub fn calendar(n: usize) -> Vec<CalEntry> {
    let mut cal = Vec::new();
    for (i, &(_, period)) in HRT.iter().enumerate() {
        let mut s = HRT_PHASE.get(i).copied().unwrap_or(1) + n as u32;
        while s < u32::from(SLOTS) {
            cal.push(CalEntry {
                slot: s,
                tx: i as u8,
                fragment: 0,
            });
            s += period;
        }
    }
    cal.sort_by_key(|e| e.slot);
    cal
}

/// Tables of every node; node 0 is the master. Every node subscribes to every topic of
/// the others (so reassembly runs on real receivers).
pub fn tables(laxity: LaxityEncoding) -> Vec<OwnedTables> {
    let bus = bus_config(laxity);
    (0..NODES)
        .map(|n| {
            let mut rx = Vec::new();
            let mut off = 0u16;
            for other in (0..NODES).filter(|&o| o != n) {
                for t in tx_topics(other) {
                    rx.push(RxTopic {
                        msg_id: t.msg_id,
                        size: t.size,
                        arena_offset: off,
                    });
                    off += t.size;
                }
            }
            rx.sort_by_key(|r| r.msg_id);
            OwnedTables {
                bus,
                module: n as u8,
                tx: tx_topics(n),
                rx,
                calendar: calendar(n),
                master_masks: if n == 0 { vec![mask()] } else { Vec::new() },
            }
        })
        .collect()
}

/// Traffic generators of node `n`, SRT event rates scaled by `load` (1.0 = Table 2).
pub fn generators(load: f64) -> Vec<Gen> {
    let mut g = Vec::new();
    for (i, _) in HRT.iter().enumerate() {
        g.push(Gen::hrt(i as u8));
    }
    for (c, class) in SRT_CLASSES.iter().enumerate() {
        for k in 0..PER_CLASS {
            let tx = (3 + c * PER_CLASS + k) as u8;
            let lo = (class.every_ns.0 as f64 / load) as Nanos;
            let hi = (class.every_ns.1 as f64 / load) as Nanos;
            g.push(Gen::random(tx, lo, hi, usize::from(class.size)));
        }
    }
    g
}

/// The whole scenario at SRT load `load` with the given laxity encoding.
pub fn scenario(laxity: LaxityEncoding, load: f64) -> crate::run::Scenario {
    let tables = tables(laxity);
    let topics = crate::run::topic_infos(
        &tables,
        |_, t| topic_class(t).to_string(),
        |_, t| HRT.get(t).map_or(0, |h| u64::from(h.1)),
    );
    crate::run::Scenario {
        gens: (0..NODES).map(|_| generators(load)).collect(),
        tables,
        topics,
        master: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn calendar_matches_fig3() {
        let m = mask();
        // Fig. 3: slots 0..=15 reserved, 16..=18 free, 19..=21 reserved, 22..=24 free.
        for s in 0..=15 {
            assert!(m & (1 << s) != 0, "slot {s}");
        }
        for s in [16, 17, 18, 22, 23, 24, 58, 59] {
            assert!(m & (1 << s) == 0, "slot {s}");
        }
        assert_eq!(m.count_ones(), 40, "sync + 3 nodes x 13 HRT slots");
        let c1 = calendar(1);
        assert_eq!(c1.iter().filter(|e| e.tx == 0).count(), 10);
        assert_eq!(c1.first().map(|e| (e.slot, e.tx)), Some((2, 0)));
        assert!(c1.iter().any(|e| e.slot == 5 && e.tx == 1));
        assert!(c1.iter().any(|e| e.slot == 35 && e.tx == 1));
        assert!(c1.iter().any(|e| e.slot == 11 && e.tx == 2));
    }

    #[test]
    fn our_laxity_covers_the_longest_deadline() {
        assert!(our_laxity().max_laxity_ns() >= 50 * MS);
        assert_eq!(topic_class(0), "H_A");
        assert_eq!(topic_class(7), "S_A");
        assert_eq!(topic_class(8), "S_B");
        assert_eq!(topic_class(17), "S_C");
    }
}
