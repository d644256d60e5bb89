//! Board-independent pieces of the RTCAN drivers, kept free of any HAL so they run (and
//! are tested) on the host, under QEMU and on the STM32F103 alike:
//! CAN bit timing from the clock tree (`bit_timing`), acceptance filter sets
//! (`filters`), a 16-bit hardware timer extended to a 64-bit clock (`wide_clock`) and
//! bxCAN time-triggered-mode SOF timestamps mapped to the local clock (`sof`).
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
pub mod filters;
pub mod sof;
pub mod wide_clock;

pub use bit_timing::{BitTiming, BitTimingError};
pub use filters::FilterSet;
pub use sof::SofClock;
pub use wide_clock::WideClock;
