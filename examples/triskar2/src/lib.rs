//! Code of the six Triskar2 module images (src/bin/*.rs). Every image is the same RTIC 2
//! app (`rtcan_app_stm32f103::module_app!`, shared with the workspaces `rtcan new`
//! writes), invoked by each bin after naming its module, app and hardware: the module's
//! generated engine and topics of `rtcan::robot_toml` (the same statics the simulator
//! runs), driven by the CAN and slot-timer interrupts (`driver`), and one async task that
//! polls the module's app from `triskar2_nodes::app` on the hardware of `io` — the app
//! code the simulator runs, unchanged. This crate adds Triskar2's hardware (`io`) to the
//! shared start-up, driver and app task, re-exported here as the bins' `fw`.
#![no_std]

pub mod io;

pub use rtcan_app_stm32f103::{board, cycles, driver, run, Mono, SYSCLK_HZ};
