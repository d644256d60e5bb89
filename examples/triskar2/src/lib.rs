//! Code of the six Triskar2 module images (src/bin/*.rs). Every image is the same RTIC 2
//! app skeleton (`rtcan_app_stm32f103::module_app!`, shared with the workspaces `rtcan
//! new` writes), laid out for the module by robot.toml (`triskar2_nodes::<module>_app!`,
//! generated) and invoked by each bin after naming its module and hardware: the module's
//! generated engine and topics of `rtcan::robot_toml` (the same statics the simulator
//! runs), driven by the CAN and slot-timer interrupts (`driver`), and one async task per
//! node placed on the module, at its robot.toml priority, polling the node's task from
//! `triskar2_nodes::tasks` on the hardware of `io` (shared through `Locked`) — the node
//! code the simulator runs, unchanged. This crate adds Triskar2's hardware (`io`) to the
//! shared start-up, driver and tasks, re-exported here as the bins' `fw`.
#![no_std]

pub mod io;

pub use io::Locked;
pub use rtcan_app_stm32f103::{board, cycles, driver, run, Mono, SYSCLK_HZ};
