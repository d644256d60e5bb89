//! Deterministic discrete-event simulator of robots on a CAN bus: every simulated module
//! runs the same `rtcan_core::Engine` (and middleware) as its firmware, through the
//! same driver boundary (`rtcan_core::Controller`), on a bit-accurate bus.
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::indexing_slicing,
        clippy::panic
    )
)]

pub mod apps;
pub mod bus;
pub mod campaign;
pub mod candump;
pub mod chains;
pub mod clock;
pub mod compare;
pub mod confinement;
pub mod controller;
pub mod cpu;
pub mod cpu_compare;
pub mod decimate;
pub mod decode;
pub mod fault;
pub mod fixed;
pub mod guardian;
pub mod histogram;
pub mod ideal;
pub mod live;
pub mod metrics;
pub mod paper;
pub mod param;
pub mod plant;
pub mod plot;
pub mod policy;
pub mod report;
pub mod rng;
pub mod robot;
pub mod rta;
pub mod run;
pub mod sample_age;
pub mod session;
pub mod slots;
pub mod sync_watch;
pub mod tables;
pub mod traffic;
pub mod triskar;
pub mod update;

pub use bus::{Bus, Module, NodeSetup, WireFrame};
pub use clock::NodeClock;
pub use controller::{Filter, SimController};
