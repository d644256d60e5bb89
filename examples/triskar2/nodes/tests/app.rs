//! The module apps on their generated topics, without a bus: frames are handed to the
//! generated ModuleHost as the engine would, system events drive the lifecycle.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use std::sync::Mutex;

use rtcan::core::driver::{Event, Host};
use rtcan::pubsub::Message;
use rtcan::robot_toml as robot;
use triskar2_nodes::app::{Motor3App, MotorHw, ProximityApp, ProximityHw};

/// The generated topics are statics: one test at a time.
static LOCK: Mutex<()> = Mutex::new(());
const MS: u64 = 1_000_000;

#[derive(Default)]
struct Wheel {
    count: u16,
    duty: f32,
}

impl MotorHw for Wheel {
    fn encoder_count(&mut self) -> u16 {
        self.count
    }
    fn set_duty(&mut self, duty: f32) {
        self.duty = duty;
    }
}

fn setpoints(w: [f32; 3]) -> [u8; 12] {
    let mut b = [0u8; 12];
    robot::WheelSpeeds { w }.encode(&mut b);
    b
}

/// Heartbeats of every module (the master's among them): robot.toml's `on_missing`
/// rules keep a module in its safe state until it has heard every module it depends on
/// (issue 15's supervision).
fn all_modules_heard(host: &mut rtcan::pubsub::ModuleHost<'static>) {
    for module in 0..robot::supervision::MODULES as u8 {
        host.event(Event::Heartbeat { module, state: 1 });
    }
}

#[test]
fn motor3_follows_its_setpoint_and_stops_in_the_safe_state() {
    let _g = LOCK.lock().unwrap_or_else(|p| p.into_inner());
    rtcan::robot_toml::motor3::reset();
    let mut host = robot::motor3::host();
    let mut a = Motor3App::new();
    let mut hw = Wheel::default();
    // Not synchronised: the node stays in Init, the motor does not move.
    host.deliver(0, &setpoints([0.0, 0.0, 10.0]), 0);
    assert_eq!(a.poll(0, &mut hw), 5 * MS);
    assert_eq!(hw.duty, 0.0);
    host.event(Event::Synced);
    all_modules_heard(&mut host);
    host.deliver(0, &setpoints([0.0, 0.0, 10.0]), 5 * MS);
    a.poll(5 * MS, &mut hw);
    assert!(
        hw.duty > 0.0,
        "wheel 3 driven towards 10 rad/s: {}",
        hw.duty
    );
    assert_eq!(robot::motor3::nodes::motor_ctrl3::NODE.state().as_u8(), 1);
    // The encoder topic went to the bus side (HRT latch).
    assert_eq!(robot::motor3::topics::ENCODER3.stats().published, 2);
    // Sync lost: safe state, zero duty, and it stays stopped when sync comes back.
    host.event(Event::SyncLost);
    host.deliver(0, &setpoints([0.0, 0.0, 10.0]), 10 * MS);
    a.poll(10 * MS, &mut hw);
    assert_eq!(hw.duty, 0.0);
    assert!(a.motor_ctrl3.is_safe());
    host.event(Event::Synced);
    host.deliver(0, &setpoints([0.0, 0.0, 10.0]), 15 * MS);
    a.poll(15 * MS, &mut hw);
    assert_eq!(hw.duty, 0.0, "no restart by itself");
    rtcan::robot_toml::motor3::reset();
    assert_eq!(robot::motor3::topics::ENCODER3.stats().published, 0);
}

struct Wall(f32);

impl ProximityHw for Wall {
    fn ranges_m(&mut self) -> [f32; 4] {
        [self.0, 0.8, 0.8, 0.8]
    }
}

fn teleop(vx: f32) -> [u8; 12] {
    let mut b = [0u8; 12];
    robot::Twist {
        vx,
        vy: 0.0,
        wz: 0.0,
    }
    .encode(&mut b);
    b
}

#[test]
fn proximity_module_limits_the_teleop_command_near_a_wall() {
    let _g = LOCK.lock().unwrap_or_else(|p| p.into_inner());
    rtcan::robot_toml::proximity::reset();
    let mut host = robot::proximity::host();
    host.event(Event::Synced);
    all_modules_heard(&mut host);
    let mut a = ProximityApp::new();
    // Far from the wall: the command passes unchanged.
    host.deliver(0, &teleop(0.3), 0);
    a.poll(0, &mut Wall(0.8));
    assert_eq!(a.obstacle_avoid.last_velocity.unwrap().vx, 0.3);
    assert_eq!(a.obstacle_avoid.limited_mask, 0);
    // At the stop distance (filtered over a few samples): forward motion is removed.
    for k in 1..=20u64 {
        host.deliver(0, &teleop(0.3), k * 40 * MS);
        a.poll(k * 40 * MS, &mut Wall(0.2));
    }
    assert!(
        a.obstacle_avoid.last_velocity.unwrap().vx < 0.001,
        "{:?}",
        a.obstacle_avoid.last_velocity
    );
    assert_eq!(a.obstacle_avoid.limited_mask, 1);
    assert!(a.obstacle_avoid.overrides >= 1);
    // A stale command is not forwarded.
    let before = robot::proximity::topics::VELOCITY.stats().published;
    a.poll(2_000 * MS, &mut Wall(0.8));
    assert_eq!(robot::proximity::topics::VELOCITY.stats().published, before);
    rtcan::robot_toml::proximity::reset();
}
