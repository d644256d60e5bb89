//! Module `motor2`: DC motor 2 and the odometry (nodes `odometry`, `motor_ctrl2`).
#![allow(clippy::unreadable_literal)]
use super::types::*;
use super::{cal, rx, tx, BUS, MASTER, MAX_MISSED_CYCLES};
use rtcan_core::id::Class;
use rtcan_core::tables::{CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_pubsub::{pool_blocks, ModuleHost, Node, Remote, RxPort, SafetyConfig, SystemStatus, Topic, TxPort};

// ---- tables (robot.toml plan, fingerprint 0x734e658e) ----
const TX: [TxTopic; 1] = [tx(0x0140, Class::Hrt, 24, 0)];
const RX_TOPICS: [RxTopic; 3] = [rx(0x0144, 8, 0), rx(0x0145, 8, 8), rx(0x0147, 12, 16)];
const CALENDAR: [CalEntry; 8] = [cal(5, 0, 3), cal(6, 0, 2), cal(7, 0, 1), cal(8, 0, 0), cal(125, 0, 3), cal(126, 0, 2), cal(127, 0, 1), cal(128, 0, 0)];
const MASTER_MASKS: [u64; 0] = [];
/// Engine tables of module `motor2` (index 2).
pub const TABLES: NodeTables<'static> = NodeTables { bus: BUS, module: 2, tx: &TX, rx: &RX_TOPICS, calendar: &CALENDAR, master_masks: &MASTER_MASKS };
/// Engine receive topics.
pub const RX: usize = 3;
/// Reassembly arena bytes.
pub const ARENA: usize = 30;
/// Acceptance filters (id, mask), one Mask32 bank each.
pub const FILTERS: &[(u32, u32)] = &[(0x00000000, 0x1fff8000), (0x00008000, 0x007fe000), (0x0000a200, 0x007fff00), (0x0000a380, 0x007fff80)];

// ---- topics: pools = subscribers × queue + subscribers + engine share + 1 loan ----
/// `encoder1` (received): subscriber 0 = odometry (queue 2).
pub static ENCODER1: Topic<Encoder, { pool_blocks(1, 2, 0, 1) }, 1, 2> = Topic::new(Remote::None, None);
/// `encoder2` (local only: publisher and subscriber both on this module).
pub static ENCODER2: Topic<Encoder, { pool_blocks(1, 2, 0, 1) }, 1, 2> = Topic::new(Remote::None, None);
/// `encoder3` (received): subscriber 0 = odometry (queue 2).
pub static ENCODER3: Topic<Encoder, { pool_blocks(1, 2, 0, 1) }, 1, 2> = Topic::new(Remote::None, None);
/// `wheel_setpoints` (received): subscriber 0 = motor_ctrl2.
pub static WHEEL_SETPOINTS: Topic<WheelSpeeds, { pool_blocks(1, 1, 0, 1) }, 1, 1> =
    Topic::new(Remote::None, None);
/// `odometry` (HRT, 4 fragments, to the gateway).
pub static ODOMETRY: Topic<Odometry, { pool_blocks(0, 1, 2, 1) }, 0, 1> = Topic::new(Remote::Hrt, None);
/// Engine SRT/NRT queue (this module sends HRT only).
pub const QUEUE: usize = 1;

static TX_PORTS: [&dyn TxPort; 1] = [&ODOMETRY];
static RX_PORTS: [&dyn RxPort; 3] = [&ENCODER1, &ENCODER3, &WHEEL_SETPOINTS];

/// Node `odometry` (priority 1).
pub static ODOMETRY_NODE: Node = Node::new("odometry");
/// Node `motor_ctrl2` (priority 3).
pub static MOTOR_CTRL2: Node = Node::new("motor_ctrl2");
static NODES: [&Node; 2] = [&ODOMETRY_NODE, &MOTOR_CTRL2];

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
