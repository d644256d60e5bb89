#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! Engine behaviour on an ideal bit-accurate bus (tests/common): the RTCAN paper's
//! benchmark schedule executed exactly, SRT in free windows only, fragmentation end to
//! end, deadline misses and queue exhaustion reported, sync loss, malformed input.
mod common;
mod paper_bus;

use common::*;
use paper_bus::{bus, msg_id, paper, Paper, FP, PERIODS, SLOT_NS, SPC, S_SIZE};
use rtcan_core::driver::{Event, TxOutcome};
use rtcan_core::fragment::counter_of;
use rtcan_core::id::{CanId, Class, MsgId};
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::tables::{BusConfig, CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_core::Frame;

/// Master (ideal clock, started at t=0 so cycle 0 starts at one slot) and slaves with
/// ±1000 ppm and offsets.
fn paper_bus(nodes: usize) -> (Bus, Paper) {
    let p = paper(nodes);
    let mut bus = Bus::new(1_000_000);
    let drift = [0.0, 1000.0, -1000.0, 500.0];
    let offset = [0.0, 3_333_333.0, 17_000.0, 123.0];
    for (n, t) in p.tables.iter().enumerate() {
        bus.add(*t, drift[n % 4], offset[n % 4]);
    }
    for n in 0..nodes {
        bus.nodes[n].host.hrt = (0..3)
            .map(|k| Some(vec![n as u8, k as u8, 0, 0, 0, 0, 0, 0xAA]))
            .collect();
    }
    (bus, p)
}

/// Master bus time 0 (slot 0 of cycle 0) in global time: the master starts one slot
/// after `new(now = 0)`.
const T0: u64 = SLOT_NS;

fn slot_of(t: u64) -> (u64, u64) {
    assert!(t >= T0, "frame at {t} before the first cycle");
    let abs = (t - T0) / SLOT_NS;
    (abs / SPC as u64, abs % SPC as u64)
}

#[test]
fn paper_benchmark_reserves_40_of_60_slots() {
    let p = paper(3);
    let mask = p.tables[0].master_masks[0];
    assert_eq!(mask.count_ones(), 40, "39 HRT slots + sync slot 0 (Fig. 3)");
    assert_eq!(mask & 1, 1);
    assert_eq!(mask >> 60, 0);
}

#[test]
fn hrt_frames_go_exactly_in_their_slots_with_drifting_slaves() {
    let (mut bus, p) = paper_bus(3);
    let cycles = 40u64;
    bus.run(T0 + cycles * SPC as u64 * SLOT_NS);
    let mut per_slot = std::collections::HashMap::new();
    let mut hrt = 0;
    for w in &bus.log {
        // Slaves may start up to one bit time early (clock sync precision).
        let (cycle, slot) = slot_of(w.sof + 1_000);
        if w.frame.id().is_sync() {
            assert_eq!(slot, 0, "sync in slot 0");
            assert_eq!(
                w.frame.id().raw() as u64,
                cycle,
                "sync carries the cycle counter"
            );
            assert!(w.sof - (T0 + cycle * 60 * SLOT_NS) < 1_000);
            continue;
        }
        let id = w.frame.id();
        if id.laxity() != 0 {
            continue;
        }
        hrt += 1;
        let k = ((id.msg_id().0 - 0x140) % 16) as usize;
        let n = ((id.msg_id().0 - 0x140) / 16) as usize;
        assert_eq!(n, w.node, "frame sent by the module that owns the topic");
        let pl = p.placements[n * 3 + k].phase_slot as u64;
        assert_eq!(
            slot % PERIODS[k] as u64,
            pl % PERIODS[k] as u64,
            "topic {n}/{k} in slot {slot} cycle {cycle} sof {}",
            w.sof
        );
        // Within one bit time of the master's slot boundary once locked (cycle >= 3).
        let start = T0 + (cycle * 60 + slot) * SLOT_NS;
        if cycle >= 3 {
            let err = w.sof.abs_diff(start);
            assert!(
                err <= 1_000,
                "node {n} slot {slot} cycle {cycle}: {err} ns off"
            );
        }
        assert!(
            per_slot.insert((cycle, slot), n).is_none(),
            "two HRT frames in one slot"
        );
        assert_eq!(w.frame.data(), &[n as u8, k as u8, 0, 0, 0, 0, 0, 0xAA]);
    }
    // Master: every cycle from 0; slaves from the cycle after their first sync.
    assert!(hrt >= 3 * 13 * (cycles as usize - 2), "{hrt} HRT frames");
    for n in 0..3 {
        assert_eq!(bus.nodes[n].engine.counters().hrt_late, 0);
        assert_eq!(bus.nodes[n].engine.counters().hrt_empty, 0);
        let received = bus.nodes[n].host.delivered.len();
        assert!(received > 0);
    }
}

#[test]
fn srt_fragmented_message_is_delivered_in_a_free_window_only() {
    let (mut bus, p) = paper_bus(3);
    bus.run(T0 + 5 * 60 * SLOT_NS);
    let payload: Vec<u8> = (0..S_SIZE as u8).map(|b| b.wrapping_mul(7)).collect();
    bus.submit(1, 3, &payload).expect("queued");
    bus.run(T0 + 8 * 60 * SLOT_NS);
    for rx_node in [0, 2] {
        let got: Vec<_> = bus.nodes[rx_node]
            .host
            .delivered
            .iter()
            .filter(|(rx, _, _)| p.tables[rx_node].rx[*rx as usize].msg_id == msg_id(1, 3))
            .collect();
        assert_eq!(
            got.len(),
            1,
            "node {rx_node}: {:?}",
            bus.nodes[rx_node].engine.counters()
        );
        assert_eq!(got[0].1, payload);
    }
    assert!(bus.nodes[1]
        .host
        .done
        .iter()
        .any(|d| d.0 == 3 && d.2 == TxOutcome::Sent));
    // Three fragments (20 B), counting down (first transfer: ID 0), SRT laxity 1..=62, all inside
    // free slots and finished before the next reserved slot.
    let mask = p.tables[0].master_masks[0];
    let frags: Vec<_> = bus
        .log
        .iter()
        .filter(|w| w.frame.id().msg_id() == msg_id(1, 3))
        .collect();
    assert_eq!(
        frags
            .iter()
            .map(|w| w.frame.id().fragment())
            .collect::<Vec<_>>(),
        vec![2, 1, 0]
    );
    assert_eq!(
        frags.iter().map(|w| w.frame.dlc()).collect::<Vec<_>>(),
        vec![8, 8, 4]
    );
    for w in &frags {
        assert!((1..=62).contains(&w.frame.id().laxity()));
        let (_, slot) = slot_of(w.sof + 1_000);
        assert_eq!(
            mask >> slot & 1,
            0,
            "SRT frame started in reserved slot {slot}"
        );
        let (_, end_slot) = slot_of(w.end - 1);
        for s in slot..=end_slot {
            assert_eq!(
                mask >> (s % 60) & 1,
                0,
                "SRT frame overran into reserved slot {s}"
            );
        }
    }
}

#[test]
fn no_frame_ever_overlaps_a_reserved_slot_under_srt_overload() {
    let (mut bus, p) = paper_bus(3);
    bus.run(T0 + 4 * 60 * SLOT_NS);
    let mask = p.tables[0].master_masks[0];
    let mut refused = 0;
    for round in 0..30u64 {
        for n in 0..3 {
            for _ in 0..3 {
                if bus.submit(n, 3, &[round as u8; S_SIZE as usize]).is_err() {
                    refused += 1;
                }
                let _ = bus.submit(n, 4, &[n as u8; 8]);
            }
        }
        let t = bus.now + 2 * SLOT_NS * 7;
        bus.run(t);
    }
    bus.run(bus.now + 20 * 60 * SLOT_NS);
    assert!(refused > 0, "queue exhaustion is reported to the caller");
    let missed: usize = (0..3)
        .map(|n| {
            bus.nodes[n]
                .host
                .done
                .iter()
                .filter(|d| d.2 == TxOutcome::DeadlineMissed)
                .count()
        })
        .sum();
    let counted: u32 = (0..3)
        .map(|n| bus.nodes[n].engine.counters().deadline_missed)
        .sum();
    assert_eq!(missed as u32, counted);
    for w in &bus.log {
        let id = w.frame.id();
        if id.laxity() == 0 {
            continue;
        }
        // Slot clocks agree to within one bit time (1 us): allow that much at both ends.
        let (c0, s0) = slot_of(w.sof + 1_000);
        let (c1, s1) = slot_of(w.end - 1_000);
        let mut abs = c0 * 60 + s0;
        while abs <= c1 * 60 + s1 {
            assert_eq!(
                mask >> (abs % 60) & 1,
                0,
                "frame {:08X} from node {} at {}..{} overlaps reserved slot {} (abs {}, starts at {})",
                id.raw(),
                w.node,
                w.sof,
                w.end,
                abs % 60,
                abs,
                T0 + abs * SLOT_NS
            );
            abs += 1;
        }
    }
    for n in 0..3 {
        assert_eq!(bus.nodes[n].engine.counters().hrt_late, 0);
    }
}

#[test]
fn nrt_goes_after_srt_and_heartbeats_flow() {
    let (mut bus, _) = paper_bus(3);
    bus.run(T0 + 30 * 60 * SLOT_NS);
    for n in 0..3 {
        let hb: Vec<_> = bus.nodes[n]
            .host
            .events
            .iter()
            .filter_map(|e| {
                if let Event::Heartbeat { module, .. } = e {
                    Some(*module)
                } else {
                    None
                }
            })
            .collect();
        for m in (0..3).filter(|&m| m != n) {
            assert!(
                hb.contains(&(m as u8)),
                "node {n} heard module {m}'s heartbeat"
            );
        }
    }
    assert!(bus.log.iter().any(|w| w.frame.id().laxity() == 63));
}

#[test]
fn slaves_report_sync_loss_and_go_silent() {
    let (mut bus, _) = paper_bus(3);
    bus.run(T0 + 10 * 60 * SLOT_NS);
    assert!(bus.nodes[1].host.events.contains(&Event::Synced));
    bus.nodes[0].alive = false;
    let cut = bus.now;
    bus.run(cut + 10 * 60 * SLOT_NS);
    for n in 1..3 {
        assert!(
            bus.nodes[n].host.events.contains(&Event::SyncLost),
            "node {n}"
        );
        assert!(bus.nodes[n].engine.counters().sync_missed >= 1);
    }
    let last = bus
        .log
        .iter()
        .filter(|w| w.node != 0)
        .map(|w| w.sof)
        .max()
        .unwrap_or(0);
    assert!(
        last < cut + 5 * 60 * SLOT_NS,
        "slaves stopped transmitting after losing sync"
    );
}

#[test]
fn malformed_frames_are_counted_never_delivered() {
    let p = paper(3);
    let mut e = TestEngine::new(p.tables[1], 0);
    let mut can = TestCan::default();
    let mut host = TestHost::default();
    // Garbage sync: wrong DLC, and a mask with bits past slot 59.
    let bad_sync = Frame::new(CanId::from_raw(5).unwrap(), &[1, 2, 3]).unwrap();
    e.on_rx(&bad_sync, 10, &mut can, &mut host);
    let bad_sync2 = Frame::new(CanId::from_raw(6).unwrap(), &[0xFF; 8]).unwrap();
    e.on_rx(&bad_sync2, 10, &mut can, &mut host);
    assert_eq!(e.counters().rx_bad_sync, 2);
    // Unknown message ID.
    let unknown = Frame::new(CanId::new(5, MsgId(0x7777), 0).unwrap(), &[0; 8]).unwrap();
    e.on_rx(&unknown, 10, &mut can, &mut host);
    assert_eq!(e.counters().rx_unknown_id, 1);
    // Wrong DLC for an 8-byte topic of node 0.
    let short = Frame::new(CanId::new(0, msg_id(0, 0), 0).unwrap(), &[1, 2, 3]).unwrap();
    e.on_rx(&short, 10, &mut can, &mut host);
    assert_eq!(e.counters().rx_bad_dlc, 1);
    // Fragment out of order for the 20-byte SRT topic (starts at counter 1, not 2).
    let ooo = Frame::new(CanId::new(7, msg_id(0, 3), 1).unwrap(), &[0; 8]).unwrap();
    e.on_rx(&ooo, 10, &mut can, &mut host);
    assert_eq!(e.counters().rx_out_of_order, 1);
    // Heartbeat with a bad DLC.
    let hb = Frame::new(CanId::new(63, MsgId(0x0100), 0).unwrap(), &[1]).unwrap();
    e.on_rx(&hb, 10, &mut can, &mut host);
    assert_eq!(e.counters().rx_bad_heartbeat, 1);
    assert!(host.delivered.is_empty());
    assert!(can.mailboxes.iter().all(|m| m.is_none()));
}

#[test]
fn fingerprint_mismatch_is_reported() {
    let p = paper(3);
    let mut e = TestEngine::new(p.tables[1], 0);
    let mut can = TestCan::default();
    let mut host = TestHost::default();
    let hb = rtcan_core::heartbeat::heartbeat_frame(rtcan_core::heartbeat::Heartbeat {
        module: 2,
        state: 1,
        fingerprint: FP ^ 1,
    })
    .unwrap();
    e.on_rx(&hb, 10, &mut can, &mut host);
    assert_eq!(
        host.events,
        vec![Event::FingerprintMismatch {
            module: 2,
            fingerprint: FP ^ 1
        }]
    );
}

#[test]
fn submit_rejects_hrt_topics_wrong_sizes_and_full_queues() {
    let p = paper(3);
    let mut e = TestEngine::new(p.tables[0], 0);
    let mut can = TestCan::default();
    let mut host = TestHost::default();
    let t = host.add(&[0; 8]);
    assert_eq!(
        e.submit(0, 0, t, &mut can, &mut host),
        Err(rtcan_core::engine::SubmitError::NotSubmittable)
    );
    assert_eq!(
        e.submit(0, 3, t, &mut can, &mut host),
        Err(rtcan_core::engine::SubmitError::NotSubmittable)
    );
    assert_eq!(
        e.submit(0, 99, t, &mut can, &mut host),
        Err(rtcan_core::engine::SubmitError::NotSubmittable)
    );
    for _ in 0..16 {
        e.submit(0, 4, t, &mut can, &mut host).unwrap();
    }
    assert_eq!(
        e.submit(0, 4, t, &mut can, &mut host),
        Err(rtcan_core::engine::SubmitError::QueueFull)
    );
    assert_eq!(e.counters().queue_full, 1);
}

#[test]
fn hrt_slot_with_nothing_to_send_is_reported() {
    let (mut bus, _) = paper_bus(1);
    bus.nodes[0].host.hrt[1] = None;
    bus.run(T0 + 3 * 60 * SLOT_NS);
    let empty = bus.nodes[0]
        .host
        .done
        .iter()
        .filter(|d| d.0 == 1 && d.2 == TxOutcome::NothingToSend)
        .count();
    assert_eq!(empty, 6, "H_B every 30 slots over 3 cycles");
    assert_eq!(bus.nodes[0].engine.counters().hrt_empty, 6);
}

#[test]
fn fragmented_hrt_message_goes_in_consecutive_slots_with_its_transfer_id() {
    // Master publishes a 30-byte HRT message (4 fragments) in slots
    // 10..=13 of every cycle; a slave receives it.
    let size = 30u16;
    let tx: &'static [TxTopic] = Box::leak(Box::new([TxTopic {
        msg_id: MsgId(0x0150),
        class: Class::Hrt,
        size,
        deadline_ns: 0,
    }]));
    let cal: &'static [CalEntry] = Box::leak(Box::new([
        CalEntry {
            slot: 10,
            tx: 0,
            fragment: 3,
        },
        CalEntry {
            slot: 11,
            tx: 0,
            fragment: 2,
        },
        CalEntry {
            slot: 12,
            tx: 0,
            fragment: 1,
        },
        CalEntry {
            slot: 13,
            tx: 0,
            fragment: 0,
        },
    ]));
    let rx: &'static [RxTopic] = Box::leak(Box::new([RxTopic {
        msg_id: MsgId(0x0150),
        size,
        arena_offset: 0,
    }]));
    let masks: &'static [u64] = Box::leak(Box::new([1u64 | 0b1111 << 10]));
    let master = NodeTables {
        bus: bus(),
        module: 0,
        tx,
        rx: &[],
        calendar: cal,
        master_masks: masks,
    };
    let slave = NodeTables {
        bus: bus(),
        module: 1,
        tx: &[],
        rx,
        calendar: &[],
        master_masks: &[],
    };
    let mut b = Bus::new(1_000_000);
    b.add(master, 0.0, 0.0);
    b.add(slave, -800.0, 42_000.0);
    let payload: Vec<u8> = (0..size as u8).map(|i| i ^ 0x5A).collect();
    b.nodes[0].host.hrt = vec![Some(payload.clone())];
    b.run(T0 + 6 * 60 * SLOT_NS);
    let frames: Vec<_> = b
        .log
        .iter()
        .filter(|w| w.frame.id().msg_id() == MsgId(0x0150))
        .collect();
    assert_eq!(frames.len(), 6 * 4);
    for (i, w) in frames.iter().enumerate() {
        let (_, slot) = slot_of(w.sof + 1_000);
        assert_eq!(slot, 10 + (i % 4) as u64);
        // 4 frames: 2 counter bits, the transfer ID above them, one more per transfer.
        assert_eq!(
            w.frame.id().fragment(),
            ((i / 4) as u8) << 2 | (3 - (i % 4) as u8)
        );
    }
    // Last fragment: payload bytes 24..30, nothing else.
    assert_eq!(frames[3].frame.data(), &payload[24..30]);
    let got: Vec<_> = b.nodes[1]
        .host
        .delivered
        .iter()
        .map(|d| d.1.clone())
        .collect();
    assert!(got.len() >= 4, "slave receives once locked: {}", got.len());
    assert!(got.iter().all(|g| *g == payload));
    assert_eq!(
        b.nodes[0]
            .host
            .done
            .iter()
            .filter(|d| d.2 == TxOutcome::Sent)
            .count(),
        6
    );
}

#[test]
fn tables_that_do_not_fit_the_engine_are_rejected() {
    use rtcan_core::engine::{check_tables, TablesError};
    let p = paper(3);
    assert_eq!(check_tables(&p.tables[1], 16, 512), Ok(()));
    assert_eq!(
        check_tables(&p.tables[1], 4, 512),
        Err(TablesError::TooManyRx)
    );
    assert_eq!(
        check_tables(&p.tables[1], 16, 64),
        Err(TablesError::ArenaTooSmall)
    );
    let mut t = p.tables[1];
    t.rx = Box::leak(vec![t.rx[1], t.rx[0]].into_boxed_slice());
    assert_eq!(check_tables(&t, 16, 512), Err(TablesError::RxNotSorted));
    let mut t = p.tables[1];
    t.calendar = Box::leak(
        vec![CalEntry {
            slot: 3,
            tx: 9,
            fragment: 0,
        }]
        .into_boxed_slice(),
    );
    assert_eq!(check_tables(&t, 16, 512), Err(TablesError::BadCalendar));
    let mut t = p.tables[1];
    t.bus.slots_per_cycle = 65;
    assert_eq!(check_tables(&t, 16, 512), Err(TablesError::BadBus));
    assert!(TestEngine::try_new(t, 0).is_err());
    // Usable in a const assertion, as the generated code does.
    const EMPTY: NodeTables<'static> = NodeTables {
        bus: BusConfig {
            bitrate: 1_000_000,
            slots_per_cycle: 10,
            slot_ns: 200_000,
            hyperperiod_cycles: 1,
            cycle_counter_wrap: 1,
            laxity: LaxityEncoding::Linear { unit_ns: 1 },
            guard_ns: 0,
            fingerprint: 0,
        },
        module: 0,
        tx: &[],
        rx: &[],
        calendar: &[],
        master_masks: &[],
    };
    const _: () = assert!(check_tables(&EMPTY, 0, 0).is_ok());
}

/// Receive tables with the given (msg_id, size, arena_offset) rows.
fn rx_table(rows: &[(u16, u16, u16)]) -> &'static [RxTopic] {
    let v: Vec<RxTopic> = rows
        .iter()
        .map(|&(id, size, arena_offset)| RxTopic {
            msg_id: MsgId(id),
            size,
            arena_offset,
        })
        .collect();
    Box::leak(v.into_boxed_slice())
}

#[test]
fn overlapping_and_out_of_range_receive_buffers_are_rejected() {
    use rtcan_core::engine::{check_tables, TablesError};
    let p = paper(3);
    let base = p.tables[1];
    let with_rx = |rows: &[(u16, u16, u16)]| NodeTables {
        rx: rx_table(rows),
        ..base
    };
    // 20-byte topic: 20 wire bytes (PROTOCOL §7.1), then an 8-byte topic.
    let good = with_rx(&[(0x140, 20, 0), (0x141, 8, 20)]);
    assert_eq!(check_tables(&good, 16, 28), Ok(()));
    // The rtcan-paper sim's old bug, in today's units: a buffer laid out two bytes short
    // of the previous topic's wire length, so its tail lands in the next topic's buffer.
    assert_eq!(
        check_tables(&with_rx(&[(0x140, 20, 0), (0x141, 8, 18)]), 16, 28),
        Err(TablesError::RxOverlap)
    );
    // Same start, and a buffer inside another one.
    assert_eq!(
        check_tables(&with_rx(&[(0x140, 8, 0), (0x141, 8, 0)]), 16, 30),
        Err(TablesError::RxOverlap)
    );
    assert_eq!(
        check_tables(&with_rx(&[(0x140, 20, 0), (0x141, 2, 10)]), 16, 30),
        Err(TablesError::RxOverlap)
    );
    // Laid out against table order: rejected too (the check is linear).
    assert_eq!(
        check_tables(&with_rx(&[(0x140, 8, 8), (0x141, 8, 0)]), 16, 30),
        Err(TablesError::RxOverlap)
    );
    // Past the end: the arena must hold the last topic's whole wire length (28 bytes).
    assert_eq!(
        check_tables(&with_rx(&[(0x141, 8, 0), (0x142, 20, 8)]), 16, 28),
        Ok(())
    );
    assert_eq!(
        check_tables(&with_rx(&[(0x141, 8, 0), (0x142, 20, 8)]), 16, 27),
        Err(TablesError::ArenaTooSmall)
    );
    assert_eq!(
        check_tables(&with_rx(&[(0x141, 8, u16::MAX)]), 16, 512),
        Err(TablesError::ArenaTooSmall)
    );
    // A topic no transfer can carry (1023 bytes > MAX_PAYLOAD = 256), receive or transmit.
    assert_eq!(
        check_tables(&with_rx(&[(0x140, 1023, 0)]), 16, 4096),
        Err(TablesError::BadSize)
    );
    let big_tx: &'static [TxTopic] = Box::leak(Box::new([TxTopic {
        msg_id: MsgId(0x150),
        class: Class::Srt,
        size: 1023,
        deadline_ns: 1,
    }]));
    let t = NodeTables {
        tx: big_tx,
        calendar: &[],
        ..base
    };
    assert_eq!(check_tables(&t, 16, 512), Err(TablesError::BadSize));
    assert!(TestEngine::try_new(with_rx(&[(0x140, 8, 0), (0x141, 8, 4)]), 0).is_err());
    assert!(TestEngine::try_new(good, 0).is_ok());
}

#[test]
fn calendar_entries_outside_the_topic_or_hyperperiod_are_rejected() {
    use rtcan_core::engine::{check_tables, TablesError};
    let p = paper(3);
    let base = p.tables[0];
    assert_eq!(check_tables(&base, 16, 512), Ok(()));
    let cal = |slot: u32, tx: u8, fragment: u8| NodeTables {
        calendar: Box::leak(Box::new([CalEntry { slot, tx, fragment }])),
        ..base
    };
    // H_A (tx 0) is one 8-byte frame: fragment 0 only. S (tx 3) is 3 fragments.
    assert_eq!(check_tables(&cal(5, 0, 0), 16, 512), Ok(()));
    assert_eq!(
        check_tables(&cal(5, 0, 1), 16, 512),
        Err(TablesError::BadCalendar)
    );
    assert_eq!(check_tables(&cal(5, 3, 2), 16, 512), Ok(()));
    assert_eq!(
        check_tables(&cal(5, 3, 3), 16, 512),
        Err(TablesError::BadCalendar)
    );
    // One hyperperiod of one 60-slot cycle: slots 0..=59.
    assert_eq!(check_tables(&cal(59, 0, 0), 16, 512), Ok(()));
    assert_eq!(
        check_tables(&cal(60, 0, 0), 16, 512),
        Err(TablesError::BadCalendar)
    );
    assert_eq!(
        check_tables(&cal(5, 5, 0), 16, 512),
        Err(TablesError::BadCalendar)
    );
}

#[test]
fn backup_master_takes_over_when_the_master_dies() {
    let (mut bus, p) = paper_bus(3);
    let masks = p.tables[0].master_masks;
    bus.nodes[1].engine.set_backup(1, masks);
    bus.nodes[2].engine.set_backup(2, masks);
    bus.run(T0 + 10 * 60 * SLOT_NS);
    bus.nodes[0].alive = false;
    let cut = bus.now;
    bus.run(cut + 30 * 60 * SLOT_NS);
    assert!(bus.nodes[1].engine.is_master(), "backup 1 took over");
    assert!(
        !bus.nodes[2].engine.is_master(),
        "backup 2 relocked on backup 1's sync instead"
    );
    assert!(
        bus.nodes[2]
            .host
            .events
            .iter()
            .filter(|e| **e == Event::Synced)
            .count()
            >= 2
    );
    let syncs: Vec<_> = bus
        .log
        .iter()
        .filter(|w| w.node == 1 && w.frame.id().is_sync())
        .map(|w| w.sof)
        .collect();
    assert!(
        syncs.len() >= 20,
        "{} syncs from the new master",
        syncs.len()
    );
    // Over the last 10 cycles both survivors send their 13 HRT frames each, in the
    // slots of their calendars relative to the new master's cycle starts, and every
    // other frame stays out of reserved slots.
    let mask = masks[0];
    for pair in syncs[syncs.len() - 11..].windows(2) {
        let (start, end) = (pair[0], pair[1]);
        // The new master's clock (+1000 ppm) now defines bus time: slots in global time
        // are a sixtieth of its measured cycle.
        let slot_of = |t: u64| (t - start) * 60 / (end - start);
        for n in 1..3 {
            let hrt: Vec<_> = bus
                .log
                .iter()
                .filter(|w| {
                    w.node == n && w.sof >= start && w.sof < end && w.frame.id().laxity() == 0
                })
                .filter(|w| !w.frame.id().is_sync())
                .collect();
            assert_eq!(hrt.len(), 13, "node {n} HRT frames in cycle at {start}");
            for w in hrt {
                let k = ((w.frame.id().msg_id().0 - 0x140) % 16) as usize;
                let slot = slot_of(w.sof + 1_000);
                let phase = p.placements[n * 3 + k].phase_slot as u64;
                assert_eq!(
                    slot % PERIODS[k] as u64,
                    phase % PERIODS[k] as u64,
                    "node {n} topic {k}"
                );
            }
        }
        for w in bus
            .log
            .iter()
            .filter(|w| w.sof >= start && w.sof < end && w.frame.id().laxity() != 0)
        {
            let s0 = slot_of(w.sof + 1_000);
            let s1 = slot_of(w.end - 1_000);
            for s in s0..=s1 {
                assert_eq!(
                    mask >> (s % 60) & 1,
                    0,
                    "frame {:08X} in reserved slot {s}",
                    w.frame.id().raw()
                );
            }
        }
    }
}

/// Master sends a 10-byte HRT topic (12 wire bytes: fragments 1 and 0) twice per cycle,
/// back to back: transfer A in slots 10, 11 and transfer B in slots 12, 13. A slave
/// receives it.
fn back_to_back_hrt(reuse_tokens: bool) -> Bus {
    let (master, slave) = back_to_back_tables();
    let mut b = Bus::new(1_000_000);
    b.add(master, 0.0, 0.0);
    b.add(slave, 300.0, 5_000.0);
    b.nodes[0].host.hrt = vec![Some((0..10).collect())];
    b.nodes[0].host.reuse_hrt_tokens = reuse_tokens;
    b
}

/// Tables of `back_to_back_hrt`: (master, slave).
fn back_to_back_tables() -> (NodeTables<'static>, NodeTables<'static>) {
    let size = 10u16;
    let id = MsgId(0x0150);
    let tx: &'static [TxTopic] = Box::leak(Box::new([TxTopic {
        msg_id: id,
        class: Class::Hrt,
        size,
        deadline_ns: 0,
    }]));
    let cal: &'static [CalEntry] = Box::leak(Box::new([(10, 1), (11, 0), (12, 1), (13, 0)].map(
        |(slot, fragment)| CalEntry {
            slot,
            tx: 0,
            fragment,
        },
    )));
    let rx: &'static [RxTopic] = Box::leak(Box::new([RxTopic {
        msg_id: id,
        size,
        arena_offset: 0,
    }]));
    let masks: &'static [u64] = Box::leak(Box::new([1u64 | 0b1111 << 10]));
    let master = NodeTables {
        bus: bus(),
        module: 0,
        tx,
        rx: &[],
        calendar: cal,
        master_masks: masks,
    };
    let slave = NodeTables {
        bus: bus(),
        module: 1,
        tx: &[],
        rx,
        calendar: &[],
        master_masks: &[],
    };
    (master, slave)
}

/// A's last fragment is destroyed by an error frame in cycle 4 and retransmitted; the
/// retransmission is still on the wire when slot 12 loads B's first fragment.
fn hrt_last_fragment_retransmitted_into_the_next_transfer(reuse_tokens: bool) {
    let mut b = back_to_back_hrt(reuse_tokens);
    // The last fragment (counter 0) of the 10-byte topic, whatever its transfer ID.
    fn last(id: CanId) -> bool {
        !id.is_sync() && id.msg_id() == MsgId(0x0150) && counter_of(10, id.fragment()) == 0
    }
    let slot11 = T0 + (4 * 60 + 11) * SLOT_NS;
    b.destroy.push((slot11, last));
    let cycles = 8;
    b.run(T0 + cycles * 60 * SLOT_NS);
    assert_eq!(b.destroyed.len(), 1);
    let retx = b
        .log
        .iter()
        .find(|w| w.sof > slot11 && last(w.frame.id()))
        .unwrap();
    assert!(
        retx.end > slot11 + SLOT_NS,
        "the retransmission ends in slot 12 ({} > {})",
        retx.end,
        slot11 + SLOT_NS
    );
    // Every transfer was delivered once, and reported once: Sent, none missed.
    let transfers = 2 * cycles as usize;
    let done = &b.nodes[0].host.done;
    assert_eq!(
        done.iter()
            .filter(|d| d.2 == TxOutcome::DeadlineMissed)
            .count(),
        0,
        "{done:?}"
    );
    assert_eq!(
        done.iter().filter(|d| d.2 == TxOutcome::Sent).count(),
        transfers
    );
    assert_eq!(b.nodes[1].host.delivered.len(), transfers);
    assert_eq!(b.nodes[1].engine.counters().rx_incomplete, 0);
    assert_eq!(b.nodes[0].engine.counters().deadline_missed, 0);
    // Every transfer's last fragment went on the wire.
    let lasts: Vec<_> = b.log.iter().filter(|w| last(w.frame.id())).collect();
    assert_eq!(lasts.len(), transfers);
}

#[test]
fn hrt_transfer_whose_last_fragment_overruns_is_reported_sent() {
    hrt_last_fragment_retransmitted_into_the_next_transfer(false);
}

#[test]
fn hrt_token_reused_while_the_last_fragment_retransmits_is_not_reported_early() {
    hrt_last_fragment_retransmitted_into_the_next_transfer(true);
}

#[test]
fn hrt_transfer_with_a_failed_earlier_fragment_is_reported_missed_once() {
    // Both fragments of transfer A pending at once (slot 10, then 11, never sent); the
    // first is aborted, then the last one goes out: receivers drop A (fragment 1
    // missing), so A is missed, reported once, by the last fragment's completion.
    let (tables, _) = back_to_back_tables();
    let mut e = TestEngine::new(tables, 0);
    let (mut can, mut host) = (TestCan::default(), TestHost::default());
    host.hrt = vec![Some((0..10).collect())];
    let slot = |k: u64| SLOT_NS + k * SLOT_NS;
    e.poll(slot(10), &mut can, &mut host);
    e.poll(slot(11), &mut can, &mut host);
    let mb = |can: &TestCan, fragment: u8| {
        can.mailboxes
            .iter()
            .position(|m| {
                m.is_some_and(|f| {
                    !f.id().is_sync() && counter_of(10, f.id().fragment()) == fragment
                })
            })
            .unwrap()
    };
    let (m1, m0) = (mb(&can, 1), mb(&can, 0));
    use rtcan_core::driver::{Mailbox, TxResult};
    can.mailboxes[m1] = None;
    e.on_tx_done(
        Mailbox(m1 as u8),
        TxResult::Aborted,
        slot(11) + 10,
        &mut can,
        &mut host,
    );
    assert!(
        host.done.is_empty(),
        "the last fragment's mailbox owns the report"
    );
    can.mailboxes[m0] = None;
    e.on_tx_done(
        Mailbox(m0 as u8),
        TxResult::Sent,
        slot(11) + 20,
        &mut can,
        &mut host,
    );
    assert_eq!(
        host.done,
        vec![(
            0,
            Some(rtcan_core::driver::Token(0)),
            TxOutcome::DeadlineMissed
        )]
    );
    // The next transfer (slots 12, 13) is unaffected.
    e.poll(slot(12), &mut can, &mut host);
    let m = mb(&can, 1);
    can.mailboxes[m] = None;
    e.on_tx_done(
        Mailbox(m as u8),
        TxResult::Sent,
        slot(12) + 10,
        &mut can,
        &mut host,
    );
    e.poll(slot(13), &mut can, &mut host);
    let m = mb(&can, 0);
    can.mailboxes[m] = None;
    e.on_tx_done(
        Mailbox(m as u8),
        TxResult::Sent,
        slot(13) + 10,
        &mut can,
        &mut host,
    );
    assert_eq!(
        host.done[1..],
        [(0, Some(rtcan_core::driver::Token(1)), TxOutcome::Sent)]
    );
}

/// Issue 10: on a real CPU a window frame's completion reaches the engine through a task
/// after the TX interrupt, possibly after the next reserved slot's frame is loaded (or,
/// in the firmware, prepared half a slot ahead). Window frames therefore leave one
/// mailbox free (`Policy::keep_tdma_mailbox`): the HRT frame of the slot after a window
/// loads although no completion of the window's frames has been processed. Without the
/// rule the window fills all three and the HRT slot is lost in the same situation.
#[test]
fn window_frames_leave_a_mailbox_for_the_next_hrt_frame() {
    use rtcan_core::driver::{Mailbox, TxResult};
    use rtcan_core::engine::Policy;
    let tx: &'static [TxTopic] = Box::leak(Box::new([
        TxTopic {
            msg_id: MsgId(0x0150),
            class: Class::Hrt,
            size: 8,
            deadline_ns: 0,
        },
        TxTopic {
            msg_id: MsgId(0x0151),
            class: Class::Srt,
            size: 8,
            deadline_ns: 50_000_000,
        },
        TxTopic {
            msg_id: MsgId(0x0152),
            class: Class::Srt,
            size: 8,
            deadline_ns: 50_000_000,
        },
        TxTopic {
            msg_id: MsgId(0x0153),
            class: Class::Srt,
            size: 8,
            deadline_ns: 50_000_000,
        },
    ]));
    let cal: &'static [CalEntry] = Box::leak(Box::new([CalEntry {
        slot: 5,
        tx: 0,
        fragment: 0,
    }]));
    // Sync in slot 0, the HRT frame in slot 5: slots 1 to 4 are a free window.
    let masks: &'static [u64] = Box::leak(Box::new([1u64 | 1 << 5]));
    let tables = NodeTables {
        bus: bus(),
        module: 0,
        tx,
        rx: &[],
        calendar: cal,
        master_masks: masks,
    };
    let before = Policy {
        keep_tdma_mailbox: false,
        ..Policy::OURS
    };
    for (policy, window_frames, hrt_loaded) in [(Policy::OURS, 2, true), (before, 3, false)] {
        let mut e = TestEngine::new(tables, 0);
        e.set_policy(policy);
        let (mut can, mut host) = (TestCan::default(), TestHost::default());
        host.hrt = vec![Some(vec![7; 8])];
        // Slot 0: the sync, completed at once.
        e.poll(T0, &mut can, &mut host);
        let sync = can.mailboxes.iter().position(Option::is_some).unwrap();
        can.mailboxes[sync] = None;
        e.on_tx_done(
            Mailbox(sync as u8),
            TxResult::Sent,
            T0 + 130_000,
            &mut can,
            &mut host,
        );
        // One message on each SRT topic (a topic's messages go one at a time).
        for tx in 1..4u8 {
            let token = host.add(&[tx; 8]);
            e.submit(T0 + 1_000, tx, token, &mut can, &mut host)
                .unwrap();
        }
        assert!(
            can.mailboxes.iter().all(Option::is_none),
            "slot 0 is reserved"
        );
        // Slot 1 opens the window.
        e.poll(T0 + SLOT_NS, &mut can, &mut host);
        let loaded = can.mailboxes.iter().filter(|m| m.is_some()).count();
        assert_eq!(loaded, window_frames, "{policy:?}");
        // Slot 5, no completion processed yet (the task that would run them is late).
        e.poll(T0 + 5 * SLOT_NS, &mut can, &mut host);
        let hrt = can
            .mailboxes
            .iter()
            .flatten()
            .filter(|f| f.id().msg_id() == MsgId(0x0150))
            .count();
        assert_eq!(hrt == 1, hrt_loaded, "{policy:?}");
        assert_eq!(e.counters().hrt_late, u32::from(!hrt_loaded), "{policy:?}");
    }
}

/// Heartbeats each module sent in the `cycles` cycles from cycle 10 on.
fn heartbeats_per_module(bus: &Bus, cycles: u64) -> [usize; 3] {
    let mut n = [0; 3];
    for w in &bus.log {
        let Some(hb) = rtcan_core::heartbeat::parse_heartbeat(&w.frame) else {
            continue;
        };
        let (cycle, _) = slot_of(w.sof);
        if (10..10 + cycles).contains(&cycle) {
            n[usize::from(hb.module)] += 1;
        }
    }
    n
}

/// A supervised robot (robot.toml `on_missing`) sets a shorter heartbeat period: every
/// module then beats every cycle; by default once every `HEARTBEAT_CYCLES` = 10.
#[test]
fn heartbeat_period_is_settable_per_robot() {
    let (mut bus, _) = paper_bus(3);
    bus.run(T0 + 40 * 60 * SLOT_NS);
    assert_eq!(heartbeats_per_module(&bus, 30), [3, 3, 3]);
    let (mut fast, _) = paper_bus(3);
    for n in &mut fast.nodes {
        n.engine.set_heartbeat_cycles(1);
    }
    fast.run(T0 + 40 * 60 * SLOT_NS);
    assert_eq!(heartbeats_per_module(&fast, 30), [30, 30, 30]);
    // 0 is clamped to 1, above 10 to 10.
    let (mut clamped, _) = paper_bus(3);
    clamped.nodes[0].engine.set_heartbeat_cycles(0);
    clamped.nodes[1].engine.set_heartbeat_cycles(200);
    clamped.nodes[2].engine.set_heartbeat_cycles(2);
    clamped.run(T0 + 40 * 60 * SLOT_NS);
    assert_eq!(heartbeats_per_module(&clamped, 30), [30, 3, 15]);
}
