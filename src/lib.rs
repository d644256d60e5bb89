#![no_std]
//! `rtcan`: the facade crate users depend on.
pub use rtcan_core as core;
