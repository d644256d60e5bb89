//! NVIC/SCB/SysTick against the ARMv7-M ARM (section cited per test).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
use super::*;

// B3.4.9 / RM0008 §10.1.1: 4 priority bits; B1.5.4: lower value preempts, equal
// priority resolves by exception number; BASEPRI and PRIMASK raise the execution priority.
#[test]
fn priorities_basepri_primask_b1_5_4() {
    let mut s = Scs::default();
    // Enable IRQ 28 (TIM2) and IRQ 20 (CAN RX0), priorities 0x20 and 0x20; IRQ 7 at 0xF0.
    s.write(0x100, (1 << 28) | (1 << 20) | (1 << 7), 4, 0)
        .unwrap();
    s.write(0x41C, 0x20, 1, 0).unwrap(); // IPR byte 28
    s.write(0x414, 0x2F, 1, 0).unwrap(); // IPR byte 20: low nibble not implemented
    assert_eq!(s.read(0x414, 0).unwrap() & 0xFF, 0x20);
    s.write(0x404, 0xF0 << 24, 4, 0).unwrap(); // IPR byte 7
    s.set_pending(28);
    s.set_pending(20);
    s.set_pending(7);
    assert_eq!(
        s.next_exception(256),
        Some(16 + 20),
        "same priority: lower number first"
    );
    // BASEPRI 0x20 masks priority 0x20 and lower urgency.
    let exec = s.execution_priority(false, false, 0x20);
    assert_eq!(s.next_exception(exec), None);
    let exec = s.execution_priority(false, false, 0x30);
    assert_eq!(s.next_exception(exec), Some(36));
    assert_eq!(
        s.next_exception(s.execution_priority(true, false, 0)),
        None,
        "PRIMASK"
    );
    // A disabled IRQ never fires (ICER, B3.4.5).
    s.write(0x180, 1 << 20, 4, 0).unwrap();
    assert_eq!(s.next_exception(256), Some(16 + 28));
    // Nesting: while 28 is active, only a higher-priority (lower value) exception preempts.
    s.activate(16 + 28);
    assert!(!s.is_pending(28));
    assert_eq!(
        s.next_exception(s.execution_priority(false, false, 0)),
        None
    );
    assert_eq!(s.deactivate(), Some(16 + 28));
    assert_eq!(
        s.next_exception(s.execution_priority(false, false, 0)),
        Some(16 + 7)
    );
}

// B3.2.6 AIRCR.PRIGROUP: with PRIGROUP = 5 only bits [7:6] preempt; sub-priority orders.
#[test]
fn priority_grouping_b3_2_6() {
    let mut s = Scs::default();
    s.write(0x100, 0b11, 4, 0).unwrap();
    s.write(0x400, 0x50 | (0x40 << 8), 4, 0).unwrap(); // IRQ0 0x50, IRQ1 0x40
    s.write(0xD0C, 0x1234_0500, 4, 0).unwrap();
    assert_eq!(s.read(0xD0C, 0).unwrap() >> 8 & 7, 0, "no VECTKEY: ignored");
    s.write(0xD0C, 0x05FA_0500, 4, 0).unwrap();
    s.activate(16);
    s.set_pending(1);
    assert_eq!(
        s.next_exception(s.execution_priority(false, false, 0)),
        None,
        "same group 0x40"
    );
}

// B3.3: SysTick counts down from RVR, COUNTFLAG and the exception at 0, reload next tick;
// CLKSOURCE 0 is HCLK/8 on the STM32F103 (RM0008 §7.2).
#[test]
fn systick_b3_3() {
    let mut s = Scs::default();
    s.write(0x014, 99, 4, 0).unwrap();
    s.write(0x018, 0, 4, 0).unwrap();
    s.write(0x010, 0b111, 4, 0).unwrap(); // enable, TICKINT, processor clock
    assert_eq!(s.systick_due_in(), Some(100));
    assert!(!s.sync_systick(1), "first tick loads RVR");
    assert_eq!(s.read(0x018, 1).unwrap(), 99);
    assert!(s.sync_systick(100));
    assert_eq!(s.read(0x010, 100).unwrap() >> 16 & 1, 1, "COUNTFLAG");
    assert_eq!(
        s.read(0x010, 100).unwrap() >> 16 & 1,
        0,
        "cleared by the read"
    );
    assert_eq!(s.next_exception(256), Some(EXC_SYSTICK));
    s.write(0x010, 0b011, 4, 100).unwrap(); // HCLK/8
    assert_eq!(s.systick_due_in(), Some(800));
}

// C1.8: DWT CYCCNT counts cycles while CTRL.CYCCNTENA, holds otherwise.
#[test]
fn dwt_cyccnt_c1_8() {
    let mut s = Scs::default();
    assert_eq!(s.read_dwt(4, 1000).unwrap(), 0);
    s.write_dwt(0, 1, 1000).unwrap();
    assert_eq!(s.read_dwt(4, 1500).unwrap(), 500);
    s.write_dwt(0, 0, 1600).unwrap();
    assert_eq!(s.read_dwt(4, 9000).unwrap(), 600);
    assert_eq!(s.read_dwt(0x10, 0), Err(0x10), "unknown DWT register");
}

// B3.4.10 STIR and B3.2.4 ICSR: software pending.
#[test]
fn stir_and_icsr_b3_2_4() {
    let mut s = Scs::default();
    s.write(0x100, 1 << 8, 4, 0).unwrap();
    s.write(0xF00, 8, 4, 0).unwrap();
    assert!(s.is_pending(8) && s.reschedule);
    assert_eq!(s.read(0xD04, 0).unwrap() >> 12 & 0x1FF, 24, "VECTPENDING");
    s.write(0xD04, 1 << 28, 4, 0).unwrap();
    s.write(0xD20, 0xFF << 16, 4, 0).unwrap(); // PendSV lowest
    assert_eq!(s.next_exception(256), Some(24));
    assert_eq!(s.read(0xE00, 0), Err(0xE00));
}
