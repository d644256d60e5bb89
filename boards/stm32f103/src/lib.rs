//! RTCAN driver for the STM32F103 (Cortex-M3, bxCAN), in the split interrupt
//! architecture of `rtcan_board_common::protocol`: the CAN parts per interrupt (`can`),
//! the slot timer and local clock on TIM2 (`slot_timer`) and the slot-timer interrupt
//! body (`glue`), and the critical sections at the protocol task's priority (`ceiling`). Meant to be driven from RTIC hardware tasks; nothing here is global,
//! every peripheral is owned by a value.
//!
//! Clock tree assumed by the constants: HSE 8 MHz, SYSCLK 72 MHz, PCLK1 36 MHz (the CAN
//! clock), TIM2 clock 72 MHz.
#![no_std]

pub mod can;
pub mod ceiling;
pub mod glue;
pub mod slot_timer;

pub use can::{
    configure, CanParts, CanRx, CanSce, CanStats, CanTx, CanTxIrq, EnableTimeout, ErrorChange,
};
pub use rtcan_board_common as common;
pub use rtcan_board_common::{can_btr, filter_set, FilterSet};
pub use slot_timer::SlotTimer;
pub use stm32f1xx_hal as hal;

/// APB1 clock feeding bxCAN, Hz.
pub const PCLK1_HZ: u32 = 36_000_000;
/// TIM2 input clock (APB1 x 2 because the APB1 prescaler is not 1), Hz.
pub const TIM2_CLOCK_HZ: u32 = 72_000_000;
/// Filter banks of the F103's bxCAN.
pub const FILTER_BANKS: usize = rtcan_board_common::filters::STM32F103_FILTER_BANKS;
