//! The two reference robots: Triskar2 (robot.toml) and the RTCAN paper benchmark.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan_core::tables::CalEntry;
use rtcan_core::{Class, MsgId};
use rtcan_model::filters::{passes, FilterBank};
use rtcan_model::{analyze, Plan, Robot};
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn triskar2() -> Plan {
    Robot::load(root().join("robot.toml")).unwrap()
}

fn paper() -> Plan {
    Robot::load(root().join("robots/rtcan-paper.toml")).unwrap()
}

fn mask(id: u16, size: u32) -> FilterBank {
    FilterBank::Mask {
        id: u32::from(id) << 7,
        mask: (!(size - 1) & 0xFFFF) << 7,
    }
}

#[test]
fn paper_reproduces_fig3() {
    let p = paper();
    assert_eq!(p.bus.slots_per_cycle, 60);
    assert_eq!(p.bus.slot_ns, 166_666);
    assert_eq!(p.bus.hyperperiod_cycles, 1);
    assert_eq!(p.bus.cycle_counter_wrap, 32768);
    // Fig. 3: H_A (1 ms) in slots 1/2/3, H_B (5 ms) in 4/5/6, H_C (10 ms) in 10/11/12.
    for (name, period, phase) in [
        ("h_a1", 6, 1),
        ("h_a2", 6, 2),
        ("h_a3", 6, 3),
        ("h_b1", 30, 4),
        ("h_b2", 30, 5),
        ("h_b3", 30, 6),
        ("h_c1", 60, 10),
        ("h_c2", 60, 11),
        ("h_c3", 60, 12),
    ] {
        let t = p.topic(name).unwrap();
        assert_eq!(
            (t.period_slots, t.phase_slot, t.fragments),
            (Some(period), Some(phase), 1),
            "{name}"
        );
    }
    let fig3 = "111111111111111100011100011100011111111100011100011100011100";
    let expected: u64 = fig3
        .chars()
        .enumerate()
        .map(|(i, c)| u64::from(c == '1') << i)
        .sum();
    assert_eq!(p.master_masks, vec![expected]);
    assert_eq!(expected.count_ones(), 40);
    assert_eq!(p.reserved_slots(), 39);
    // 45 SRT topics, deadlines from Table 2; 16 bytes take 2 frames, 20 bytes 3.
    assert_eq!(
        p.topics.iter().filter(|t| t.class == Class::Srt).count(),
        45
    );
    let sb = p.topic("s_b2_3").unwrap();
    assert_eq!(
        (sb.size, sb.fragments, sb.deadline_ns),
        (16, 2, Some(10_000_000))
    );
    assert_eq!(p.topic("s_c3_5").unwrap().fragments, 3);
    // One receiver set (the capture module): 54 topics in one 64-ID block, one mask.
    assert_eq!(p.topic("h_a1").unwrap().msg_id, MsgId(0x140));
    assert_eq!(p.topic("h_c3").unwrap().msg_id, MsgId(0x148));
    assert_eq!(p.topic("s_a1_1").unwrap().msg_id, MsgId(0x149));
    let monitor = p.module("monitor").unwrap();
    assert_eq!(monitor.banks.len(), 3);
    assert_eq!(monitor.banks[2].filter, mask(0x140, 64));
    assert_eq!(monitor.rx.len(), 54);
}

#[test]
fn paper_check_text_shows_the_calendar() {
    let text = rtcan_model::report::text(&paper());
    assert!(
        text.contains("  node1    SA..B..A..C..A.....A.....A.....A..B..A.....A.....A.....A....\n"),
        "{text}"
    );
    assert!(
        text.contains("  node3    ...A..B..A..C..A.....A.....A.....A..B..A.....A.....A.....A..\n")
    );
    assert!(text.contains("  mask     111111111111111100011100011100011111111100011100011100011100   40/60 reserved\n"));
    assert!(text.contains(
        "h_a1       node1   0x0140  1000 Hz (1 ms)  1000.004 Hz (999.996 us)  6 slots   1"
    ));
}

#[test]
fn triskar2_plan() {
    let p = triskar2();
    assert_eq!(p.bus.bitrate, 1_000_000);
    assert_eq!(p.bus.hyperperiod_cycles, 4);
    assert_eq!(p.bus.cycle_counter_wrap, 32768);
    assert_eq!(p.module("gateway").map(|m| m.is_master), Some(true));
    let expect = [
        ("odometry", 0x140, Some((120, 5, 3))),
        ("proximity", 0x141, Some((240, 8, 1))),
        ("battery", 0x142, None),
        ("log", 0x143, None),
        ("encoder1", 0x144, Some((30, 1, 1))),
        ("encoder3", 0x145, Some((30, 2, 1))),
        ("velocity", 0x146, None),
        ("wheel_setpoints", 0x147, Some((60, 3, 2))),
        ("teleop", 0x148, None),
    ];
    for (name, id, hrt) in expect {
        let t = p.topic(name).unwrap();
        assert_eq!(t.msg_id, MsgId(id), "{name}");
        assert!(t.on_bus, "{name}");
        if let Some((period, phase, frags)) = hrt {
            assert_eq!(
                (t.period_slots, t.phase_slot, t.fragments),
                (Some(period), Some(phase), frags),
                "{name}"
            );
        }
    }
    // encoder2 is only read by odometry on the same module: never on the bus.
    let e2 = p.topic("encoder2").unwrap();
    assert!(!e2.on_bus);
    assert_eq!(e2.phase_slot, None);
    // 1000 Hz-style discretisation: 200 Hz -> 30 slots of 166.666 us = 4.99998 ms.
    assert_eq!(
        p.topic("encoder1").unwrap().actual_period_ns(&p.bus),
        Some(4_999_980)
    );
    // Reserved: per 240-slot hyperperiod 8+8 (encoders) + 8 (setpoints: 4 x 2) + 6 (odometry 2 x 3) + 1.
    assert_eq!(p.reserved_slots(), 31);
    assert_eq!(
        p.master_masks,
        vec![0x1_8000_01ff, 0x1_8000_001f, 0x1_8000_00ff, 0x1_8000_001f]
    );
    assert_eq!(p.module("gateway").unwrap().banks[2].filter, mask(0x140, 4));
    let m2 = p.module("motor2").unwrap();
    assert_eq!(m2.banks.len(), 4);
    assert_eq!(m2.banks[2].filter, mask(0x144, 2));
    assert_eq!(m2.banks[3].filter, mask(0x147, 1));
    assert_eq!(p.module("psu").unwrap().banks.len(), 2);
}

#[test]
fn triskar2_module_tables() {
    let p = triskar2();
    let idx = p.modules.iter().position(|m| m.name == "motor1").unwrap();
    let t = p.tables(idx).unwrap();
    assert_eq!(t.module, 1);
    assert_eq!(t.bus.fingerprint, p.fingerprint);
    assert_eq!(t.bus.slots_per_cycle, 60);
    assert_eq!(t.bus.hyperperiod_cycles, 4);
    assert_eq!(
        t.tx.iter().map(|x| x.msg_id.0).collect::<Vec<_>>(),
        // encoder1, wheel_setpoints; then module_state_motor1 and health_motor1 (the
        // module-state topics, numbered after every declared and service topic).
        vec![0x144, 0x147, 0x151, 0x152]
    );
    assert_eq!(
        t.rx.iter()
            .map(|x| (x.msg_id.0, x.size, x.arena_offset))
            .collect::<Vec<_>>(),
        // velocity; the health of motor2, motor3, proximity and psu (a block shared
        // with the gateway); the gateway's health. Not the gateway's module table: only
        // the host reads it.
        vec![
            (0x146, 12, 0),
            (0x14C, 8, 12),
            (0x14D, 8, 20),
            (0x14E, 8, 28),
            (0x14F, 8, 36),
            (0x153, 8, 44)
        ]
    );
    assert!(t.master_masks.is_empty());
    let first: Vec<CalEntry> = t.calendar.iter().take(5).copied().collect();
    assert_eq!(
        first,
        vec![
            CalEntry {
                slot: 1,
                tx: 0,
                fragment: 0
            },
            CalEntry {
                slot: 3,
                tx: 1,
                fragment: 1
            },
            CalEntry {
                slot: 4,
                tx: 1,
                fragment: 0
            },
            CalEntry {
                slot: 31,
                tx: 0,
                fragment: 0
            },
            CalEntry {
                slot: 61,
                tx: 0,
                fragment: 0
            },
        ]
    );
    assert_eq!(t.calendar.len(), 8 + 8);
    let gw = p.modules.iter().position(|m| m.name == "gateway").unwrap();
    assert_eq!(p.tables(gw).unwrap().master_masks.len(), 4);
}

/// Every module's banks pass exactly the topics it receives (all laxity and fragment
/// values a topic's frames can carry), the sync and heartbeats, and no other topic.
#[test]
fn filters_are_exact() {
    for p in [triskar2(), paper()] {
        for (mi, m) in p.modules.iter().enumerate() {
            let pass = |raw: u32| m.banks.iter().any(|b| passes(&b.filter, raw));
            assert!(pass(0x7FFF), "{}: sync", m.name);
            assert!(pass((63 << 23) | (0x13F << 7)), "{}: heartbeat", m.name);
            for t in p.topics.iter().filter(|t| t.on_bus) {
                let wanted = t.module != mi && t.subscribers.iter().any(|s| s.module == mi);
                let laxities: Vec<u32> = match t.class {
                    Class::Hrt => vec![0],
                    Class::Srt => (1..=62).collect(),
                    Class::Nrt => vec![63],
                };
                for lax in laxities {
                    for frag in 0..u32::from(t.fragments) {
                        let raw = (lax << 23) | (u32::from(t.msg_id.0) << 7) | frag;
                        assert_eq!(
                            pass(raw),
                            wanted,
                            "{}: {} lax {lax} frag {frag}",
                            m.name,
                            t.name
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn fingerprint_is_stable_and_sensitive() {
    let src = std::fs::read_to_string(root().join("robot.toml")).unwrap();
    let a = analyze("robot.toml", &src).plan.unwrap().fingerprint;
    assert_eq!(
        a,
        analyze("other-name.toml", &src).plan.unwrap().fingerprint
    );
    // Reordering topic sections changes nothing on the wire, so not the fingerprint.
    let (head, topics) = src.split_at(src.find("[topics.teleop]").unwrap());
    let mut sections: Vec<&str> = topics.split("\n[topics.").collect();
    sections.reverse();
    let reordered = format!(
        "{head}{}",
        sections
            .iter()
            .map(|s| if s.starts_with('[') {
                s.to_string()
            } else {
                format!("[topics.{s}")
            })
            .collect::<Vec<_>>()
            .join("\n")
    );
    let b = analyze("robot.toml", &reordered);
    assert!(b.diagnostics.is_empty(), "{}", b.diagnostics.render());
    assert_eq!(b.plan.unwrap().fingerprint, a);
    // A different rate changes it.
    let changed = src
        .replace(
            "rate = \"50Hz\"\nsubscribers = [\"ros_bridge\"]",
            "rate = \"25Hz\"\nsubscribers = [\"ros_bridge\"]",
        )
        // The slower odometry lengthens the odometry_feedback chain past 50 ms.
        .replace("budget = \"50ms\"", "budget = \"100ms\"");
    assert_ne!(changed, src);
    assert_ne!(analyze("robot.toml", &changed).plan.unwrap().fingerprint, a);
}

#[test]
fn two_hundred_hrt_topics_on_64_slots() {
    let start = std::time::Instant::now();
    let p = Robot::load(root().join("robots/hrt200.toml")).unwrap();
    let elapsed = start.elapsed();
    assert_eq!(p.topics.len(), 200);
    assert_eq!(p.bus.hyperperiod_slots, 1024);
    // 40 x 16 + 80 x 2 + 80 x 1 per 1024-slot hyperperiod.
    assert_eq!(p.reserved_slots(), 880);
    assert_eq!(p.module("sink").unwrap().banks.len(), 3);
    // Generous bound for an unoptimised test build on a shared 2-core machine.
    assert!(elapsed.as_secs() < 10, "{elapsed:?}");
}
