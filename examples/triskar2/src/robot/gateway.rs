//! Module `gateway`: host link and bus master (node `ros_bridge`).
#![allow(clippy::unreadable_literal)]
use super::types::*;
use super::{cal, rx, tx, BUS, MASTER, MAX_MISSED_CYCLES};
use rtcan_core::id::Class;
use rtcan_core::tables::{CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_pubsub::{pool_blocks, ModuleHost, Node, Remote, RxPort, SafetyConfig, SystemStatus, Topic, TxPort};

// ---- tables (robot.toml plan, fingerprint 0x734e658e) ----
const TX: [TxTopic; 1] = [tx(0x0148, Class::Srt, 12, 20000000)];
const RX_TOPICS: [RxTopic; 4] = [rx(0x0140, 24, 0), rx(0x0141, 8, 26), rx(0x0142, 5, 34), rx(0x0143, 32, 39)];
const CALENDAR: [CalEntry; 0] = [];
const MASTER_MASKS: [u64; 4] = [0x1800003ff, 0x18000001f, 0x1800001ff, 0x18000001f];
/// Engine tables of module `gateway` (index 0).
pub const TABLES: NodeTables<'static> = NodeTables { bus: BUS, module: 0, tx: &TX, rx: &RX_TOPICS, calendar: &CALENDAR, master_masks: &MASTER_MASKS };
/// Engine receive topics.
pub const RX: usize = 4;
/// Reassembly arena bytes.
pub const ARENA: usize = 73;
/// Acceptance filters (id, mask), one Mask32 bank each.
pub const FILTERS: &[(u32, u32)] = &[(0x00000000, 0x1fff8000), (0x00008000, 0x007fe000), (0x0000a000, 0x007ffe00)];

// ---- topics: pools = subscribers × queue + subscribers + engine share + 1 loan ----
/// `teleop` (SRT, 20 ms deadline, from the host link to obstacle_avoid).
pub static TELEOP: Topic<Twist, { pool_blocks(0, 2, 3, 1) }, 0, 2> =
    Topic::new(Remote::Srt, Some(crate::driver::kick));
/// `odometry` (received): subscriber 0 = ros_bridge.
pub static ODOMETRY: Topic<Odometry, { pool_blocks(1, 1, 0, 1) }, 1, 1> = Topic::new(Remote::None, None);
/// `proximity` (received): subscriber 0 = ros_bridge (queue 2).
pub static PROXIMITY: Topic<Proximity, { pool_blocks(1, 2, 0, 1) }, 1, 2> = Topic::new(Remote::None, None);
/// `battery` (received): subscriber 0 = ros_bridge.
pub static BATTERY: Topic<Battery, { pool_blocks(1, 1, 0, 1) }, 1, 1> = Topic::new(Remote::None, None);
/// `log` (received): subscriber 0 = ros_bridge (queue 4).
pub static LOG: Topic<LogLine, { pool_blocks(1, 4, 0, 1) }, 1, 4> = Topic::new(Remote::None, None);
/// Engine SRT/NRT queue: `teleop` (2 fragments per message, queue 2).
pub const QUEUE: usize = 4;

static TX_PORTS: [&dyn TxPort; 1] = [&TELEOP];
static RX_PORTS: [&dyn RxPort; 4] = [&ODOMETRY, &PROXIMITY, &BATTERY, &LOG];

/// Node `ros_bridge` (priority 1).
pub static ROS_BRIDGE: Node = Node::new("ros_bridge");
static NODES: [&Node; 1] = [&ROS_BRIDGE];

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
