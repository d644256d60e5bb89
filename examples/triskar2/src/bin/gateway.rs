//! Module `gateway`: the bus master and the host link (node `ros_bridge`: the host's
//! velocity command → `teleop` at 20 Hz; `odometry`, `proximity`, `battery`, `log` →
//! host). Link: USART1 115 200 Bd via a USB-serial adapter (`fw::io::GatewayIo`).
#![no_std]
#![no_main]

use robot::gateway as module;
use rtcan::robot_toml as robot;
use triskar2_firmware as fw;
type Hw = fw::io::GatewayIo;
const NAME: &str = "gateway";

/// The board has working TTCM (STM32F103: yes; see docs/BRINGUP.md).
const STAMPS: rtcan_board_stm32f103::common::Stamps = rtcan_board_stm32f103::common::Stamps::Ttcm;

// The RTIC app robot.toml lays out for this module: a task per node placed here.
triskar2_nodes::gateway_app!();
