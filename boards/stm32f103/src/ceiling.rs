//! This board's `critical_section` implementation: BASEPRI raised to the protocol task's
//! priority (boards/common `ceiling`), so the slot timer (TIM2) and the CAN interrupts are
//! never blocked by a critical section; PRIMASK (`critical-section-single-core`) would
//! block them all. Every image linking this crate gets it; no other implementation may be
//! in the graph (`cortex-m` without that feature).
use rtcan_board_common::ceiling::basepri_of;

/// RTIC logical priority of the protocol task, the ceiling of every critical section: the
/// one source of it. The RTIC app's `priority = ...` literals must agree (boards/app
/// `module_app!` asserts it at compile time): the protocol task and everything below it
/// may enter critical sections, the CAN interrupts and the slot timer above it may not.
/// 13: the node tasks get levels 1..=12 below it (boards/app `driver`), the CAN interrupts
/// 14 and the slot timer 15 above it, all under RTIC's PRIMASK level (16).
pub const PROTOCOL_PRIORITY: u8 = 13;

/// Priority bits the STM32F103's NVIC implements (4; the PAC's value, which RTIC uses).
pub const NVIC_PRIO_BITS: u8 = stm32f1xx_hal::pac::NVIC_PRIO_BITS;

/// The ceiling as a BASEPRI value (0x30 for logical 13 with 4 bits).
pub const CEILING: u8 = basepri_of(PROTOCOL_PRIORITY, NVIC_PRIO_BITS);

#[cfg(all(target_arch = "arm", target_os = "none"))]
mod imp {
    use super::CEILING;
    use rtcan_board_common::ceiling::{enter, leave};

    struct Ceiling;
    critical_section::set_impl!(Ceiling);

    // SAFETY: BASEPRI at CEILING excludes every context that may enter a critical section
    // (all run at or below it, checked by `enter` on each acquisition); `release` gets the
    // value its `acquire` returned (critical_section's contract).
    unsafe impl critical_section::Impl for Ceiling {
        unsafe fn acquire() -> u32 {
            // `_critical_section_1_0_acquire` is one function: users call it, the check
            // is not copied into each.
            enter(CEILING, violated)
        }

        unsafe fn release(old: u32) {
            leave(old);
        }
    }

    /// Code above the ceiling entered a critical section: it could corrupt what the
    /// section protects, so stop. `udf` is what panic-probe ends a panic with (a fault the
    /// probe and the emulator show); a panic message would cost flash every image pays.
    fn violated(_exception: u32) -> ! {
        cortex_m::asm::udf()
    }
}
