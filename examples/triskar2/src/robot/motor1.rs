//! Module `motor1`: DC motor 1 and the inverse kinematics (nodes `kinematics`, `motor_ctrl1`).
#![allow(clippy::unreadable_literal)]
use super::types::*;
use super::{cal, rx, tx, BUS, MASTER, MAX_MISSED_CYCLES};
use rtcan_core::id::Class;
use rtcan_core::tables::{CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_pubsub::{pool_blocks, ModuleHost, Node, Remote, RxPort, SafetyConfig, SystemStatus, Topic, TxPort};

// ---- tables (robot.toml plan, fingerprint 0x734e658e) ----
const TX: [TxTopic; 2] = [tx(0x0144, Class::Hrt, 8, 0), tx(0x0147, Class::Hrt, 12, 0)];
const RX_TOPICS: [RxTopic; 1] = [rx(0x0146, 12, 0)];
const CALENDAR: [CalEntry; 16] = [cal(1, 0, 0), cal(3, 1, 1), cal(4, 1, 0), cal(31, 0, 0), cal(61, 0, 0), cal(63, 1, 1), cal(64, 1, 0), cal(91, 0, 0), cal(121, 0, 0), cal(123, 1, 1), cal(124, 1, 0), cal(151, 0, 0), cal(181, 0, 0), cal(183, 1, 1), cal(184, 1, 0), cal(211, 0, 0)];
const MASTER_MASKS: [u64; 0] = [];
/// Engine tables of module `motor1` (index 1).
pub const TABLES: NodeTables<'static> = NodeTables { bus: BUS, module: 1, tx: &TX, rx: &RX_TOPICS, calendar: &CALENDAR, master_masks: &MASTER_MASKS };
/// Engine receive topics.
pub const RX: usize = 1;
/// Reassembly arena bytes.
pub const ARENA: usize = 14;
/// Acceptance filters (id, mask), one Mask32 bank each.
pub const FILTERS: &[(u32, u32)] = &[(0x00000000, 0x1fff8000), (0x00008000, 0x007fe000), (0x0000a300, 0x007fff80)];

// ---- topics: pools = subscribers × queue + subscribers + engine share + 1 loan ----
/// `velocity` (received, SRT from proximity): subscriber 0 = kinematics.
pub static VELOCITY: Topic<Twist, { pool_blocks(1, 1, 0, 1) }, 1, 1> = Topic::new(Remote::None, None);
/// `wheel_setpoints` (HRT): subscriber 0 = motor_ctrl1; motors 2 and 3 get it by bus.
pub static WHEEL_SETPOINTS: Topic<WheelSpeeds, { pool_blocks(1, 1, 2, 1) }, 1, 1> =
    Topic::new(Remote::Hrt, None);
/// `encoder1` (HRT, to odometry on motor2).
pub static ENCODER1: Topic<Encoder, { pool_blocks(0, 1, 2, 1) }, 0, 1> = Topic::new(Remote::Hrt, None);
/// Engine SRT/NRT queue (this module sends HRT only).
pub const QUEUE: usize = 1;

static TX_PORTS: [&dyn TxPort; 2] = [&ENCODER1, &WHEEL_SETPOINTS];
static RX_PORTS: [&dyn RxPort; 1] = [&VELOCITY];

/// Node `kinematics` (priority 2).
pub static KINEMATICS: Node = Node::new("kinematics");
/// Node `motor_ctrl1` (priority 3).
pub static MOTOR_CTRL1: Node = Node::new("motor_ctrl1");
static NODES: [&Node; 2] = [&KINEMATICS, &MOTOR_CTRL1];

/// This module's system-status view (fed by the engine's events).
pub static STATUS: SystemStatus = SystemStatus::new(SafetyConfig {
    module: TABLES.module,
    master: MASTER,
    max_missed_cycles: MAX_MISSED_CYCLES,
});

/// The engine's host: topics in table order, status, nodes.
pub fn host() -> ModuleHost<'static> {
    ModuleHost::new(&TX_PORTS, &RX_PORTS, &STATUS, &NODES)
}
