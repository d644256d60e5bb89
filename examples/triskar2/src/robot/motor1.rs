//! Module `motor1`: DC motor 1 and the inverse kinematics.
#![allow(clippy::unreadable_literal)]
#[allow(unused_imports)] // not every module has a calendar or receive topics
use super::{cal, rx, tx, BUS, MASTER, MAX_MISSED_CYCLES};
use rtcan_core::id::Class;
use rtcan_core::tables::{CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_core::time::Nanos;
use rtcan_pubsub::{ModuleHost, Node, RxPort, SafetyConfig, SystemStatus, TxPort};

// ---- tables (robot.toml plan, fingerprint 0x734e658e) ----
pub const TX: [TxTopic; 2] = [tx(0x0144, Class::Hrt, 8, 0), tx(0x0147, Class::Hrt, 12, 0)];
pub const RX: [RxTopic; 1] = [rx(0x0146, 12, 0)];
pub const CALENDAR: [CalEntry; 16] = [cal(1, 0, 0), cal(3, 1, 1), cal(4, 1, 0), cal(31, 0, 0), cal(61, 0, 0), cal(63, 1, 1), cal(64, 1, 0), cal(91, 0, 0), cal(121, 0, 0), cal(123, 1, 1), cal(124, 1, 0), cal(151, 0, 0), cal(181, 0, 0), cal(183, 1, 1), cal(184, 1, 0), cal(211, 0, 0)];
pub const MASTER_MASKS: [u64; 0] = [];
/// Engine tables of module `motor1` (index 1).
pub const TABLES: NodeTables<'static> = NodeTables { bus: BUS, module: 1, tx: &TX, rx: &RX, calendar: &CALENDAR, master_masks: &MASTER_MASKS };
/// Engine receive topics.
pub const RX_COUNT: usize = 1;
/// Reassembly arena bytes.
pub const ARENA_BYTES: usize = 14;
/// Acceptance filters (id, mask), one Mask32 bank each.
pub const FILTERS: &[(u32, u32)] = &[(0x00000000, 0x1fff8000), (0x00008000, 0x007fe000), (0x0000a300, 0x007fff80)];

/// Engine SRT/NRT queue capacity.
pub const QUEUE_CAPACITY: usize = 1;
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
    /// Pool blocks of `velocity`.
    pub const VELOCITY_POOL: usize = pool_blocks(1, 1, 0, 1);
    /// Topic `velocity`: 1 local subscriber(s), queues of 1, received from the bus.
    pub type VelocityTopic = Topic<Twist, VELOCITY_POOL, 1, 1>;
    /// Topic `velocity`.
    pub static VELOCITY: VelocityTopic = Topic::new(Remote::None, None);
    /// Pool blocks of `wheel_setpoints`.
    pub const WHEEL_SETPOINTS_POOL: usize = pool_blocks(1, 1, 2, 1);
    /// Topic `wheel_setpoints`: 1 local subscriber(s), queues of 1, sent on the bus.
    pub type WheelSetpointsTopic = Topic<WheelSpeeds, WHEEL_SETPOINTS_POOL, 1, 1>;
    /// Topic `wheel_setpoints`.
    pub static WHEEL_SETPOINTS: WheelSetpointsTopic = Topic::new(Remote::Hrt, None);
    /// Pool blocks of `encoder1`.
    pub const ENCODER1_POOL: usize = pool_blocks(0, 1, 2, 1);
    /// Topic `encoder1`: 0 local subscriber(s), queues of 1, sent on the bus.
    pub type Encoder1Topic = Topic<Encoder, ENCODER1_POOL, 0, 1>;
    /// Topic `encoder1`.
    pub static ENCODER1: Encoder1Topic = Topic::new(Remote::Hrt, None);
}

/// Nodes: lifecycle and typed handles for exactly the topics each declares.
pub mod nodes {
    /// Node `kinematics` (priority 2).
    pub mod kinematics {
        use super::super::super::types::*;
        use super::super::topics::*;
        #[allow(unused_imports)] // not every node both publishes and subscribes
        use rtcan_pubsub::{Node, Publisher, Subscriber};
        /// Lifecycle (its state goes into the module's heartbeat).
        pub static NODE: Node = Node::new("kinematics");
        /// Task priority from robot.toml (1 = lowest).
        pub const PRIORITY: u8 = 2;
        /// Publisher of topic `wheel_setpoints`.
        pub fn wheel_setpoints_pub() -> Publisher<'static, WheelSpeeds, WHEEL_SETPOINTS_POOL, 1, 1> {
            WHEEL_SETPOINTS.publisher()
        }
        /// Subscription to topic `velocity`.
        pub fn velocity_sub() -> Subscriber<'static, Twist, VELOCITY_POOL, 1, 1> {
            VELOCITY.subscriber::<0>()
        }
    }
    /// Node `motor_ctrl1` (priority 3).
    pub mod motor_ctrl1 {
        use super::super::super::types::*;
        use super::super::topics::*;
        #[allow(unused_imports)] // not every node both publishes and subscribes
        use rtcan_pubsub::{Node, Publisher, Subscriber};
        /// Lifecycle (its state goes into the module's heartbeat).
        pub static NODE: Node = Node::new("motor_ctrl1");
        /// Task priority from robot.toml (1 = lowest).
        pub const PRIORITY: u8 = 3;
        /// Publisher of topic `encoder1`.
        pub fn encoder1_pub() -> Publisher<'static, Encoder, ENCODER1_POOL, 0, 1> {
            ENCODER1.publisher()
        }
        /// Subscription to topic `wheel_setpoints`.
        pub fn wheel_setpoints_sub() -> Subscriber<'static, WheelSpeeds, WHEEL_SETPOINTS_POOL, 1, 1> {
            WHEEL_SETPOINTS.subscriber::<0>()
        }
    }
}

static TX_PORTS: [&dyn TxPort; 2] = [&topics::ENCODER1, &topics::WHEEL_SETPOINTS];
static RX_PORTS: [&dyn RxPort; 1] = [&topics::VELOCITY];
static NODES: [&Node; 2] = [&nodes::kinematics::NODE, &nodes::motor_ctrl1::NODE];

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
