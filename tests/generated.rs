//! The code generated for the top-level robot.toml (by build.rs, `rtcan::robot_toml`) and
//! by `rtcan::robot!` compiles and agrees with the model: exact encodings, topic
//! constants, tables, filters and master masks.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use rtcan::core::{CanId, Class, MsgId};
use rtcan::pubsub::Message;
use rtcan::robot_toml as robot;
use rtcan_model::{Plan, Robot};

mod codec {
    rtcan::robot!("tests/robots/codec.toml");
}
mod paper {
    rtcan::robot!("robots/rtcan-paper.toml");
}
/// The same file through the macro: must equal what build.rs generated.
mod triskar {
    rtcan::robot!("robot.toml");
}

fn plan(file: &str) -> Plan {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/").to_string() + file;
    Robot::load(path).unwrap_or_else(|d| panic!("{}", d.render()))
}

fn bytes<M: Message>(m: &M) -> Vec<u8> {
    let mut out = vec![0u8; M::SIZE];
    m.encode(&mut out);
    assert_eq!(
        M::decode(&out).map(|d| bytes_of(&d)),
        Some(out.clone()),
        "round trip"
    );
    out
}

fn bytes_of<M: Message>(m: &M) -> Vec<u8> {
    let mut out = vec![0u8; M::SIZE];
    m.encode(&mut out);
    out
}

#[test]
fn triskar_messages_encode_little_endian_packed() {
    let e = robot::Encoder {
        ticks: -2,
        speed: 1.5,
    };
    assert_eq!(bytes(&e), [0xFE, 0xFF, 0xFF, 0xFF, 0x00, 0x00, 0xC0, 0x3F]);
    let b = robot::Battery {
        mv: 12_000,
        ma: -500,
        pct: 87,
    };
    assert_eq!(bytes(&b), [0xE0, 0x2E, 0x0C, 0xFE, 87]);
    assert_eq!(robot::Battery::SIZE, 5);
    let w = robot::WheelSpeeds {
        w: [1.0, -2.0, 0.5],
    };
    assert_eq!(bytes(&w), [0, 0, 0x80, 0x3F, 0, 0, 0, 0xC0, 0, 0, 0, 0x3F]);
    let mut text = [0u8; 29];
    text[..2].copy_from_slice(b"ok");
    let l = robot::LogLine {
        level: 3,
        code: 0x0102,
        text,
    };
    let lb = bytes(&l);
    assert_eq!(lb.len(), 32);
    assert_eq!(&lb[..5], &[3, 0x02, 0x01, b'o', b'k']);
    assert!(lb[5..].iter().all(|b| *b == 0));
    // Wrong lengths decode to None, never a panic.
    assert_eq!(robot::Encoder::decode(&[0; 7]), None);
    assert_eq!(robot::Encoder::decode(&[0; 9]), None);
    assert_eq!(
        robot::Battery::default(),
        robot::Battery {
            mv: 0,
            ma: 0,
            pct: 0
        }
    );
}

#[test]
fn every_field_type_has_its_exact_encoding() {
    let m = codec::AllPrims {
        a_u8: 0x01,
        a_u16: 0x0302,
        a_u32: 0x0706_0504,
        a_u64: 0x0F0E_0D0C_0B0A_0908,
        a_i8: -1,
        a_i16: -2,
        a_i32: -3,
        a_i64: -4,
        a_f32: -0.0,
        a_f64: 2.0,
        a_bool: true,
        a_arr: [1, -1, 0x1234],
        flags: [false, true],
    };
    let mut expect = vec![0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07];
    expect.extend(8u8..=0x0F);
    expect.extend([0xFF, 0xFE, 0xFF, 0xFD, 0xFF, 0xFF, 0xFF]);
    expect.extend([0xFC, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF]);
    expect.extend([0, 0, 0, 0x80]);
    expect.extend([0, 0, 0, 0, 0, 0, 0, 0x40]);
    expect.push(1);
    expect.extend([1, 0, 0xFF, 0xFF, 0x34, 0x12]);
    expect.extend([0, 1]);
    assert_eq!(
        codec::AllPrims::SIZE,
        1 + 2 + 4 + 8 + 1 + 2 + 4 + 8 + 4 + 8 + 1 + 6 + 2
    );
    assert_eq!(bytes(&m), expect);
    // A bool byte other than 0/1 is rejected.
    let mut bad = expect.clone();
    bad[42] = 2;
    assert_eq!(codec::AllPrims::decode(&bad), None);
    assert_eq!(codec::Flags::decode(&[1]), Some(codec::Flags { on: true }));
    assert_eq!(codec::Flags::decode(&[7]), None);
    // A short output buffer is left partly written, no panic.
    let mut short = [0xAAu8; 3];
    m.encode(&mut short);
    assert_eq!(short, [0x01, 0x02, 0x03]);
}

fn check_topics(infos: &[rtcan::TopicInfo], plan: &Plan) {
    assert_eq!(infos.len(), plan.topics.len());
    for (i, t) in infos.iter().zip(&plan.topics) {
        assert_eq!(i.name, t.name);
        assert_eq!(i.msg_id, t.msg_id, "{}", t.name);
        assert_eq!(i.class, t.class, "{}", t.name);
        assert_eq!(i.size, t.size, "{}", t.name);
        assert_eq!(i.fragments, t.fragments, "{}", t.name);
        assert_eq!(i.on_bus, t.on_bus, "{}", t.name);
        assert_eq!(usize::from(i.module), t.module, "{}", t.name);
        assert_eq!(i.period_slots, t.period_slots, "{}", t.name);
        assert_eq!(i.phase_slot, t.phase_slot, "{}", t.name);
        assert_eq!(i.deadline_ns, t.deadline_ns, "{}", t.name);
    }
}

#[test]
fn topic_constants_equal_the_plan() {
    let p = plan("robot.toml");
    check_topics(robot::topics::all(), &p);
    check_topics(paper::topics::all(), &plan("robots/rtcan-paper.toml"));
    // Spot values a reader can check against robot.toml: encoder1 is a 200 Hz HRT
    // topic of 8 bytes, one frame, sent by motor1 (module 1) every 30 slots of 166.66 us.
    let e = robot::topics::ENCODER1;
    assert_eq!(
        (e.class, e.size, e.fragments, e.module, e.period_slots),
        (Class::Hrt, 8, 1, 1, Some(30))
    );
    assert_eq!(robot::topics::VELOCITY.deadline_ns, Some(10_000_000));
    assert_eq!(robot::topics::LOG.fragments, 4);
    // encoder2 is consumed on its own module (odometry on motor2): never on the bus.
    assert_eq!(
        (
            robot::topics::ENCODER2.on_bus,
            robot::topics::ENCODER2.module
        ),
        (false, 2)
    );
}

type ModuleRow = (
    &'static str,
    rtcan::core::NodeTables<'static>,
    &'static [(u32, u32)],
);

/// The module tables of the generated code, by module index.
fn triskar_tables() -> Vec<ModuleRow> {
    vec![
        ("gateway", robot::gateway::TABLES, robot::gateway::FILTERS),
        ("motor1", robot::motor1::TABLES, robot::motor1::FILTERS),
        ("motor2", robot::motor2::TABLES, robot::motor2::FILTERS),
        ("motor3", robot::motor3::TABLES, robot::motor3::FILTERS),
        (
            "proximity",
            robot::proximity::TABLES,
            robot::proximity::FILTERS,
        ),
        ("psu", robot::psu::TABLES, robot::psu::FILTERS),
    ]
}

#[test]
fn module_tables_equal_the_plan_and_the_macro_output() {
    let p = plan("robot.toml");
    assert_eq!(robot::FINGERPRINT, p.fingerprint);
    assert_eq!(
        triskar::FINGERPRINT,
        robot::FINGERPRINT,
        "macro and build.rs agree"
    );
    assert_eq!(robot::BUS, p.bus.config(p.fingerprint));
    assert_eq!(usize::from(robot::MASTER), p.bus.master);
    let tables = triskar_tables();
    assert_eq!(tables.len(), p.modules.len());
    for (i, (name, t, _)) in tables.iter().enumerate() {
        let m = p.tables(i).unwrap();
        assert_eq!(*name, p.modules[i].name);
        assert_eq!(t.bus, m.bus, "{name}");
        assert_eq!(t.module, m.module, "{name}");
        assert_eq!(t.tx, m.tx.as_slice(), "{name}");
        assert_eq!(t.rx, m.rx.as_slice(), "{name}");
        assert_eq!(t.calendar, m.calendar.as_slice(), "{name}");
        assert_eq!(t.master_masks, m.master_masks.as_slice(), "{name}");
    }
    assert_eq!(
        triskar::motor2::TABLES.calendar,
        robot::motor2::TABLES.calendar
    );
    // Engine sizes: motor1 receives `velocity` (12 B), and as the backup master the
    // five other modules' health (8 B each); the gateway receives odometry (24),
    // proximity (8), battery (5), log (32), the `proximity_read` service's reply frames
    // (5: call number + sensor + range) and the five other modules' health (robot.toml
    // `on_missing`). No module receives a module table: only the host reads it.
    assert_eq!(
        (robot::motor1::RX_COUNT, robot::motor1::ARENA_BYTES),
        (1 + 5, 12 + 5 * 8)
    );
    assert_eq!(robot::gateway::RX_COUNT, 5 + 5);
    assert_eq!(robot::gateway::ARENA_BYTES, 24 + 8 + 5 + 32 + 5 + 5 * 8);
    // The gateway sends proximity_read requests (SRT, queue of in_flight = 2) besides
    // teleop (queue 2), its heartbeat, its health and its module table (NRT, queue 1).
    assert_eq!(robot::gateway::QUEUE_CAPACITY, 1 + 2 + 2 + 1 + 1);
    // psu sends battery and log (NRT, queues 1 and 4), its heartbeat and its health.
    assert_eq!(robot::psu::QUEUE_CAPACITY, 1 + 1 + 4 + 1);
    assert_eq!(
        (robot::gateway::IS_MASTER, robot::psu::IS_MASTER),
        (true, false)
    );
}

/// Every identifier topic `t` can appear with on the wire.
fn wire_ids(t: &rtcan_model::TopicPlan) -> Vec<u32> {
    let laxities: Vec<u8> = match t.class {
        Class::Hrt => vec![0],
        Class::Srt => (1..=62).collect(),
        Class::Nrt => vec![63],
    };
    let mut ids = Vec::new();
    for lax in laxities {
        // Multi-frame topics: any fragment field (transfer ID and counter, PROTOCOL §7.1).
        let fields = if t.fragments > 1 { 128 } else { 1 };
        for frag in 0..fields {
            ids.push(CanId::new(lax, t.msg_id, frag).unwrap().raw());
        }
    }
    ids
}

fn check_filters(p: &Plan, filters: &[(&str, &[(u32, u32)])]) {
    for (mi, (name, f)) in filters.iter().enumerate() {
        let m = &p.modules[mi];
        assert_eq!(*name, m.name);
        for (ti, t) in p.topics.iter().enumerate().filter(|(_, t)| t.on_bus) {
            let wanted = m.rx.contains(&ti);
            for id in wire_ids(t) {
                assert_eq!(
                    rtcan::filters_pass(f, id),
                    wanted,
                    "module {name}, topic {}, id {id:#x}",
                    t.name
                );
            }
        }
        // The sync frame with any cycle counter, and every heartbeat, always pass.
        for counter in [0u32, 1, 0x1234, 0x7FFF] {
            assert!(rtcan::filters_pass(f, counter), "{name}: sync {counter:#x}");
        }
        for module in 0..64u16 {
            let hb = CanId::new(63, MsgId(0x100 + module), 0).unwrap().raw();
            assert!(rtcan::filters_pass(f, hb), "{name}: heartbeat {module}");
        }
        // Nothing else: an SRT frame with a sync-range message ID is rejected.
        assert!(!rtcan::filters_pass(
            f,
            CanId::new(5, MsgId(0x10), 0).unwrap().raw()
        ));
    }
}

#[test]
fn filters_accept_exactly_the_subscriptions() {
    let p = plan("robot.toml");
    let t = triskar_tables();
    let filters: Vec<(&str, &[(u32, u32)])> = t.iter().map(|(n, _, f)| (*n, *f)).collect();
    check_filters(&p, &filters);
    // The bank form is the same acceptance as the flat form.
    for id in (0..0x1FFF_FFFFu32).step_by(0x3FF) {
        let banks = robot::gateway::FILTER_BANKS.iter().any(|b| b.passes(id));
        assert_eq!(banks, rtcan::filters_pass(robot::gateway::FILTERS, id));
    }
    assert!(robot::gateway::FILTER_BANKS.len() <= 14);

    let p = plan("robots/rtcan-paper.toml");
    check_filters(
        &p,
        &[
            ("node1", paper::node1::FILTERS),
            ("node2", paper::node2::FILTERS),
            ("node3", paper::node3::FILTERS),
            ("monitor", paper::monitor::FILTERS),
        ],
    );
}

#[test]
fn master_masks_equal_the_model_and_the_paper_reserves_40_of_60() {
    let p = plan("robot.toml");
    assert_eq!(robot::MASTER_MASKS.as_slice(), p.master_masks.as_slice());
    assert_eq!(robot::gateway::TABLES.master_masks, &robot::MASTER_MASKS);
    assert!(robot::motor1::TABLES.master_masks.is_empty());
    // Every mask marks the sync slot, and the union of the calendars is the mask.
    let slots = u32::from(robot::BUS.slots_per_cycle);
    let mut union = vec![1u64; robot::MASTER_MASKS.len()];
    for (_, t, _) in triskar_tables() {
        for c in t.calendar {
            let bit = 1u64 << (c.slot % slots);
            let cycle = (c.slot / slots) as usize;
            assert_eq!(union[cycle] & bit, 0, "slot {} reserved twice", c.slot);
            union[cycle] |= bit;
        }
    }
    assert_eq!(union.as_slice(), robot::MASTER_MASKS.as_slice());

    let paper_plan = plan("robots/rtcan-paper.toml");
    assert_eq!(
        paper::MASTER_MASKS.as_slice(),
        paper_plan.master_masks.as_slice()
    );
    assert_eq!(paper::BUS.slots_per_cycle, 60);
    assert!(!paper::MASTER_MASKS.is_empty());
    for m in paper::MASTER_MASKS {
        assert_eq!(m.count_ones(), 40, "{m:#018x}");
    }
    assert_eq!(paper::node1::TABLES.master_masks, &paper::MASTER_MASKS);
}

#[test]
fn typed_handles_publish_and_subscribe_locally() {
    // encoder2 is published and consumed on motor2 (odometry): a local topic.
    use robot::motor2::nodes::{motor_ctrl2, odometry};
    let sub = odometry::encoder2_sub();
    motor_ctrl2::encoder2_pub()
        .send(
            robot::Encoder {
                ticks: 7,
                speed: 0.25,
            },
            1_000,
        )
        .unwrap();
    let m = sub.try_recv().unwrap();
    assert_eq!(
        (*m, m.stamp()),
        (
            robot::Encoder {
                ticks: 7,
                speed: 0.25
            },
            1_000
        )
    );
    assert_eq!(motor_ctrl2::PRIORITY, 3);
    assert_eq!(odometry::NODE.name(), "odometry");
}

/// `<module>::params`: the declarations of robot.toml `[params]` in wire-index order, equal
/// to the model's, and typed handles whose `get`/`set` read and range-check the live table
/// (as a `set` over the bus does).
#[test]
fn params_are_generated_as_typed_handles_on_the_module_table() {
    use rtcan::pubsub::param::{Refused, Value};
    let p = plan("robot.toml");
    for (mi, m) in p.modules.iter().enumerate() {
        let decls: Vec<_> = p.params.iter().filter(|d| d.module == mi).collect();
        let specs: &[rtcan::pubsub::param::ParamSpec] = match m.name.as_str() {
            "motor1" => &robot::motor1::params::SPECS,
            "proximity" => &robot::proximity::params::SPECS,
            "gateway" => &robot::gateway::params::SPECS,
            "motor2" => &robot::motor2::params::SPECS,
            "motor3" => &robot::motor3::params::SPECS,
            "psu" => &robot::psu::params::SPECS,
            other => panic!("module {other} not in this test"),
        };
        assert_eq!(specs.len(), decls.len(), "{}", m.name);
        for (s, d) in specs.iter().zip(&decls) {
            assert_eq!(
                (s.name, s.unit, s.persist),
                (d.name.as_str(), d.unit.as_str(), d.persist)
            );
        }
    }
    use robot::motor1::params::{table, KI, KP};
    assert_eq!(robot::motor1::params::COUNT, 2);
    assert_eq!(robot::motor1::params::SPECS[0].name, "motor1.kp");
    assert_eq!(robot::motor1::params::SPECS[0].min, Value::F32(0.0));
    assert_eq!(robot::motor1::params::SPECS[0].max, Value::F32(1.0));
    assert_eq!((KP.index(), KI.index()), (0, 1));
    let mut t = table();
    assert_eq!((KP.get(&t), KI.get(&t)), (0.04, 1.0));
    assert_eq!(KP.set(&mut t, 0.8), Ok(0.8));
    assert_eq!(KP.get(&t), 0.8);
    assert_eq!(KP.set(&mut t, 1.5), Err(Refused::OutOfRange));
    assert_eq!(KP.set(&mut t, f32::NAN), Err(Refused::BadValue));
    assert_eq!(KP.get(&t), 0.8, "a refused value is never applied");
    assert_eq!(t.refused, 2);
    // The wire's set reaches the same value through the handle.
    let req = rtcan::pubsub::param::Request::Set {
        index: KI.index(),
        bits: 2.5f32.to_bits(),
    };
    let _ = t.serve(&req.encode(), &mut |_, _| true);
    assert_eq!(KI.get(&t), 2.5);
    use robot::proximity::params::{LOG_EVERY, STOP_DISTANCE};
    let mut t = robot::proximity::params::table();
    assert_eq!((STOP_DISTANCE.get(&t), LOG_EVERY.get(&t)), (0.25, 10u32));
    assert_eq!(LOG_EVERY.set(&mut t, 0), Err(Refused::OutOfRange));
    assert_eq!(LOG_EVERY.set(&mut t, 1000), Ok(1000));
    assert_eq!(robot::gateway::params::COUNT, 0);
}
