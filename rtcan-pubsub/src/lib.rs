//! R2P publish/subscribe middleware over RTCAN: typed topics with compile-time pools,
//! zero-copy local delivery, the remote side as `rtcan_core::Host`, real-time
//! publisher classes, node lifecycle and the safe-state rule. `no_std`, no allocation;
//! shared state is guarded by `critical_section` (sound under RTIC priorities: ISR
//! producers, task consumers). See README.md for the memory layout and the glue pattern.
#![cfg_attr(not(test), no_std)]
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::indexing_slicing,
        clippy::panic
    )
)]

pub mod bench;
pub mod flash;
mod handle;
pub mod message;
pub mod node;
pub mod param;
pub mod param_store;
pub mod port;
mod publisher;
mod ring;
pub mod service;
pub mod slot_grid;
pub mod status;
mod subscriber;
pub mod supervision;
pub mod topic;

pub use handle::{Loan, Msg};
pub use message::{Message, WireBuf};
pub use node::{module_state, Node, NodeState};
pub use port::{ModuleHost, RxPort, TxPort};
pub use publisher::{AllocWait, PoolExhausted, PublishWait, Publisher, SendError, WouldBlock};
pub use slot_grid::{HrtSlots, SlotEvery, SlotGrid};
pub use status::{SafeReason, SafetyConfig, Supervised, SystemStatus};
pub use subscriber::{Recv, Subscriber};
pub use supervision::{
    EngineHealth, ModuleRow, ModuleRule, ModuleTable, OnMissing, Publish, Supervisor,
};
pub use topic::{pool_blocks, RecvError, Remote, Topic, TopicCells, TopicStats};
