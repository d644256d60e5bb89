//! Module `psu`: the battery monitor (node `battery_monitor`, 10 Hz sampling,
//! publishes `battery` at 1 Hz and a `log` line at 2 Hz, both NRT).
#![no_std]
#![no_main]

use robot::psu as module;
use rtcan::robot_toml as robot;
use triskar2_firmware as fw;
type Hw = fw::io::PsuIo;
const NAME: &str = "psu";

/// The board has working TTCM (STM32F103: yes; see docs/BRINGUP.md).
const STAMPS: rtcan_board_stm32f103::common::Stamps = rtcan_board_stm32f103::common::Stamps::Ttcm;

// The RTIC app robot.toml lays out for this module: a task per node placed here.
triskar2_nodes::psu_app!();
