//! Module `psu`: power supply (node `battery_monitor`).
#![allow(clippy::unreadable_literal)]
use super::types::*;
use super::{cal, rx, tx, BUS, MASTER, MAX_MISSED_CYCLES};
use rtcan_core::id::Class;
use rtcan_core::tables::{CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_pubsub::{pool_blocks, ModuleHost, Node, Remote, RxPort, SafetyConfig, SystemStatus, Topic, TxPort};

// ---- tables (robot.toml plan, fingerprint 0x734e658e) ----
const TX: [TxTopic; 2] = [tx(0x0142, Class::Nrt, 5, 0), tx(0x0143, Class::Nrt, 32, 0)];
const RX_TOPICS: [RxTopic; 0] = [];
const CALENDAR: [CalEntry; 0] = [];
const MASTER_MASKS: [u64; 0] = [];
/// Engine tables of module `psu` (index 5).
pub const TABLES: NodeTables<'static> = NodeTables { bus: BUS, module: 5, tx: &TX, rx: &RX_TOPICS, calendar: &CALENDAR, master_masks: &MASTER_MASKS };
/// Engine receive topics.
pub const RX: usize = 0;
/// Reassembly arena bytes.
pub const ARENA: usize = 0;
/// Acceptance filters (id, mask), one Mask32 bank each.
pub const FILTERS: &[(u32, u32)] = &[(0x00000000, 0x1fff8000), (0x00008000, 0x007fe000)];

// ---- topics: pools = subscribers × queue + subscribers + engine share + 1 loan ----
/// `battery` (NRT, 1 Hz, to the gateway).
pub static BATTERY: Topic<Battery, { pool_blocks(0, 1, 2, 1) }, 0, 1> =
    Topic::new(Remote::Nrt, Some(crate::driver::kick));
/// `log` (NRT, queue 4, to the gateway).
pub static LOG: Topic<LogLine, { pool_blocks(0, 4, 5, 1) }, 0, 4> =
    Topic::new(Remote::Nrt, Some(crate::driver::kick));
/// Engine SRT/NRT queue: both NRT topics.
pub const QUEUE: usize = 5;

static TX_PORTS: [&dyn TxPort; 2] = [&BATTERY, &LOG];
static RX_PORTS: [&dyn RxPort; 0] = [];

/// Node `battery_monitor` (priority 1).
pub static BATTERY_MONITOR: Node = Node::new("battery_monitor");
static NODES: [&Node; 1] = [&BATTERY_MONITOR];

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
