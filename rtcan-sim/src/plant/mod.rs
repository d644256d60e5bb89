//! Plant models for the Triskar2 robot (std, f64): what the simulated modules' sensors
//! read and their actuators drive. Each model is a plain struct stepped with an explicit
//! `dt`; nothing here knows about the bus, so a closed loop can run with or without it.
//!
//! This module uses only `std`: the node crate's closed-loop test compiles these files
//! directly (`#[path]`) to run the real node code against the same plants as the
//! simulator, without a dependency cycle between the two crates.
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::indexing_slicing,
        clippy::panic
    )
)]

pub mod battery;
pub mod motor;
pub mod noise;
pub mod omni;
pub mod ranger;
pub mod world;

pub use battery::{BatteryPack, BatteryParams};
pub use motor::{DcMotor, DcMotorParams};
pub use noise::NoiseSource;
pub use omni::{OmniBase, OmniGeometry, Pose2, Twist2};
pub use ranger::{IrRanger, RangerArray, RangerMount};
pub use world::{Segment, World};
