//! Module `motor1`: DC motor 1 (node `motor_ctrl1`, 200 Hz PID, publishes `encoder1`)
//! and the inverse kinematics (node `kinematics`, 100 Hz, `velocity` →
//! `wheel_setpoints` for all three motors).
#![no_std]
#![no_main]

use robot::motor1 as module;
use rtcan::robot_toml as robot;
use triskar2_firmware as fw;
type Hw = fw::io::MotorIo;
const NAME: &str = "motor1";

/// The board has working TTCM (STM32F103: yes; see docs/BRINGUP.md).
const STAMPS: rtcan_board_stm32f103::common::Stamps = rtcan_board_stm32f103::common::Stamps::Ttcm;

// The RTIC app robot.toml lays out for this module: a task per node placed here.
triskar2_nodes::motor1_app!();
