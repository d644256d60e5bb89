//! Module `proximity`: four Sharp IR rangers (node `ir_ranger`, 25 Hz, publishes
//! `proximity`) and the obstacle override (node `obstacle_avoid`, on every `teleop`
//! and `proximity` message: the command limited by the ranges → `velocity`).
#![no_std]
#![no_main]

use robot::proximity as module;
use rtcan::robot_toml as robot;
use triskar2_firmware as fw;
type Hw = fw::io::RangerIo;
const NAME: &str = "proximity";

/// The board has working TTCM (STM32F103: yes; see docs/BRINGUP.md).
const STAMPS: rtcan_board_stm32f103::common::Stamps = rtcan_board_stm32f103::common::Stamps::Ttcm;

// The RTIC app robot.toml lays out for this module: a task per node placed here.
triskar2_nodes::proximity_app!();
