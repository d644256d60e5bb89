//! Module `psu`: power supply.
#![allow(clippy::unreadable_literal)]
#[allow(unused_imports)] // not every module has a calendar or receive topics
use super::{cal, rx, tx, BUS, MASTER, MAX_MISSED_CYCLES};
use rtcan_core::id::Class;
use rtcan_core::tables::{CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_core::time::Nanos;
use rtcan_pubsub::{ModuleHost, Node, RxPort, SafetyConfig, SystemStatus, TxPort};

// ---- tables (robot.toml plan, fingerprint 0x734e658e) ----
pub const TX: [TxTopic; 2] = [tx(0x0142, Class::Nrt, 5, 0), tx(0x0143, Class::Nrt, 32, 0)];
pub const RX: [RxTopic; 0] = [];
pub const CALENDAR: [CalEntry; 0] = [];
pub const MASTER_MASKS: [u64; 0] = [];
/// Engine tables of module `psu` (index 5).
pub const TABLES: NodeTables<'static> = NodeTables { bus: BUS, module: 5, tx: &TX, rx: &RX, calendar: &CALENDAR, master_masks: &MASTER_MASKS };
/// Engine receive topics.
pub const RX_COUNT: usize = 0;
/// Reassembly arena bytes.
pub const ARENA_BYTES: usize = 0;
/// Acceptance filters (id, mask), one Mask32 bank each.
pub const FILTERS: &[(u32, u32)] = &[(0x00000000, 0x1fff8000), (0x00008000, 0x007fe000)];

/// Engine SRT/NRT queue capacity.
pub const QUEUE_CAPACITY: usize = 5;
/// This module's engine type.
pub type Engine<'t> = rtcan_core::engine::Engine<'t, RX_COUNT, ARENA_BYTES, QUEUE_CAPACITY>;
/// The engine, started at local time `now`.
pub fn engine(now: Nanos) -> Engine<'static> {
    Engine::new(TABLES, now)
}

/// Topic statics: pools = subscribers × queue + subscribers + engine share + 1 loan.
pub mod topics {
    use super::super::types::*;
    use rtcan_pubsub::{pool_blocks, Remote, Topic};
    /// Pool blocks of `battery`.
    pub const BATTERY_POOL: usize = pool_blocks(0, 1, 2, 1);
    /// Topic `battery`: 0 local subscriber(s), queues of 1, sent on the bus.
    pub type BatteryTopic = Topic<Battery, BATTERY_POOL, 0, 1>;
    /// Topic `battery`.
    pub static BATTERY: BatteryTopic = Topic::new(Remote::Nrt, Some(crate::driver::kick));
    /// Pool blocks of `log`.
    pub const LOG_POOL: usize = pool_blocks(0, 4, 5, 1);
    /// Topic `log`: 0 local subscriber(s), queues of 4, sent on the bus.
    pub type LogTopic = Topic<LogLine, LOG_POOL, 0, 4>;
    /// Topic `log`.
    pub static LOG: LogTopic = Topic::new(Remote::Nrt, Some(crate::driver::kick));
}

/// Nodes: lifecycle and typed handles for exactly the topics each declares.
pub mod nodes {
    /// Node `battery_monitor` (priority 1).
    pub mod battery_monitor {
        use super::super::super::types::*;
        use super::super::topics::*;
        #[allow(unused_imports)] // not every node both publishes and subscribes
        use rtcan_pubsub::{Node, Publisher, Subscriber};
        /// Lifecycle (its state goes into the module's heartbeat).
        pub static NODE: Node = Node::new("battery_monitor");
        /// Task priority from robot.toml (1 = lowest).
        pub const PRIORITY: u8 = 1;
        /// Publisher of topic `battery`.
        pub fn battery_pub() -> Publisher<'static, Battery, BATTERY_POOL, 0, 1> {
            BATTERY.publisher()
        }
        /// Publisher of topic `log`.
        pub fn log_pub() -> Publisher<'static, LogLine, LOG_POOL, 0, 4> {
            LOG.publisher()
        }
    }
}

static TX_PORTS: [&dyn TxPort; 2] = [&topics::BATTERY, &topics::LOG];
static RX_PORTS: [&dyn RxPort; 0] = [];
static NODES: [&Node; 1] = [&nodes::battery_monitor::NODE];

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
