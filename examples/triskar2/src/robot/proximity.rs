//! Module `proximity`: four IR rangers and the obstacle override.
#![allow(clippy::unreadable_literal)]
#[allow(unused_imports)] // not every module has a calendar or receive topics
use super::{cal, rx, tx, BUS, MASTER, MAX_MISSED_CYCLES};
use rtcan_core::id::Class;
use rtcan_core::tables::{CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_core::time::Nanos;
use rtcan_pubsub::{ModuleHost, Node, RxPort, SafetyConfig, SystemStatus, TxPort};

// ---- tables (robot.toml plan, fingerprint 0x734e658e) ----
pub const TX: [TxTopic; 2] = [tx(0x0141, Class::Hrt, 8, 0), tx(0x0146, Class::Srt, 12, 10000000)];
pub const RX: [RxTopic; 1] = [rx(0x0148, 12, 0)];
pub const CALENDAR: [CalEntry; 1] = [cal(9, 0, 0)];
pub const MASTER_MASKS: [u64; 0] = [];
/// Engine tables of module `proximity` (index 4).
pub const TABLES: NodeTables<'static> = NodeTables { bus: BUS, module: 4, tx: &TX, rx: &RX, calendar: &CALENDAR, master_masks: &MASTER_MASKS };
/// Engine receive topics.
pub const RX_COUNT: usize = 1;
/// Reassembly arena bytes.
pub const ARENA_BYTES: usize = 14;
/// Acceptance filters (id, mask), one Mask32 bank each.
pub const FILTERS: &[(u32, u32)] = &[(0x00000000, 0x1fff8000), (0x00008000, 0x007fe000), (0x0000a400, 0x007ffc00)];

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
    pub const TELEOP_POOL: usize = pool_blocks(1, 2, 0, 1);
    /// Topic `teleop`: 1 local subscriber(s), queues of 2, received from the bus.
    pub type TeleopTopic = Topic<Twist, TELEOP_POOL, 1, 2>;
    /// Topic `teleop`.
    pub static TELEOP: TeleopTopic = Topic::new(Remote::None, None);
    /// Pool blocks of `proximity`.
    pub const PROXIMITY_POOL: usize = pool_blocks(1, 1, 2, 1);
    /// Topic `proximity`: 1 local subscriber(s), queues of 1, sent on the bus.
    pub type ProximityTopic = Topic<Proximity, PROXIMITY_POOL, 1, 1>;
    /// Topic `proximity`.
    pub static PROXIMITY: ProximityTopic = Topic::new(Remote::Hrt, None);
    /// Pool blocks of `velocity`.
    pub const VELOCITY_POOL: usize = pool_blocks(0, 2, 3, 1);
    /// Topic `velocity`: 0 local subscriber(s), queues of 2, sent on the bus.
    pub type VelocityTopic = Topic<Twist, VELOCITY_POOL, 0, 2>;
    /// Topic `velocity`.
    pub static VELOCITY: VelocityTopic = Topic::new(Remote::Srt, Some(crate::driver::kick));
}

/// Nodes: lifecycle and typed handles for exactly the topics each declares.
pub mod nodes {
    /// Node `ir_ranger` (priority 2).
    pub mod ir_ranger {
        use super::super::super::types::*;
        use super::super::topics::*;
        #[allow(unused_imports)] // not every node both publishes and subscribes
        use rtcan_pubsub::{Node, Publisher, Subscriber};
        /// Lifecycle (its state goes into the module's heartbeat).
        pub static NODE: Node = Node::new("ir_ranger");
        /// Task priority from robot.toml (1 = lowest).
        pub const PRIORITY: u8 = 2;
        /// Publisher of topic `proximity`.
        pub fn proximity_pub() -> Publisher<'static, Proximity, PROXIMITY_POOL, 1, 1> {
            PROXIMITY.publisher()
        }
    }
    /// Node `obstacle_avoid` (priority 3).
    pub mod obstacle_avoid {
        use super::super::super::types::*;
        use super::super::topics::*;
        #[allow(unused_imports)] // not every node both publishes and subscribes
        use rtcan_pubsub::{Node, Publisher, Subscriber};
        /// Lifecycle (its state goes into the module's heartbeat).
        pub static NODE: Node = Node::new("obstacle_avoid");
        /// Task priority from robot.toml (1 = lowest).
        pub const PRIORITY: u8 = 3;
        /// Publisher of topic `velocity`.
        pub fn velocity_pub() -> Publisher<'static, Twist, VELOCITY_POOL, 0, 2> {
            VELOCITY.publisher()
        }
        /// Subscription to topic `teleop`.
        pub fn teleop_sub() -> Subscriber<'static, Twist, TELEOP_POOL, 1, 2> {
            TELEOP.subscriber::<0>()
        }
        /// Subscription to topic `proximity`.
        pub fn proximity_sub() -> Subscriber<'static, Proximity, PROXIMITY_POOL, 1, 1> {
            PROXIMITY.subscriber::<0>()
        }
    }
}

static TX_PORTS: [&dyn TxPort; 2] = [&topics::PROXIMITY, &topics::VELOCITY];
static RX_PORTS: [&dyn RxPort; 1] = [&topics::TELEOP];
static NODES: [&Node; 2] = [&nodes::ir_ranger::NODE, &nodes::obstacle_avoid::NODE];

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
