//! Instruction counting under QEMU `-icount shift=N,sleep=off`: every instruction
//! advances virtual time by 2^N ns and SysTick counts virtual time, so SysTick ticks are
//! proportional to instructions (12.8 ticks per instruction at shift=10 on lm3s6965evb).
//! The ratio and the measurement overhead are calibrated at start-up with a block of
//! NOPs, not assumed. (DWT CYCCNT is not emulated by QEMU: it reads 0.)
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;

const RELOAD: u32 = 0x00FF_FFFF;

/// What a measurement is of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `Engine::poll` at a slot boundary.
    Poll,
    /// `Engine::on_rx`.
    Rx,
    /// `Engine::on_tx_done` (includes loading the next frame).
    TxDone,
}

/// Receives measurements of engine calls from the bus.
pub trait Meter {
    /// Runs `f`, accounting it under `kind`.
    fn measure(&mut self, kind: Kind, f: &mut dyn FnMut());
}

/// Measures nothing (tests).
pub struct NoMeter;

impl Meter for NoMeter {
    fn measure(&mut self, _kind: Kind, f: &mut dyn FnMut()) {
        f()
    }
}

/// SysTick-based instruction meter.
pub struct SysTickMeter {
    syst: SYST,
    /// SysTick ticks per 1000 instructions (calibrated).
    ticks_per_kinsn: u32,
    /// Ticks of an empty measurement (calibrated).
    overhead: u32,
}

/// Max, sum and count of one kind, in instructions.
#[derive(Clone, Copy, Debug, Default)]
pub struct Stat {
    /// Largest.
    pub max: u32,
    /// Sum.
    pub sum: u64,
    /// Count.
    pub n: u32,
}

impl Stat {
    /// Adds one sample.
    pub fn add(&mut self, v: u32) {
        self.max = self.max.max(v);
        self.sum += v as u64;
        self.n += 1;
    }
    /// Mean (0 if empty).
    pub fn mean(&self) -> u32 {
        if self.n == 0 {
            0
        } else {
            (self.sum / self.n as u64) as u32
        }
    }
}

impl SysTickMeter {
    /// Starts SysTick (core clock, full 24-bit reload) and calibrates.
    pub fn new(mut syst: SYST) -> Self {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(RELOAD);
        syst.clear_current();
        syst.enable_counter();
        let mut m = SysTickMeter {
            syst,
            ticks_per_kinsn: 1,
            overhead: 0,
        };
        let empty = m.raw_ticks(&mut || {});
        // 1000 NOPs: one instruction each.
        let nops = m.raw_ticks(&mut || unsafe {
            core::arch::asm!(
                ".rept 1000",
                "nop",
                ".endr",
                options(nomem, nostack, preserves_flags)
            );
        });
        m.overhead = empty;
        m.ticks_per_kinsn = nops.saturating_sub(empty).max(1);
        m
    }
    /// SysTick ticks per 1000 instructions (12 800 expected at shift=10).
    pub fn ticks_per_kinsn(&self) -> u32 {
        self.ticks_per_kinsn
    }
    fn raw_ticks(&mut self, f: &mut dyn FnMut()) -> u32 {
        let a = SYST::get_current();
        f();
        let b = SYST::get_current();
        // SysTick counts down and wraps at RELOAD.
        a.wrapping_sub(b) & RELOAD
    }
    /// Instructions executed by `f` (overhead removed).
    pub fn instructions(&mut self, f: &mut dyn FnMut()) -> u32 {
        let t = self.raw_ticks(f).saturating_sub(self.overhead);
        ((t as u64 * 1000 + self.ticks_per_kinsn as u64 / 2) / self.ticks_per_kinsn as u64) as u32
    }
    /// Releases SysTick.
    pub fn free(self) -> SYST {
        self.syst
    }
}

/// A `SysTickMeter` that keeps statistics per `Kind`.
pub struct KindMeter {
    /// The meter.
    pub meter: SysTickMeter,
    /// `Engine::poll` at slot boundaries.
    pub poll: Stat,
    /// `Engine::on_rx`.
    pub rx: Stat,
    /// `Engine::on_tx_done`.
    pub tx_done: Stat,
}

impl Meter for KindMeter {
    fn measure(&mut self, kind: Kind, f: &mut dyn FnMut()) {
        let n = self.meter.instructions(f);
        match kind {
            Kind::Poll => self.poll.add(n),
            Kind::Rx => self.rx.add(n),
            Kind::TxDone => self.tx_done.add(n),
        }
    }
}

/// Prints one benchmark line in the format `run-qemu.sh` tabulates.
pub fn report(name: &str, s: &Stat) {
    cortex_m_semihosting::hprintln!(
        "BENCH {} max {} mean {} samples {}",
        name,
        s.max,
        s.mean(),
        s.n
    );
}
