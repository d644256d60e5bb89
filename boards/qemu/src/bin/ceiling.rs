//! On-target test of the firmware's critical sections (boards/common `ceiling`, BASEPRI at
//! the protocol task's priority) on the Cortex-M3 with real NVIC interrupts, at the
//! firmware's RTIC priorities on the lm3s6965's 3 bits:
//!
//! | interrupt | plays | logical priority | byte |
//! |---|---|---|---|
//! | GPIOA | the slot timer | 4 | 0x80 |
//! | GPIOC | the protocol task | 2 (the ceiling) | 0xC0 |
//! | GPIOB | the app task | 1 | 0xE0 |
//!
//! Asserted: a critical section in thread mode lets the slot timer run inside it (never
//! blocked) and holds the app task off until it ends; BASEPRI is the ceiling inside
//! (nested too) and restored after; the protocol and app levels may enter one; the slot
//! timer entering one stops the program (the check on every acquisition: the panic
//! handler passes the run only then). Exit code 0 = pass.
#![no_std]
#![no_main]

use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::peripheral::NVIC;
use cortex_m::register::basepri;
use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use lm3s6965::{interrupt, Interrupt};
use rtcan_board_common::ceiling::basepri_of;
use rtcan_board_qemu::ceiling::{CEILING, NVIC_PRIO_BITS, VIOLATION_EXPECTED};
use rtcan_board_qemu::{check, fail};

const SLOT: Interrupt = Interrupt::GPIOA;
const APP: Interrupt = Interrupt::GPIOB;
const PROTOCOL: Interrupt = Interrupt::GPIOC;

/// Runs of each handler.
static SLOT_RUNS: AtomicU32 = AtomicU32::new(0);
static APP_RUNS: AtomicU32 = AtomicU32::new(0);
static PROTOCOL_RUNS: AtomicU32 = AtomicU32::new(0);
/// Handlers' critical sections completed (BASEPRI seen inside, as read).
static APP_SECTION: AtomicU32 = AtomicU32::new(0);
static PROTOCOL_SECTION: AtomicU32 = AtomicU32::new(0);
/// When non-zero, the slot-timer handler enters a critical section (the violation).
static SLOT_ENTERS: AtomicU32 = AtomicU32::new(0);

fn pend_and_settle(i: Interrupt) {
    NVIC::pend(i);
    // The pended interrupt is taken (if its priority allows) before the next instruction.
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
}

#[entry]
fn main() -> ! {
    let Some(mut p) = cortex_m::Peripherals::take() else {
        fail()
    };
    // SAFETY: priorities set before the interrupts are unmasked; no critical section is
    // relied on yet.
    unsafe {
        p.NVIC.set_priority(SLOT, basepri_of(4, NVIC_PRIO_BITS));
        p.NVIC.set_priority(PROTOCOL, basepri_of(2, NVIC_PRIO_BITS));
        p.NVIC.set_priority(APP, basepri_of(1, NVIC_PRIO_BITS));
        NVIC::unmask(SLOT);
        NVIC::unmask(PROTOCOL);
        NVIC::unmask(APP);
    }
    check!(CEILING == 0xC0, "ceiling {:#x}", CEILING);

    // Thread mode: the slot timer runs inside the section, the app task after it.
    let (inside, slot_inside, app_inside) = critical_section::with(|_| {
        pend_and_settle(SLOT);
        pend_and_settle(APP);
        let nested = critical_section::with(|_| basepri::read());
        check!(nested == CEILING, "nested BASEPRI {:#x}", nested);
        (
            basepri::read(),
            SLOT_RUNS.load(Ordering::Relaxed),
            APP_RUNS.load(Ordering::Relaxed),
        )
    });
    check!(inside == CEILING, "BASEPRI inside {:#x}", inside);
    check!(
        slot_inside == 1,
        "slot timer blocked by the section: {} runs",
        slot_inside
    );
    check!(
        app_inside == 0,
        "app task ran inside the section: {} runs",
        app_inside
    );
    check!(
        APP_RUNS.load(Ordering::Relaxed) == 1,
        "app task not run after the section"
    );
    check!(
        basepri::read() == 0,
        "BASEPRI not restored: {:#x}",
        basepri::read()
    );
    // The app's own section saw the ceiling.
    check!(
        APP_SECTION.load(Ordering::Relaxed) == u32::from(CEILING),
        "app section"
    );

    // The protocol level, at the ceiling, may enter one too.
    pend_and_settle(PROTOCOL);
    check!(
        PROTOCOL_RUNS.load(Ordering::Relaxed) == 1,
        "protocol task not run"
    );
    check!(
        PROTOCOL_SECTION.load(Ordering::Relaxed) == u32::from(CEILING),
        "protocol section"
    );
    hprintln!("ceiling: slot timer ran inside a critical section, app task held off, BASEPRI {:#x} then 0", CEILING);

    // Above the ceiling: refused (the panic handler ends the run as passed).
    VIOLATION_EXPECTED.store(true, Ordering::Relaxed);
    SLOT_ENTERS.store(1, Ordering::Relaxed);
    pend_and_settle(SLOT);
    VIOLATION_EXPECTED.store(false, Ordering::Relaxed);
    hprintln!("FAIL: the slot timer entered a critical section unchecked");
    fail()
}

#[interrupt]
fn GPIOA() {
    SLOT_RUNS.fetch_add(1, Ordering::Relaxed);
    if SLOT_ENTERS.load(Ordering::Relaxed) != 0 {
        critical_section::with(|_| SLOT_RUNS.fetch_add(1, Ordering::Relaxed));
    }
}

#[interrupt]
fn GPIOB() {
    APP_RUNS.fetch_add(1, Ordering::Relaxed);
    let seen = critical_section::with(|_| basepri::read());
    APP_SECTION.store(u32::from(seen), Ordering::Relaxed);
}

#[interrupt]
fn GPIOC() {
    PROTOCOL_RUNS.fetch_add(1, Ordering::Relaxed);
    let seen = critical_section::with(|_| basepri::read());
    PROTOCOL_SECTION.store(u32::from(seen), Ordering::Relaxed);
}
