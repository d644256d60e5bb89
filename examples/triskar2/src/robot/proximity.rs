//! Module `proximity`: four IR rangers and the obstacle override (nodes `ir_ranger`, `obstacle_avoid`).
#![allow(clippy::unreadable_literal)]
use super::types::*;
use super::{cal, rx, tx, BUS, MASTER, MAX_MISSED_CYCLES};
use rtcan_core::id::Class;
use rtcan_core::tables::{CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_pubsub::{pool_blocks, ModuleHost, Node, Remote, RxPort, SafetyConfig, SystemStatus, Topic, TxPort};

// ---- tables (robot.toml plan, fingerprint 0x734e658e) ----
const TX: [TxTopic; 2] = [tx(0x0141, Class::Hrt, 8, 0), tx(0x0146, Class::Srt, 12, 10000000)];
const RX_TOPICS: [RxTopic; 1] = [rx(0x0148, 12, 0)];
const CALENDAR: [CalEntry; 1] = [cal(9, 0, 0)];
const MASTER_MASKS: [u64; 0] = [];
/// Engine tables of module `proximity` (index 4).
pub const TABLES: NodeTables<'static> = NodeTables { bus: BUS, module: 4, tx: &TX, rx: &RX_TOPICS, calendar: &CALENDAR, master_masks: &MASTER_MASKS };
/// Engine receive topics.
pub const RX: usize = 1;
/// Reassembly arena bytes.
pub const ARENA: usize = 14;
/// Acceptance filters (id, mask), one Mask32 bank each.
pub const FILTERS: &[(u32, u32)] = &[(0x00000000, 0x1fff8000), (0x00008000, 0x007fe000), (0x0000a400, 0x007ffc00)];

// ---- topics: pools = subscribers × queue + subscribers + engine share + 1 loan ----
/// `teleop` (received, SRT from the gateway): subscriber 0 = obstacle_avoid (queue 2).
pub static TELEOP: Topic<Twist, { pool_blocks(1, 2, 0, 1) }, 1, 2> = Topic::new(Remote::None, None);
/// `proximity` (HRT every 40 ms): subscriber 0 = obstacle_avoid; the gateway by bus.
pub static PROXIMITY: Topic<Proximity, { pool_blocks(1, 1, 2, 1) }, 1, 1> = Topic::new(Remote::Hrt, None);
/// `velocity` (SRT, 10 ms deadline, to kinematics on motor1).
pub static VELOCITY: Topic<Twist, { pool_blocks(0, 2, 3, 1) }, 0, 2> =
    Topic::new(Remote::Srt, Some(crate::driver::kick));
/// Engine SRT/NRT queue: `velocity` (2 fragments per message, queue 2).
pub const QUEUE: usize = 4;

static TX_PORTS: [&dyn TxPort; 2] = [&PROXIMITY, &VELOCITY];
static RX_PORTS: [&dyn RxPort; 1] = [&TELEOP];

/// Node `ir_ranger` (priority 2).
pub static IR_RANGER: Node = Node::new("ir_ranger");
/// Node `obstacle_avoid` (priority 3).
pub static OBSTACLE_AVOID: Node = Node::new("obstacle_avoid");
static NODES: [&Node; 2] = [&IR_RANGER, &OBSTACLE_AVOID];

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
