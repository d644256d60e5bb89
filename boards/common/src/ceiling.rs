//! Critical sections that never block the interrupts above a ceiling.
//!
//! Why not PRIMASK (`cortex-m`'s `critical-section-single-core`): every
//! `critical_section::with` user of the firmware (the R2P topics, the module status, the
//! app task's wake-up, rtic-time's timer queue) runs at or below the protocol task's
//! priority, yet a PRIMASK section blocks the slot timer and the CAN interrupts too: round
//! 6's module table evaluated its `on_missing` rules inside one and the emulated
//! slot→TXRQ rose from 0.76–2.37 µs to 5.6–8.6 µs (patches/README.md). Raising BASEPRI to
//! the ceiling instead excludes everything at or below it (all the users) and leaves the
//! interrupts above it (slot timer, CAN) free to run.
//!
//! The mutual exclusion holds only if no code above the ceiling enters such a section, so
//! `enter` checks it on every acquisition (IPSR, then the active exception's priority
//! byte: ≈ 8 instructions) and calls the violation handler instead of entering: in debug
//! builds and with feature `ceiling-check`, which the STM32F103 board crate enables (its
//! release images check too; the users all run at priority ≤ 2, off the slot path).
//!
//! The boards set the implementation with `critical_section::set_impl!` over [`enter`] and
//! [`leave`] (boards/stm32f103 `ceiling`, boards/qemu `ceiling`); the priority arithmetic
//! and the check are plain functions, tested on the host.

/// BASEPRI value that masks RTIC logical priority `logical` and every lower one on a core
/// with `bits` implemented priority bits (RTIC's `cortex_logical2hw`: logical 1 is the
/// least urgent, hardware priority values grow as urgency falls).
pub const fn basepri_of(logical: u8, bits: u8) -> u8 {
    let levels = 1u16 << bits;
    (levels.saturating_sub(logical as u16) << (8 - bits as u16)) as u8
}

/// Whether code running in exception `exception` (IPSR: 0 is thread mode), whose
/// priority byte is `priority`, is above the ceiling `ceiling` (a BASEPRI value), i.e. a
/// critical section there would not exclude anything it could preempt.
/// Reset, NMI and HardFault (1–3) have fixed priorities above every configurable one.
pub const fn above_ceiling(exception: u32, priority: u8, ceiling: u8) -> bool {
    match exception {
        0 => false,
        1..=3 => true,
        _ => priority < ceiling,
    }
}

#[cfg(all(target_arch = "arm", target_os = "none"))]
pub use cortex_m3::{enter, leave};

#[cfg(all(target_arch = "arm", target_os = "none"))]
mod cortex_m3 {
    #[cfg(any(debug_assertions, feature = "ceiling-check"))]
    use super::above_ceiling;
    use core::arch::asm;
    #[cfg(any(debug_assertions, feature = "ceiling-check"))]
    use core::ptr::read_volatile;

    /// NVIC_IPR0: one priority byte per external interrupt (exception 16 + n).
    #[cfg(any(debug_assertions, feature = "ceiling-check"))]
    const NVIC_IPR: usize = 0xE000_E400;
    /// SCB_SHPR1: one priority byte per system exception from 4 (MemManage).
    #[cfg(any(debug_assertions, feature = "ceiling-check"))]
    const SCB_SHPR: usize = 0xE000_ED18;

    /// The active exception's number (IPSR; 0 in thread mode).
    #[cfg(any(debug_assertions, feature = "ceiling-check"))]
    #[inline(always)]
    fn active_exception() -> u32 {
        let ipsr: u32;
        // SAFETY: reads a special register, no side effect.
        unsafe { asm!("mrs {}, IPSR", out(reg) ipsr, options(nomem, nostack, preserves_flags)) };
        ipsr & 0x1FF
    }

    /// The priority byte of configurable exception `exception` (≥ 4).
    #[cfg(any(debug_assertions, feature = "ceiling-check"))]
    #[inline(always)]
    fn priority_of(exception: u32) -> u8 {
        let addr = if exception >= 16 {
            NVIC_IPR + (exception as usize - 16)
        } else {
            SCB_SHPR + (exception as usize).saturating_sub(4)
        };
        // SAFETY: an architectural, always readable System Control Space byte.
        unsafe { read_volatile(addr as *const u8) }
    }

    /// Enters a critical section at `ceiling` (a BASEPRI value): checks that the caller
    /// runs at or below it (else `violated(exception)`, which never returns),
    /// raises BASEPRI to it (never lowers it: BASEPRI_MAX) and returns the old value for
    /// [`leave`] (a whole register: restoring it needs no zero-extension at each user).
    /// Inlined into the board's `acquire` (constants folded), which users call.
    #[inline(always)]
    pub fn enter(ceiling: u8, violated: fn(u32) -> !) -> u32 {
        // Checked in the firmware images (boards/stm32f103 enables `ceiling-check`) and in
        // debug builds; the QEMU benchmarks leave it out (their rows compare with
        // PRIMASK-era figures) except the `ceiling` test, which needs it.
        #[cfg(any(debug_assertions, feature = "ceiling-check"))]
        {
            let exception = active_exception();
            if exception != 0 && above_ceiling(exception, priority_of(exception), ceiling) {
                violated(exception);
            }
        }
        #[cfg(not(any(debug_assertions, feature = "ceiling-check")))]
        let _ = violated;
        let old: u32;
        // SAFETY: BASEPRI_MAX only raises the masking level; no memory access, but a
        // compiler barrier (no `nomem`) so nothing of the section moves above it.
        unsafe {
            asm!("mrs {}, BASEPRI", out(reg) old, options(nostack, preserves_flags));
            asm!("msr BASEPRI_MAX, {}", in(reg) u32::from(ceiling), options(nostack, preserves_flags));
        }
        old
    }

    /// Leaves the critical section `enter` returned `old` for: BASEPRI back to it.
    #[inline(always)]
    pub fn leave(old: u32) {
        // SAFETY: restores the level the matching `enter` found (sections nest LIFO);
        // a compiler barrier like `enter`.
        unsafe { asm!("msr BASEPRI, {}", in(reg) old, options(nostack, preserves_flags)) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basepri_matches_rtic_logical_priorities_on_4_and_3_bits() {
        // STM32F103 (4 bits): logical 1..=4 -> 0xF0, 0xE0, 0xD0, 0xC0.
        assert_eq!(basepri_of(1, 4), 0xF0);
        assert_eq!(basepri_of(2, 4), 0xE0);
        assert_eq!(basepri_of(3, 4), 0xD0);
        assert_eq!(basepri_of(4, 4), 0xC0);
        // lm3s6965 (QEMU, 3 bits).
        assert_eq!(basepri_of(2, 3), 0xC0);
        assert_eq!(basepri_of(4, 3), 0x80);
    }

    #[test]
    fn only_code_above_the_ceiling_is_a_violation() {
        let ceiling = basepri_of(2, 4);
        // Thread mode (init, idle) and the protocol task's own level: allowed.
        assert!(!above_ceiling(0, 0, ceiling));
        assert!(!above_ceiling(16 + 7, basepri_of(2, 4), ceiling));
        // The app task (1) and SysTick (0xF0): below, allowed.
        assert!(!above_ceiling(16 + 8, basepri_of(1, 4), ceiling));
        assert!(!above_ceiling(15, 0xF0, ceiling));
        // CAN interrupts (3) and the slot timer (4): above.
        assert!(above_ceiling(16 + 20, basepri_of(3, 4), ceiling));
        assert!(above_ceiling(16 + 28, basepri_of(4, 4), ceiling));
        // NMI and HardFault, whatever the byte reads.
        assert!(above_ceiling(2, 0xFF, ceiling));
        assert!(above_ceiling(3, 0xFF, ceiling));
        // An interrupt left at reset priority 0 (the most urgent): above.
        assert!(above_ceiling(16, 0, ceiling));
    }
}
