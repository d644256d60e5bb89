//! Module `gateway`: host link and bus master.
#![allow(clippy::unreadable_literal)]
#[allow(unused_imports)] // not every module has a calendar or receive topics
use super::{cal, rx, tx, BUS, MASTER, MAX_MISSED_CYCLES};
use rtcan_core::id::Class;
use rtcan_core::tables::{CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_core::time::Nanos;
use rtcan_pubsub::{ModuleHost, Node, RxPort, SafetyConfig, SystemStatus, TxPort};

// ---- tables (robot.toml plan, fingerprint 0x734e658e) ----
pub const TX: [TxTopic; 1] = [tx(0x0148, Class::Srt, 12, 20000000)];
pub const RX: [RxTopic; 4] = [rx(0x0140, 24, 0), rx(0x0141, 8, 26), rx(0x0142, 5, 34), rx(0x0143, 32, 39)];
pub const CALENDAR: [CalEntry; 0] = [];
pub const MASTER_MASKS: [u64; 4] = [0x1800003ff, 0x18000001f, 0x1800001ff, 0x18000001f];
/// Engine tables of module `gateway` (index 0).
pub const TABLES: NodeTables<'static> = NodeTables { bus: BUS, module: 0, tx: &TX, rx: &RX, calendar: &CALENDAR, master_masks: &MASTER_MASKS };
/// Engine receive topics.
pub const RX_COUNT: usize = 4;
/// Reassembly arena bytes.
pub const ARENA_BYTES: usize = 73;
/// Acceptance filters (id, mask), one Mask32 bank each.
pub const FILTERS: &[(u32, u32)] = &[(0x00000000, 0x1fff8000), (0x00008000, 0x007fe000), (0x0000a000, 0x007ffe00)];

/// Engine SRT/NRT queue capacity.
pub const QUEUE_CAPACITY: usize = 4;
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
    /// Pool blocks of `teleop`.
    pub const TELEOP_POOL: usize = pool_blocks(0, 2, 3, 1);
    /// Topic `teleop`: 0 local subscriber(s), queues of 2, sent on the bus.
    pub type TeleopTopic = Topic<Twist, TELEOP_POOL, 0, 2>;
    /// Topic `teleop`.
    pub static TELEOP: TeleopTopic = Topic::new(Remote::Srt, Some(crate::driver::kick));
    /// Pool blocks of `odometry`.
    pub const ODOMETRY_POOL: usize = pool_blocks(1, 1, 0, 1);
    /// Topic `odometry`: 1 local subscriber(s), queues of 1, received from the bus.
    pub type OdometryTopic = Topic<Odometry, ODOMETRY_POOL, 1, 1>;
    /// Topic `odometry`.
    pub static ODOMETRY: OdometryTopic = Topic::new(Remote::None, None);
    /// Pool blocks of `proximity`.
    pub const PROXIMITY_POOL: usize = pool_blocks(1, 2, 0, 1);
    /// Topic `proximity`: 1 local subscriber(s), queues of 2, received from the bus.
    pub type ProximityTopic = Topic<Proximity, PROXIMITY_POOL, 1, 2>;
    /// Topic `proximity`.
    pub static PROXIMITY: ProximityTopic = Topic::new(Remote::None, None);
    /// Pool blocks of `battery`.
    pub const BATTERY_POOL: usize = pool_blocks(1, 1, 0, 1);
    /// Topic `battery`: 1 local subscriber(s), queues of 1, received from the bus.
    pub type BatteryTopic = Topic<Battery, BATTERY_POOL, 1, 1>;
    /// Topic `battery`.
    pub static BATTERY: BatteryTopic = Topic::new(Remote::None, None);
    /// Pool blocks of `log`.
    pub const LOG_POOL: usize = pool_blocks(1, 4, 0, 1);
    /// Topic `log`: 1 local subscriber(s), queues of 4, received from the bus.
    pub type LogTopic = Topic<LogLine, LOG_POOL, 1, 4>;
    /// Topic `log`.
    pub static LOG: LogTopic = Topic::new(Remote::None, None);
}

/// Nodes: lifecycle and typed handles for exactly the topics each declares.
pub mod nodes {
    /// Node `ros_bridge` (priority 1).
    pub mod ros_bridge {
        use super::super::super::types::*;
        use super::super::topics::*;
        #[allow(unused_imports)] // not every node both publishes and subscribes
        use rtcan_pubsub::{Node, Publisher, Subscriber};
        /// Lifecycle (its state goes into the module's heartbeat).
        pub static NODE: Node = Node::new("ros_bridge");
        /// Task priority from robot.toml (1 = lowest).
        pub const PRIORITY: u8 = 1;
        /// Publisher of topic `teleop`.
        pub fn teleop_pub() -> Publisher<'static, Twist, TELEOP_POOL, 0, 2> {
            TELEOP.publisher()
        }
        /// Subscription to topic `odometry`.
        pub fn odometry_sub() -> Subscriber<'static, Odometry, ODOMETRY_POOL, 1, 1> {
            ODOMETRY.subscriber::<0>()
        }
        /// Subscription to topic `proximity`.
        pub fn proximity_sub() -> Subscriber<'static, Proximity, PROXIMITY_POOL, 1, 2> {
            PROXIMITY.subscriber::<0>()
        }
        /// Subscription to topic `battery`.
        pub fn battery_sub() -> Subscriber<'static, Battery, BATTERY_POOL, 1, 1> {
            BATTERY.subscriber::<0>()
        }
        /// Subscription to topic `log`.
        pub fn log_sub() -> Subscriber<'static, LogLine, LOG_POOL, 1, 4> {
            LOG.subscriber::<0>()
        }
    }
}

static TX_PORTS: [&dyn TxPort; 1] = [&topics::TELEOP];
static RX_PORTS: [&dyn RxPort; 4] = [&topics::ODOMETRY, &topics::PROXIMITY, &topics::BATTERY, &topics::LOG];
static NODES: [&Node; 1] = [&nodes::ros_bridge::NODE];

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
