//! Two generated Triskar2 modules (the gateway, bus master, and the proximity module)
//! with their engines and `ModuleHost`s on an ideal bus: a typed HRT message (IR ranges,
//! proximity → gateway) in its reserved slots and a typed SRT message (teleop command,
//! gateway → proximity) by deadline, through the generated filters, tables and handles.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

mod common;

use common::{Bus, Module};
use rtcan::core::Class;

mod robot {
    rtcan::robot!("robot.toml");
}

use robot::{gateway, proximity, topics};

#[test]
fn gateway_and_proximity_exchange_typed_hrt_and_srt_messages() {
    let mut bus = Bus::new(robot::BUS.bitrate);
    let gw = bus.add(Box::new(Module::new(
        gateway::engine(0),
        gateway::host(),
        gateway::FILTERS,
    )));
    let px = bus.add(Box::new(Module::new(
        proximity::engine(0),
        proximity::host(),
        proximity::FILTERS,
    )));
    let slot = robot::BUS.slot_ns;
    let cycle = robot::BUS.cycle_ns();

    // Two cycles: the proximity module locks on the gateway's sync.
    bus.run(2 * cycle);
    assert!(proximity::STATUS.safe_reason() != Some(rtcan::pubsub::SafeReason::NoSync));

    // HRT: the IR ranger publishes; the value goes out in its reserved slot.
    let ranges = robot::Proximity {
        range_mm: [120, 340, 65535, 8],
    };
    let t_pub = bus.now;
    proximity::nodes::ir_ranger::proximity_pub()
        .send(ranges, t_pub)
        .unwrap();
    // Local subscriber (obstacle avoidance on the same module) sees it at once.
    let local = proximity::nodes::obstacle_avoid::proximity_sub()
        .try_recv()
        .unwrap();
    assert_eq!(*local, ranges);
    drop(local);

    // SRT: the ROS bridge forwards a velocity command to the obstacle avoidance.
    let cmd = robot::Twist {
        vx: 0.5,
        vy: -0.25,
        wz: 1.0,
    };
    let t_cmd = bus.now;
    gateway::nodes::ros_bridge::teleop_pub()
        .send(cmd, t_cmd)
        .unwrap();

    // One HRT period (4 cycles) later both have arrived.
    let period = u64::from(topics::PROXIMITY.period_slots.unwrap()) * slot;
    assert_eq!(period, 240 * slot);
    bus.run(t_pub + period + cycle);

    let got = gateway::nodes::ros_bridge::proximity_sub()
        .try_recv()
        .unwrap();
    assert_eq!(*got, ranges);
    let got_cmd = proximity::nodes::obstacle_avoid::teleop_sub()
        .try_recv()
        .unwrap();
    assert_eq!(*got_cmd, cmd);
    // Delivered within the topic's deadline, stamped with the first frame's SOF.
    let deadline = topics::TELEOP.deadline_ns.unwrap();
    assert!(got_cmd.stamp() > t_cmd && got_cmd.stamp() < t_cmd + deadline);
    assert_eq!(topics::TELEOP.class, Class::Srt);

    // On the wire: the HRT frames have laxity 0, the topic's ID, and start in a slot
    // of the generated calendar; the SRT frame has an SRT laxity code.
    let hrt: Vec<_> = bus
        .log
        .iter()
        .filter(|f| f.frame.id().msg_id() == topics::PROXIMITY.msg_id)
        .collect();
    assert_eq!(hrt.len(), 1, "one message of one frame");
    assert_eq!(hrt[0].frame.id().laxity(), 0);
    assert_eq!(hrt[0].node, px);
    assert_eq!(hrt[0].frame.data(), &[120, 0, 84, 1, 255, 255, 8, 0]);
    assert_eq!(got.stamp(), hrt[0].sof);
    // The master's cycle 0 starts one slot after its creation at t = 0.
    let bus_slot = (hrt[0].sof - slot) / slot;
    let hyper = u64::from(robot::BUS.hyperperiod_cycles) * u64::from(robot::BUS.slots_per_cycle);
    let cal_slot = u32::try_from(bus_slot % hyper).unwrap();
    assert!(
        proximity::CALENDAR.iter().any(|c| c.slot == cal_slot),
        "HRT frame in slot {cal_slot}, calendar {:?}",
        proximity::CALENDAR
    );
    assert!(
        (hrt[0].sof - slot) % slot < slot / 4,
        "starts at the slot boundary"
    );
    let srt: Vec<_> = bus
        .log
        .iter()
        .filter(|f| f.frame.id().msg_id() == topics::TELEOP.msg_id)
        .collect();
    assert_eq!(srt.len(), usize::from(topics::TELEOP.fragments));
    assert!(srt
        .iter()
        .all(|f| (1..=62).contains(&f.frame.id().laxity()) && f.node == gw));

    // Every frame on this bus (sync, heartbeats, the two topics) is meant for the other
    // module: the generated filters passed all of them.
    assert_eq!(bus.filtered, vec![]);
    assert_eq!(gateway::topics::PROXIMITY.stats().published, 1);
    assert_eq!(proximity::topics::PROXIMITY.stats().sent, 1);
}
