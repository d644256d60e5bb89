//! Module `motor3`: DC motor 3 (node `motor_ctrl3`).
#![allow(clippy::unreadable_literal)]
use super::types::*;
use super::{cal, rx, tx, BUS, MASTER, MAX_MISSED_CYCLES};
use rtcan_core::id::Class;
use rtcan_core::tables::{CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_pubsub::{pool_blocks, ModuleHost, Node, Remote, RxPort, SafetyConfig, SystemStatus, Topic, TxPort};

// ---- tables (robot.toml plan, fingerprint 0x734e658e) ----
const TX: [TxTopic; 1] = [tx(0x0145, Class::Hrt, 8, 0)];
const RX_TOPICS: [RxTopic; 1] = [rx(0x0147, 12, 0)];
const CALENDAR: [CalEntry; 8] = [cal(2, 0, 0), cal(32, 0, 0), cal(62, 0, 0), cal(92, 0, 0), cal(122, 0, 0), cal(152, 0, 0), cal(182, 0, 0), cal(212, 0, 0)];
const MASTER_MASKS: [u64; 0] = [];
/// Engine tables of module `motor3` (index 3).
pub const TABLES: NodeTables<'static> = NodeTables { bus: BUS, module: 3, tx: &TX, rx: &RX_TOPICS, calendar: &CALENDAR, master_masks: &MASTER_MASKS };
/// Engine receive topics.
pub const RX: usize = 1;
/// Reassembly arena bytes.
pub const ARENA: usize = 14;
/// Acceptance filters (id, mask), one Mask32 bank each.
pub const FILTERS: &[(u32, u32)] = &[(0x00000000, 0x1fff8000), (0x00008000, 0x007fe000), (0x0000a380, 0x007fff80)];

// ---- topics: pools = subscribers × queue + subscribers + engine share + 1 loan ----
/// `wheel_setpoints` (received): subscriber 0 = motor_ctrl3.
pub static WHEEL_SETPOINTS: Topic<WheelSpeeds, { pool_blocks(1, 1, 0, 1) }, 1, 1> =
    Topic::new(Remote::None, None);
/// `encoder3` (HRT, to odometry on motor2).
pub static ENCODER3: Topic<Encoder, { pool_blocks(0, 1, 2, 1) }, 0, 1> = Topic::new(Remote::Hrt, None);
/// Engine SRT/NRT queue (this module sends HRT only).
pub const QUEUE: usize = 1;

static TX_PORTS: [&dyn TxPort; 1] = [&ENCODER3];
static RX_PORTS: [&dyn RxPort; 1] = [&WHEEL_SETPOINTS];

/// Node `motor_ctrl3` (priority 3).
pub static MOTOR_CTRL3: Node = Node::new("motor_ctrl3");
static NODES: [&Node; 1] = [&MOTOR_CTRL3];

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
