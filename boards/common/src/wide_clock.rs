//! A free-running 16-bit hardware counter extended to 64 bits in software.
//!
//! The interrupt handler counts *half* periods: one at overflow (update event) and one
//! at a compare event at 0x8000. The parity of that count says which half the counter
//! should be in, so a reading stays correct even when the overflow interrupt is pending
//! but not yet served (e.g. while a same-priority CAN handler runs): no lock-step with
//! the interrupt, no retry loop. Same method as embassy-stm32's time driver.

/// Half-period counter of a 16-bit timer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WideClock {
    half_periods: u32,
}

/// What to do with the compare channel of the wake-up alarm.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Arm {
    /// The target is already due: run the handler now (pend the interrupt).
    Due,
    /// Program the compare register to this value and enable its interrupt.
    Compare(u16),
    /// Too far ahead for the 16-bit compare: re-evaluate at the next half-period event.
    Later,
}

impl WideClock {
    /// Counter at 0, no half periods seen.
    pub const fn new() -> Self {
        WideClock { half_periods: 0 }
    }
    /// A clock that has counted `half_periods` already (models, tests).
    pub const fn from_half_periods(half_periods: u32) -> Self {
        WideClock { half_periods }
    }
    /// Call once per update (overflow) and once per half-period compare event.
    pub fn on_half_period(&mut self) {
        self.half_periods = self.half_periods.wrapping_add(1);
    }
    /// Half periods counted so far.
    pub const fn half_periods(&self) -> u32 {
        self.half_periods
    }
    /// 64-bit tick count from the current hardware counter value.
    pub const fn ticks(&self, counter: u16) -> u64 {
        let p = self.half_periods;
        ((p as u64) << 15) + ((counter as u32 ^ ((p & 1) << 15)) as u64)
    }
    /// How to arm the alarm for tick `target` when the clock reads `now` ticks. The
    /// compare register is only used within 0xC000 ticks (3/4 of a wrap) so that a match
    /// cannot happen one wrap early; beyond that the half-period events re-evaluate.
    pub const fn arm(target: u64, now: u64) -> Arm {
        if target <= now {
            Arm::Due
        } else if target - now < 0xC000 {
            Arm::Compare(target as u16)
        } else {
            Arm::Later
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Simulates the hardware: counter runs, events happen at 0x8000 and at wrap, and the
    /// handler may serve them late. Readings must be monotonic and exact.
    #[test]
    fn readings_are_exact_even_with_pending_events() {
        let mut clk = WideClock::new();
        let mut served = 0u64; // half periods served by the "ISR"
        for t in 0u64..(5 * 65_536) {
            let counter = t as u16;
            let due = t >> 15; // half-period events that have happened
                               // The ISR is late by up to 0x3000 ticks after each event.
            if served < due && (t & 0x7FFF) >= 0x3000 {
                clk.on_half_period();
                served += 1;
            }
            assert!(served + 1 >= due);
            assert_eq!(clk.ticks(counter), t, "at {t}");
        }
    }

    #[test]
    fn arm_decides_compare_due_or_later() {
        assert_eq!(WideClock::arm(100, 100), Arm::Due);
        assert_eq!(WideClock::arm(99, 100), Arm::Due);
        assert_eq!(WideClock::arm(0x1_0005, 0xFFF0), Arm::Compare(5));
        assert_eq!(
            WideClock::arm(100 + 0xBFFF, 100),
            Arm::Compare((100 + 0xBFFF) as u16)
        );
        assert_eq!(WideClock::arm(100 + 0xC000, 100), Arm::Later);
    }
}
