//! An emulated STM32F103 for the rtcan firmware images: Unicorn executes the Cortex-M3
//! instruction set; the NVIC/SysTick/SCB/DWT (`scs`) and the STM32F103 peripherals
//! (`bxcan`, `periph`) are modelled here from the ARMv7-M ARM and RM0008, section by section.
//! Unknown register accesses are errors with address and PC, never silent zeros.
//!
//! GPL-2.0-or-later because it links libunicorn. Nothing in the firmware or in the
//! `rtcan` library depends on this crate.
pub mod access;
pub mod bus;
pub mod bxcan;
pub mod compare;
pub mod elf;
pub mod engine_ram;
pub mod mcu;
pub mod periph;
pub mod probe;
pub mod publications;
pub mod report;
pub mod robot;
pub mod rtt;
pub mod scs;
pub mod serial;
pub mod sim_report;
pub mod sites;
mod uc;

/// mimalloc in place of the C library's malloc for the whole process, Unicorn included
/// (its `override` feature): Unicorn 2.0.1 sends every store to RAM through
/// `notdirty_write`, which builds and frees a page collection (a GTree: several
/// malloc/free pairs) per store, and glibc's allocator was ≈ 10 % of a perf profile.
/// Called by `Mcu::new` so that the linker keeps mimalloc's object, whose `malloc`/`free`
/// then resolve libunicorn's references.
pub fn link_allocator() {
    // SAFETY: freeing null is a no-op.
    unsafe { libmimalloc_sys::mi_free(core::ptr::null_mut()) }
}

/// Result of a register access: the value read, or the unknown offset.
pub type Access = Result<u32, u32>;
