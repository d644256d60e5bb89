//! The slot timer and the local clock, both on TIM2 (16-bit, free running at 8 MHz:
//! one tick = 125 ns exactly, wrap every 8.192 ms). The counter is extended to 64 bits in
//! software (`WideClock`: update event + compare channel 2 at half period); compare
//! channel 1 is the engine's wake-up alarm, armed at the local time `Engine::poll`
//! returned. No polling and no busy wait: between events the CPU sleeps.
use rtcan_board_common::wide_clock::{Arm, WideClock};
use rtcan_core::time::Nanos;
use stm32f1xx_hal::pac;
use stm32f1xx_hal::rcc::Enable;

/// Tick rate of the local clock.
pub const TICK_HZ: u32 = 8_000_000;
/// Nanoseconds per tick.
pub const TICK_NS: u64 = 1_000_000_000 / TICK_HZ as u64;

// TIM2 register bits (RM0008 §15.4).
const CR1_CEN: u32 = 1;
const DIER_UIE: u32 = 1;
const DIER_CC1IE: u32 = 1 << 1;
const DIER_CC2IE: u32 = 1 << 2;
const SR_UIF: u32 = 1;
const SR_CC1IF: u32 = 1 << 1;
const SR_CC2IF: u32 = 1 << 2;
const EGR_UG: u32 = 1;

/// The timer clock is not a multiple of `TICK_HZ`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BadTimerClock;

/// TIM2 as local clock and slot timer.
pub struct SlotTimer {
    tim: pac::TIM2,
    clock: WideClock,
    /// Pending alarm, in ticks.
    alarm: Option<u64>,
}

impl SlotTimer {
    /// Starts TIM2 from `timer_clock_hz` (72 MHz with the clock tree of this crate).
    pub fn new(
        tim: pac::TIM2,
        rcc: &mut pac::RCC,
        timer_clock_hz: u32,
    ) -> Result<Self, BadTimerClock> {
        if !timer_clock_hz.is_multiple_of(TICK_HZ) || timer_clock_hz / TICK_HZ > 0x1_0000 {
            return Err(BadTimerClock);
        }
        pac::TIM2::enable(rcc);
        tim.cr1().write(|w| unsafe { w.bits(0) });
        tim.psc()
            .write(|w| unsafe { w.bits(timer_clock_hz / TICK_HZ - 1) });
        tim.arr().write(|w| unsafe { w.bits(0xFFFF) });
        tim.ccr(1).write(|w| unsafe { w.bits(0x8000) });
        // Load the prescaler now (update event), then drop the flag that causes.
        tim.egr().write(|w| unsafe { w.bits(EGR_UG) });
        tim.sr().write(|w| unsafe { w.bits(0) });
        tim.dier()
            .write(|w| unsafe { w.bits(DIER_UIE | DIER_CC2IE) });
        tim.cr1().write(|w| unsafe { w.bits(CR1_CEN) });
        Ok(SlotTimer {
            tim,
            clock: WideClock::new(),
            alarm: None,
        })
    }

    fn ticks(&self) -> u64 {
        self.clock.ticks(self.tim.cnt().read().bits() as u16)
    }

    /// Local time in ns.
    pub fn now(&self) -> Nanos {
        self.ticks() * TICK_NS
    }

    /// Arms the alarm at local time `at` (rounded up to a tick). Returns false if `at` is
    /// already due: the caller runs the engine again instead of waiting.
    pub fn set_alarm(&mut self, at: Nanos) -> bool {
        let target = at.div_ceil(TICK_NS);
        self.alarm = Some(target);
        self.arm()
    }

    fn arm(&mut self) -> bool {
        let Some(target) = self.alarm else {
            return true;
        };
        match WideClock::arm(target, self.ticks()) {
            Arm::Due => {
                self.alarm = None;
                self.set_cc1_interrupt(false);
                false
            }
            Arm::Compare(value) => {
                self.tim.ccr(0).write(|w| unsafe { w.bits(value as u32) });
                self.set_cc1_interrupt(true);
                // The counter may have passed `value` while it was written.
                if self.ticks() >= target {
                    self.alarm = None;
                    self.set_cc1_interrupt(false);
                    return false;
                }
                true
            }
            Arm::Later => {
                self.set_cc1_interrupt(false);
                true
            }
        }
    }

    fn set_cc1_interrupt(&mut self, on: bool) {
        self.tim.sr().write(|w| unsafe { w.bits(!SR_CC1IF) });
        self.tim.dier().modify(|r, w| unsafe {
            w.bits(if on {
                r.bits() | DIER_CC1IE
            } else {
                r.bits() & !DIER_CC1IE
            })
        });
    }

    /// TIM2 interrupt: counts half periods and returns true when the alarm is due (then
    /// run `Engine::poll` and re-arm with its result).
    pub fn on_interrupt(&mut self) -> bool {
        let sr = self.tim.sr().read().bits();
        // rc_w0 flags: write 0 to the ones handled, 1 to leave the others alone.
        self.tim
            .sr()
            .write(|w| unsafe { w.bits(!(sr & (SR_UIF | SR_CC2IF))) });
        if sr & SR_UIF != 0 {
            self.clock.on_half_period();
        }
        if sr & SR_CC2IF != 0 {
            self.clock.on_half_period();
        }
        // A half-period event may bring a far alarm into compare range, and the compare
        // event itself means it is due: `arm` decides both.
        !self.arm()
    }
}
