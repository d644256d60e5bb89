//! RTCAN protocol engine.
//!
//! `no_std`, no allocation, no HAL and no global state: time and I/O are passed in
//! (`Engine::poll(now, controller, host)`, smoltcp style), so the same code runs on an
//! STM32 under RTIC, on a Cortex-M3 under QEMU and in the host simulator.
//! The normative wire format is `docs/PROTOCOL.md`.
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

pub mod admission;
pub mod arbiter;
pub mod bit_timing;
pub mod calendar;
pub mod clock;
pub mod confinement;
pub mod counters;
pub mod driver;
pub mod engine;
pub mod fragment;
pub mod frame;
pub mod heartbeat;
pub mod id;
pub mod laxity;
pub mod queue;
pub mod service;
pub mod sync;
pub mod tables;
pub mod time;
pub mod timing;

pub use driver::{Controller, Host, Mailbox, TxOutcome};
pub use engine::Engine;
pub use frame::Frame;
pub use id::{CanId, Class, MsgId};
pub use tables::{BusConfig, CalEntry, NodeTables, RxTopic, TxTopic};
pub use time::Nanos;
