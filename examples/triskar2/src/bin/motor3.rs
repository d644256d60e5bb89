//! Module `motor3`: DC motor 3 (node `motor_ctrl3`, 200 Hz PID, publishes `encoder3`).
#![no_std]
#![no_main]

use robot::motor3 as module;
use rtcan::robot_toml as robot;
use triskar2_firmware as fw;
type Hw = fw::io::MotorIo;
const NAME: &str = "motor3";

/// The board has working TTCM (STM32F103: yes; see docs/BRINGUP.md).
const STAMPS: rtcan_board_stm32f103::common::Stamps = rtcan_board_stm32f103::common::Stamps::Ttcm;

// The RTIC app robot.toml lays out for this module: a task per node placed here.
triskar2_nodes::motor3_app!();
