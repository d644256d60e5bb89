//! The QEMU machine's `critical_section` implementation: the STM32F103's (BASEPRI at the
//! protocol task's priority, boards/common `ceiling`, boards/stm32f103 `ceiling`) on the
//! lm3s6965's 3 priority bits, so the benchmarks time the firmware's critical sections and
//! `src/bin/ceiling.rs` tests the mechanism on a Cortex-M3 with real interrupts.
use core::sync::atomic::{AtomicBool, Ordering};

use rtcan_board_common::ceiling::{basepri_of, enter, leave};

/// The protocol task's RTIC priority on this 8-level NVIC (the ceiling; the STM32F103
/// images use 13 of 16 levels, same shape: node tasks below, CAN and slot timer above).
pub const PROTOCOL_PRIORITY: u8 = 2;
/// Priority bits the lm3s6965's NVIC implements.
pub const NVIC_PRIO_BITS: u8 = 3;
/// The ceiling as a BASEPRI value (0xC0 on 3 bits).
pub const CEILING: u8 = basepri_of(PROTOCOL_PRIORITY, NVIC_PRIO_BITS);

/// Set by a test that provokes a violation on purpose: the panic handler then ends the
/// run as passed instead of failed.
pub static VIOLATION_EXPECTED: AtomicBool = AtomicBool::new(false);
/// Set when the check refused a section: the panic handler must not print then
/// (semihosting's output takes a critical section, which would be refused again).
pub static VIOLATED: AtomicBool = AtomicBool::new(false);

struct Ceiling;
critical_section::set_impl!(Ceiling);

// SAFETY: as the STM32F103's (boards/stm32f103 `ceiling`): every user runs at or below
// CEILING (checked by `enter`); `release` gets its `acquire`'s value.
unsafe impl critical_section::Impl for Ceiling {
    unsafe fn acquire() -> u32 {
        enter(CEILING, violated)
    }

    unsafe fn release(old: u32) {
        leave(old);
    }
}

#[allow(clippy::panic)] // the invariant's check: stop, never continue unprotected
fn violated(_exception: u32) -> ! {
    VIOLATED.store(true, Ordering::Relaxed);
    panic!("critical section above the protocol priority")
}
