//! Topic constants of a generated robot.
use crate::core::{Class, MsgId, Nanos};

/// Everything the plan fixed about one topic (`robot::topics::NAME`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TopicInfo {
    /// Name in robot.toml.
    pub name: &'static str,
    /// Message ID on the wire (`ID[22:7]`).
    pub msg_id: MsgId,
    /// Traffic class.
    pub class: Class,
    /// Payload bytes.
    pub size: u16,
    /// Frames per message.
    pub fragments: u8,
    /// Sent on the bus (some subscriber is on another module than the publisher).
    pub on_bus: bool,
    /// Index of the publishing module.
    pub module: u8,
    /// HRT: period in slots.
    pub period_slots: Option<u32>,
    /// HRT on the bus: first reserved slot, counted from slot 0 of cycle 0.
    pub phase_slot: Option<u32>,
    /// SRT: relative deadline, ns.
    pub deadline_ns: Option<Nanos>,
}
