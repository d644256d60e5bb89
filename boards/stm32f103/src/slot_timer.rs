//! The slot timer and the local clock, both on TIM2 (16-bit, free running at 8 MHz:
//! one tick = 125 ns exactly, wrap every 8.192 ms). The counter is extended to 64 bits in
//! software (`WideClock`: update event + compare channel 2 at half period). Compare
//! channel 1 commits the prepared slot plan (boards/common `protocol`), compare channel 3
//! is the prepare alarm that pends the protocol task ahead of a wake-up. No polling and
//! no busy wait: between events the CPU sleeps.
use rtcan_board_common::protocol::{Alarm, AlarmSetting, SlotTimerHw};
use rtcan_board_common::wide_clock::WideClock;
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
const DIER_CC3IE: u32 = 1 << 3;
const SR_UIF: u32 = 1;
const SR_CC1IF: u32 = 1 << 1;
const SR_CC2IF: u32 = 1 << 2;
const SR_CC3IF: u32 = 1 << 3;
const EGR_UG: u32 = 1;

/// The timer clock is not a multiple of `TICK_HZ`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BadTimerClock;

/// TIM2 as local clock and slot timer.
pub struct SlotTimer {
    tim: pac::TIM2,
    clock: WideClock,
    /// Commit target beyond the compare range (re-armed at half-period events).
    commit_later: Option<u64>,
    /// Prepare target beyond the compare range.
    prepare_later: Option<u64>,
}

/// Which alarm a compare channel serves.
#[derive(Clone, Copy)]
enum Channel {
    Commit,
    Prepare,
}

impl Channel {
    const fn index(self) -> usize {
        match self {
            Channel::Commit => 0,
            Channel::Prepare => 2,
        }
    }
    const fn ie(self) -> u32 {
        match self {
            Channel::Commit => DIER_CC1IE,
            Channel::Prepare => DIER_CC3IE,
        }
    }
    const fn flag(self) -> u32 {
        match self {
            Channel::Commit => SR_CC1IF,
            Channel::Prepare => SR_CC3IF,
        }
    }
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
            commit_later: None,
            prepare_later: None,
        })
    }

    /// Local time in ticks (two reads: the counter and the half-period count).
    pub fn ticks(&self) -> u64 {
        self.clock.ticks(self.tim.cnt().read().bits() as u16)
    }

    /// Local time in ns.
    pub fn now(&self) -> Nanos {
        Self::ns_of(self.ticks())
    }

    /// Local time of tick `ticks`, ns (outside critical sections: a 64-bit product).
    pub const fn ns_of(ticks: u64) -> Nanos {
        ticks * TICK_NS
    }

    fn set_ie(&mut self, ch: Channel, on: bool) {
        self.tim.dier().modify(|r, w| unsafe {
            w.bits(if on {
                r.bits() | ch.ie()
            } else {
                r.bits() & !ch.ie()
            })
        });
    }

    /// Applies `setting` (decided before the caller's critical section) to `ch`:
    /// register writes only. The caller reads the clock again and calls `rescue` if the
    /// target passed meanwhile (the counter may have passed the value before it was
    /// written: no match until the wrap).
    #[inline(always)]
    fn apply(&mut self, ch: Channel, setting: AlarmSetting) {
        let later = match setting {
            AlarmSetting::Off => {
                self.set_ie(ch, false);
                None
            }
            AlarmSetting::Due => {
                self.raise(ch);
                None
            }
            AlarmSetting::Compare { value, .. } => {
                self.tim
                    .ccr(ch.index())
                    .write(|w| unsafe { w.bits(value as u32) });
                // rc_w0: clear only this flag (a match of the old value).
                self.tim.sr().write(|w| unsafe { w.bits(!ch.flag()) });
                self.set_ie(ch, true);
                None
            }
            AlarmSetting::Later { at_ticks } => {
                self.set_ie(ch, false);
                Some(at_ticks)
            }
        };
        match ch {
            Channel::Commit => self.commit_later = later,
            Channel::Prepare => self.prepare_later = later,
        }
    }

    /// Arms a far target that came into range, in the interrupt: against a fresh reading,
    /// raised if it passed meanwhile.
    fn arm_now(&mut self, ch: Channel, target: u64) {
        self.apply(ch, AlarmSetting::new(target, self.ticks()));
        if self.ticks() >= target {
            self.rescue_channel(ch);
        }
    }

    /// The clock passed `ch`'s target: if its interrupt is still enabled and its flag
    /// not set, the match was lost; raise it.
    fn rescue_channel(&mut self, ch: Channel) {
        let sr = self.tim.sr().read().bits();
        let dier = self.tim.dier().read().bits();
        if dier & ch.ie() != 0 && sr & ch.flag() == 0 {
            self.raise(ch);
        }
    }

    /// Ticks from the commit compare's match to now (bench builds: the slot boundary's
    /// latency as the hardware saw it, blocking and interrupt entry included).
    pub fn ticks_since_commit_match(&self) -> u16 {
        let cnt = self.tim.cnt().read().bits() as u16;
        let ccr = self.tim.ccr(0).read().bits() as u16;
        cnt.wrapping_sub(ccr)
    }

    /// TIM2 interrupt entry: which alarms fired (two register reads, nothing written, so
    /// the commit can follow at once). A CC1 match with its interrupt enabled is the
    /// boundary: the compare is only used within 3/4 of a wrap, so it cannot match early.
    pub fn flags(&self) -> TimerFlags {
        let sr = self.tim.sr().read().bits();
        let dier = self.tim.dier().read().bits();
        TimerFlags {
            sr,
            commit: sr & SR_CC1IF != 0 && dier & DIER_CC1IE != 0,
            prepare: sr & SR_CC3IF != 0 && dier & DIER_CC3IE != 0,
        }
    }

    /// The rest of the interrupt, after the commit: clears the flags, disarms the alarms
    /// that fired, counts half periods and re-arms far targets that came into range; one
    /// already due is raised again by a software compare event (the interrupt re-enters
    /// at once and handles it like a match).
    pub fn acknowledge(&mut self, f: TimerFlags) {
        // rc_w0 flags: write 0 to the ones handled, 1 to leave the others alone.
        self.tim
            .sr()
            .write(|w| unsafe { w.bits(!(f.sr & (SR_UIF | SR_CC1IF | SR_CC2IF | SR_CC3IF))) });
        if f.commit || f.prepare {
            let off =
                (if f.commit { DIER_CC1IE } else { 0 }) | (if f.prepare { DIER_CC3IE } else { 0 });
            self.tim
                .dier()
                .modify(|r, w| unsafe { w.bits(r.bits() & !off) });
        }
        if f.sr & (SR_UIF | SR_CC2IF) != 0 {
            if f.sr & SR_UIF != 0 {
                self.clock.on_half_period();
            }
            if f.sr & SR_CC2IF != 0 {
                self.clock.on_half_period();
            }
            // A far target may now be within compare range.
            if let Some(t) = self.commit_later.take() {
                self.arm_now(Channel::Commit, t);
            }
            if let Some(t) = self.prepare_later.take() {
                self.arm_now(Channel::Prepare, t);
            }
        }
    }

    /// Software compare event on `ch` with its interrupt enabled: the TIM2 interrupt
    /// handles it as a match.
    fn raise(&mut self, ch: Channel) {
        // EGR.CCxG sits at the bit of SR.CCxIF.
        self.tim.egr().write(|w| unsafe { w.bits(ch.flag()) });
        self.set_ie(ch, true);
    }
}

/// What a TIM2 interrupt found (`SlotTimer::flags`).
#[derive(Clone, Copy, Debug)]
pub struct TimerFlags {
    sr: u32,
    /// The commit compare matched: apply the plan.
    pub commit: bool,
    /// The prepare alarm fired: pend the protocol task.
    pub prepare: bool,
}

impl Channel {
    const fn of(alarm: Alarm) -> Self {
        match alarm {
            Alarm::Commit => Channel::Commit,
            Alarm::Prepare => Channel::Prepare,
        }
    }
}

impl SlotTimerHw for SlotTimer {
    fn ticks(&self) -> u64 {
        SlotTimer::ticks(self)
    }
    fn ns_of(ticks: u64) -> Nanos {
        SlotTimer::ns_of(ticks)
    }
    fn ticks_of(at: Nanos) -> u64 {
        at.div_ceil(TICK_NS)
    }
    // Inline: the alarm is a constant at each call site.
    #[inline(always)]
    fn arm(&mut self, alarm: Alarm, setting: AlarmSetting) {
        self.apply(Channel::of(alarm), setting);
    }
    fn rescue(&mut self, alarm: Alarm) {
        self.rescue_channel(Channel::of(alarm));
    }
}
