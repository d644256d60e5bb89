//! The robot from a PC: from the same robot.toml (one `rtcan_model::Plan`, the topics'
//! field layouts of `rtcan_sim::decode::plan_catalog`) JSON access to every topic, and a
//! [`Link`] trait with the ways to reach a bus: the simulated robot in-process
//! ([`sim::SimLink`], paced to the wall clock or not), candump logs
//! ([`replay::ReplayLink`]), the gateway's serial link ([`serial::SerialLink`]) and a CAN
//! adapter ([`can::CanLink`] over a [`can::FramePort`]: SocketCAN with the `socketcan`
//! feature on Linux, a candump log in tests). The `rtcan` commands `echo`, `pub`, `record` and `monitor`
//! are thin layers over this crate.
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::indexing_slicing,
        clippy::panic
    )
)]

pub mod can;
pub mod dbc;
pub mod gateway;
pub mod link;
pub mod monitor;
pub mod replay;
pub mod serial;
pub mod sim;
pub mod value;

pub use link::{open, Link, Source, Stamped};
