//! RCC, TIM2..4, ADC1, IWDG against RM0008 (section cited per test).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
use super::*;

// §7.3.1/§7.3.2: HSE on → HSERDY; PLL from HSE ×9 → PLLRDY; SW = PLL → SWS = PLL;
// 72 MHz SYSCLK, APB1 /2 = 36 MHz, TIM2 clock ×2 = 72 MHz (§7.2).
#[test]
fn rcc_clock_tree_7_3() {
    let mut r = Rcc::default();
    assert_eq!(r.sysclk(), 8_000_000, "HSI after reset");
    r.write(0x00, 0x83 | (1 << 16)).unwrap();
    assert_ne!(r.read(0).unwrap() & (1 << 17), 0, "HSERDY");
    r.write(0x04, (1 << 16) | (7 << 18) | (4 << 8)).unwrap();
    r.write(0x04, (1 << 16) | (7 << 18) | (4 << 8) | 2).unwrap();
    assert_eq!(
        r.read(4).unwrap() >> 2 & 3,
        0,
        "PLL not ready: SWS stays HSI"
    );
    r.write(0x00, 0x83 | (1 << 16) | (1 << 24)).unwrap();
    assert_ne!(r.read(0).unwrap() & (1 << 25), 0, "PLLRDY");
    r.write(0x04, (1 << 16) | (7 << 18) | (4 << 8) | 2).unwrap();
    assert_eq!(r.read(4).unwrap() >> 2 & 3, 2);
    assert_eq!(
        (r.sysclk(), r.pclk1(), r.tim2clk()),
        (72_000_000, 36_000_000, 72_000_000)
    );
    let mut dead = Rcc {
        hse_dead: true,
        ..Rcc::default()
    };
    dead.write(0x00, 1 << 16).unwrap();
    assert_eq!(
        dead.read(0).unwrap() & (1 << 17),
        0,
        "dead crystal: no HSERDY"
    );
    assert_eq!(r.read(0x30), Err(0x30));
}

// §15.3.1/§15.3.2/§15.4.6: UG loads PSC and sets UIF; the counter runs at
// clk/(PSC+1); CCxIF at CNT = CCRx, UIF at overflow; rc_w0 flags.
#[test]
fn tim_counter_compare_update_15_3() {
    let clk = 72_000_000;
    let mut t = Tim2::new();
    t.write(0x28, 8).unwrap(); // 8 MHz
    t.write(0x34, 100).unwrap();
    t.write(0x38, 0x8000).unwrap();
    t.write(0x14, 1).unwrap();
    assert_eq!(t.read(0x10).unwrap() & 1, 1, "UG sets UIF");
    t.write(0x10, 0).unwrap();
    t.write(0x0C, 0b110).unwrap(); // CC1IE, CC2IE
    t.write(0x00, 1).unwrap();
    // 99 ticks of 125 ns: no match yet.
    t.sync(99 * 125_000, clk);
    assert_eq!(t.read(0x24).unwrap(), 99);
    assert!(!t.irq());
    assert_eq!(t.next_event(99 * 125_000, clk), Some(100 * 125_000));
    t.sync(100 * 125_000, clk);
    assert_eq!(t.read(0x10).unwrap() & 0b110, 0b010, "CC1IF");
    assert!(t.irq());
    t.write(0x10, !0b010).unwrap();
    assert!(!t.irq(), "written 0 clears");
    // Past CCR2 and the overflow: CC2IF and UIF set, CC1 (100) not passed again.
    t.sync(0x1_0005 * 125_000, clk);
    assert_eq!(t.read(0x10).unwrap() & 0b111, 0b101);
    assert_eq!(t.read(0x24).unwrap(), 5);
    assert_eq!(t.read(0x30), Err(0x30), "reserved offset");
}

// §15.3.12: in encoder mode the clock does not move the counter; edges do, modulo ARR+1.
#[test]
fn tim_encoder_mode_15_3_12() {
    let mut t = Tim2::new();
    t.write(0x08, 3).unwrap();
    t.write(0x00, 1).unwrap();
    t.sync(1_000_000_000, 72_000_000);
    assert_eq!(t.read(0x24).unwrap(), 0);
    t.encoder_step(-3);
    assert_eq!(t.read(0x24).unwrap(), 0xFFFD);
    t.encoder_step(10);
    assert_eq!(t.read(0x24).unwrap(), 7);
}

// §11.3.1/§11.12.3: SWSTART with EXTSEL = SWSTART converts SQ1; EOC set, cleared by DR.
#[test]
fn adc_single_conversion_11_3() {
    let mut a = Adc::new();
    a.input[2] = 1234;
    a.write(0x08, 1).unwrap();
    a.write(0x34, 2).unwrap();
    a.write(0x08, 1 | (7 << 17) | (1 << 20) | (1 << 22))
        .unwrap();
    assert_eq!(
        a.read(0x08).unwrap() & (1 << 22),
        0,
        "SWSTART cleared at start"
    );
    assert_eq!(a.read(0x00).unwrap() & 2, 2, "EOC");
    assert_eq!(a.read(0x4C).unwrap(), 1234);
    assert_eq!(a.read(0x00).unwrap() & 2, 0, "DR read clears EOC");
}

// §19.4.1: 0xCCCC starts, 0xAAAA reloads; PR/RLR only after 0x5555.
#[test]
fn iwdg_19_4() {
    let mut w = Iwdg::new();
    w.write(0x08, 10, 0).unwrap();
    assert_eq!(w.read(0x08).unwrap(), 0xFFF, "locked");
    w.write(0x00, 0x5555, 0).unwrap();
    w.write(0x04, 0, 0).unwrap();
    w.write(0x08, 9, 0).unwrap();
    w.write(0x00, 0xCCCC, 0).unwrap();
    // (9+1) × 4 / 40 kHz = 1 ms.
    assert_eq!(w.deadline, Some(1_000_000_000));
    w.write(0x00, 0xAAAA, 500_000_000).unwrap();
    assert_eq!(w.deadline, Some(1_500_000_000));
}
