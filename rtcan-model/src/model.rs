//! The validated robot description: what robot.toml says, with names resolved to indices,
//! sizes and slot periods computed, and spans kept for the planner's diagnostics.
use crate::diag::Span;
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::Class;

/// A module's board: fixes the MCU, hence CAN filter banks, flash and RAM.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Board {
    /// STM32F103C8 ("blue pill" class): 64 KiB flash, 20 KiB RAM.
    Stm32f103c8,
    /// STM32F103RB: 128 KiB flash, 20 KiB RAM.
    Stm32f103rb,
    /// STM32F103RE (the RTCAN paper's modules): 512 KiB flash, 64 KiB RAM.
    Stm32f103re,
    /// QEMU lm3s6965evb with the software CAN; filters modelled on the F103.
    Qemu,
}

impl Board {
    /// Every board, in documentation order.
    pub const ALL: [Board; 4] = [
        Board::Stm32f103c8,
        Board::Stm32f103rb,
        Board::Stm32f103re,
        Board::Qemu,
    ];

    /// Name as written in robot.toml.
    pub const fn name(self) -> &'static str {
        match self {
            Board::Stm32f103c8 => "stm32f103c8",
            Board::Stm32f103rb => "stm32f103rb",
            Board::Stm32f103re => "stm32f103re",
            Board::Qemu => "qemu",
        }
    }
    /// Parses a board name.
    pub fn from_name(name: &str) -> Option<Board> {
        Board::ALL.into_iter().find(|b| b.name() == name)
    }
    /// Clock of the CAN controller (APB1 on the F103: 36 MHz with the clock tree of
    /// `boards/stm32f103`, `PCLK1_HZ`), from which the bit timing is derived; `None` for
    /// the QEMU board, whose software CAN runs at any bit rate.
    pub const fn can_clock_hz(self) -> Option<u32> {
        match self {
            Board::Stm32f103c8 | Board::Stm32f103rb | Board::Stm32f103re => Some(36_000_000),
            Board::Qemu => None,
        }
    }
    /// CAN filter banks (the F103 without CAN2 has 14, whatever the HAL's `num_banks()` says).
    pub const fn filter_banks(self) -> u8 {
        14
    }
    /// Flash in bytes.
    pub const fn flash_bytes(self) -> u32 {
        match self {
            Board::Stm32f103c8 => 64 * 1024,
            Board::Stm32f103rb => 128 * 1024,
            Board::Stm32f103re => 512 * 1024,
            Board::Qemu => 256 * 1024,
        }
    }
    /// RAM in bytes.
    pub const fn ram_bytes(self) -> u32 {
        match self {
            Board::Stm32f103c8 | Board::Stm32f103rb => 20 * 1024,
            Board::Stm32f103re | Board::Qemu => 64 * 1024,
        }
    }
}

/// Primitive field types; all little-endian on the wire.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Prim {
    /// u8
    U8,
    /// u16
    U16,
    /// u32
    U32,
    /// u64
    U64,
    /// i8
    I8,
    /// i16
    I16,
    /// i32
    I32,
    /// i64
    I64,
    /// f32
    F32,
    /// f64
    F64,
    /// bool (one byte, 0 or 1)
    Bool,
}

impl Prim {
    /// Every primitive.
    pub const ALL: [Prim; 11] = [
        Prim::U8,
        Prim::U16,
        Prim::U32,
        Prim::U64,
        Prim::I8,
        Prim::I16,
        Prim::I32,
        Prim::I64,
        Prim::F32,
        Prim::F64,
        Prim::Bool,
    ];
    /// Rust name.
    pub const fn name(self) -> &'static str {
        match self {
            Prim::U8 => "u8",
            Prim::U16 => "u16",
            Prim::U32 => "u32",
            Prim::U64 => "u64",
            Prim::I8 => "i8",
            Prim::I16 => "i16",
            Prim::I32 => "i32",
            Prim::I64 => "i64",
            Prim::F32 => "f32",
            Prim::F64 => "f64",
            Prim::Bool => "bool",
        }
    }
    /// Size on the wire in bytes.
    pub const fn size(self) -> usize {
        match self {
            Prim::U8 | Prim::I8 | Prim::Bool => 1,
            Prim::U16 | Prim::I16 => 2,
            Prim::U32 | Prim::I32 | Prim::F32 => 4,
            Prim::U64 | Prim::I64 | Prim::F64 => 8,
        }
    }
    /// Parses a primitive name.
    pub fn from_name(name: &str) -> Option<Prim> {
        Prim::ALL.into_iter().find(|p| p.name() == name)
    }
}

/// A field type: a primitive or a fixed-length array of one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FieldType {
    /// Element type.
    pub prim: Prim,
    /// `Some(n)` for `[prim; n]`.
    pub len: Option<u16>,
}

impl FieldType {
    /// Size in bytes.
    pub const fn size(self) -> usize {
        match self.len {
            Some(n) => self.prim.size() * n as usize,
            None => self.prim.size(),
        }
    }
    /// Rust spelling: `f32`, `[i16; 3]`.
    pub fn rust(self) -> String {
        match self.len {
            Some(n) => format!("[{}; {n}]", self.prim.name()),
            None => self.prim.name().to_string(),
        }
    }
}

/// One field of a message type.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Field {
    /// Name (snake_case).
    pub name: String,
    /// Type.
    pub ty: FieldType,
    /// Byte offset in the payload (fields are packed in declaration order, no padding).
    pub offset: usize,
}

/// A message type (`[types.Name]`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MsgType {
    /// Name (CamelCase).
    pub name: String,
    /// Fields in wire order.
    pub fields: Vec<Field>,
    /// Payload size in bytes.
    pub size: usize,
    /// Where it is declared.
    pub span: Option<Span>,
}

/// How a module's CAN filters are configured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FilterMode {
    /// Hardware filters pass exactly the sync frame, heartbeats and subscribed topics.
    Exact,
    /// One accept-everything bank; the engine's RX table drops the rest (counted).
    AcceptAll,
}

/// A module (`[modules.name]`): one MCU on the bus.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Module {
    /// Name.
    pub name: String,
    /// Board.
    pub board: Board,
    /// Filter configuration.
    pub filters: FilterMode,
    /// Where it is declared.
    pub span: Option<Span>,
}

/// A node (`[nodes.name]`): an R2P task on a module.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Node {
    /// Name.
    pub name: String,
    /// Module index.
    pub module: usize,
    /// Task priority (1 = lowest).
    pub priority: u8,
    /// Where it is declared.
    pub span: Option<Span>,
}

/// A subscription.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Subscriber {
    /// Node index.
    pub node: usize,
    /// Queue length (messages), >= 1.
    pub queue: u16,
    /// Where the subscription is written.
    pub span: Option<Span>,
}

/// Spans of a topic's keys, for planner diagnostics.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TopicSpans {
    /// The `[topics.name]` key.
    pub name: Option<Span>,
    /// The rate/period value (HRT, or SRT/NRT average rate).
    pub timing: Option<Span>,
    /// The deadline value.
    pub deadline: Option<Span>,
}

/// A topic (`[topics.name]`).
#[derive(Clone, Debug, PartialEq)]
pub struct Topic {
    /// Name.
    pub name: String,
    /// Message type index.
    pub ty: usize,
    /// Publishing node index.
    pub publisher: usize,
    /// Class.
    pub class: Class,
    /// HRT: period in slots (rounded from the requested period).
    pub period_slots: Option<u32>,
    /// HRT: the requested period in ns (from rate, period or period_slots).
    pub requested_period_ns: Option<f64>,
    /// SRT: relative deadline in ns.
    pub deadline_ns: Option<u64>,
    /// SRT/NRT: average message rate used for the bus-load check (none = not counted).
    pub rate_hz: Option<f64>,
    /// HRT: how long before each of its slots the publisher runs, ns (`lead`, default
    /// [`crate::validate::DEFAULT_HRT_LEAD_NS`]).
    pub lead_ns: Option<u64>,
    /// Subscribers in file order.
    pub subscribers: Vec<Subscriber>,
    /// Spans.
    pub spans: TopicSpans,
}

/// Spans of `[bus]` keys.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BusSpans {
    /// `[bus]` itself.
    pub table: Option<Span>,
    /// `bitrate` value.
    pub bitrate: Option<Span>,
    /// `slots` value.
    pub slots: Option<Span>,
    /// `cycle` / `cycle_us` value.
    pub cycle: Option<Span>,
}

/// `[bus]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Bus {
    /// Bit rate, bit/s.
    pub bitrate: u32,
    /// Cycle length as written, ns.
    pub cycle_ns: u64,
    /// Slots per cycle (2..=64; slot 0 carries the sync frame).
    pub slots: u8,
    /// Slot length: cycle / slots, rounded down to a whole ns.
    pub slot_ns: u64,
    /// SRT laxity encoding.
    pub laxity: LaxityEncoding,
    /// Guard time per slot, ns.
    pub guard_ns: u64,
    /// Master module index.
    pub master: usize,
    /// Backup masters in takeover order (room in the format; not yet used by the engine).
    pub backup_masters: Vec<usize>,
    /// Relative tolerance of HRT period discretisation.
    pub tolerance: f64,
    /// Worst-case 8-byte frame plus intermission, ns.
    pub worst_frame_ns: u64,
    /// Spans.
    pub spans: BusSpans,
}

/// The validated description.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// Bus parameters.
    pub bus: Bus,
    /// Message types in file order.
    pub types: Vec<MsgType>,
    /// Modules in file order (index = heartbeat offset).
    pub modules: Vec<Module>,
    /// Nodes in file order.
    pub nodes: Vec<Node>,
    /// Topics in file order.
    pub topics: Vec<Topic>,
    /// `[robot]` and the topics' outside-world keys (`rtcan_model::bridge_keys`).
    pub bridge: crate::bridge_keys::BridgeDecl,
    /// `[services]` (rtcan_model::services): their topics and types are appended after
    /// the declared ones.
    pub services: Vec<crate::services::Service>,
    /// `[params]` (rtcan_model::params), in declaration order.
    pub params: Vec<crate::params::ParamDecl>,
    /// A supervised robot's module-state topics (rtcan_model::module_state), appended
    /// after the services' ones.
    pub module_state: Option<crate::module_state::StateTopics>,
}

impl Model {
    /// True for the request and reply topics of a service.
    pub fn is_service_topic(&self, topic: usize) -> bool {
        self.services
            .iter()
            .any(|s| s.request_topic == topic || s.reply_topic == topic)
    }
    /// True for a module-state topic (health or table) of a supervised robot.
    pub fn is_module_state_topic(&self, topic: usize) -> bool {
        self.module_state
            .as_ref()
            .is_some_and(|s| s.contains(topic))
    }
    /// Payload size of a topic.
    pub fn topic_size(&self, topic: &Topic) -> usize {
        self.types.get(topic.ty).map_or(0, |t| t.size)
    }
    /// Module of a node.
    pub fn node_module(&self, node: usize) -> usize {
        self.nodes.get(node).map_or(0, |n| n.module)
    }
    /// True when some subscriber is on another module than the publisher: only those
    /// topics go on the bus (local subscribers share memory, as in R2P), and the module
    /// tables, which only the host reads.
    pub fn on_bus(&self, topic: &Topic) -> bool {
        let pm = self.node_module(topic.publisher);
        topic
            .subscribers
            .iter()
            .any(|s| self.node_module(s.node) != pm)
            || self.is_module_table(topic)
    }
    /// True for a module table topic (`module_state_<m>`): on the bus with no module
    /// subscribing, for the host (rtcan_model::module_state).
    pub fn is_module_table(&self, topic: &Topic) -> bool {
        self.module_state.as_ref().is_some_and(|s| {
            s.tables
                .iter()
                .any(|&(_, t)| self.topics.get(t).is_some_and(|x| x.name == topic.name))
        })
    }
}
