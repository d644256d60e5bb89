//! Board-independent pieces of the RTCAN drivers, kept free of any HAL so they run (and
//! are tested) on the host, under QEMU and on the STM32F103 alike:
//! CAN bit timing from the clock tree (`bit_timing`), acceptance filter sets
//! (`filters`), a 16-bit hardware timer extended to a 64-bit clock (`wide_clock`),
//! bxCAN time-triggered-mode SOF timestamps mapped to the local clock (`sof`), and the
//! split interrupt architecture both boards run: prepared slot plans committed by the
//! slot timer (`slot_plan`, `tx_image`) and the protocol task around the engine
//! (`protocol`), and critical sections that leave the interrupts above the protocol
//! task's priority unblocked (`ceiling`).
#![cfg_attr(not(test), no_std)]
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::indexing_slicing,
        clippy::panic
    )
)]

pub mod bit_timing;
pub mod ceiling;
pub mod filters;
pub mod protocol;
pub mod slot_plan;
pub mod sof;
pub mod tx_image;
pub mod wide_clock;

pub use bit_timing::{BitTiming, BitTimingError};
pub use filters::FilterSet;
pub use protocol::{
    Alarm, AlarmSetting, Direct, Lock, Protocol, RxEvent, SlotCore, SlotTimerHw, Stamps, TxEvent,
};
pub use slot_plan::SlotPlan;
pub use sof::SofClock;
pub use tx_image::{TxImage, TxPort};
pub use wide_clock::WideClock;
