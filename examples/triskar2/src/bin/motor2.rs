//! Module `motor2`: DC motor 2 (node `motor_ctrl2`, 200 Hz PID, publishes the local
//! topic `encoder2`) and the odometry (node `odometry`, 50 Hz, `encoder1..3` →
//! `odometry` for the gateway).
#![no_std]
#![no_main]

use robot::motor2 as module;
use rtcan::robot_toml as robot;
use triskar2_firmware as fw;
type Hw = fw::io::MotorIo;
const NAME: &str = "motor2";

/// The board has working TTCM (STM32F103: yes; see docs/BRINGUP.md).
const STAMPS: rtcan_board_stm32f103::common::Stamps = rtcan_board_stm32f103::common::Stamps::Ttcm;

// The RTIC app robot.toml lays out for this module: a task per node placed here.
triskar2_nodes::motor2_app!();
