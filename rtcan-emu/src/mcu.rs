//! One emulated STM32F103C8/CB: Unicorn's Cortex-M3 plus the models of `scs`, `periph`
//! and `bxcan`, with time = instructions retired × cycles per instruction.
use crate::bxcan::BxCan;
use crate::elf;
use crate::periph::{Adc, Afio, Exti, Flash, Gpio, Iwdg, Rcc, Tim2, APB1_CAN, PS};
use crate::scs::Scs;
use crate::serial::{Dma, Usart, USART1_DR};
use crate::sites::{Block, Site, Sites};
use crate::uc::*;
use crate::Access;
use core::ffi::c_void;

/// Memory of the largest STM32F103 the images target (xE: 512 KiB flash, 64 KiB SRAM; RM0008
/// §3.3); a C8 image simply never touches the rest.
pub const FLASH_BASE: u32 = 0x0800_0000;
pub const FLASH_SIZE: u32 = 512 * 1024;
pub const SRAM_BASE: u32 = 0x2000_0000;
pub const SRAM_SIZE: u32 = 64 * 1024;

/// Emulated time per instruction.
#[derive(Clone, Copy, Debug)]
pub struct Timing {
    /// Core cycles per instruction with zero wait states.
    pub cpi: f64,
    /// Extra cycles per instruction per flash wait state (the prefetch buffer hides most).
    pub per_wait_state: f64,
    /// Cycles of exception entry and of exception return (Cortex-M3 TRM §5.5.1: 12).
    pub exception_cycles: u64,
}

impl Default for Timing {
    fn default() -> Self {
        Timing {
            cpi: 1.0,
            per_wait_state: 0.25,
            exception_cycles: 12,
        }
    }
}

/// An access to an address no model implements.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownAccess {
    pub addr: u32,
    pub pc: u32,
    pub write: bool,
    pub time_ps: u64,
}

/// A store into a watched range (`Mcu::watch_writes`): diagnostics of what the image
/// did when, with the exact emulated time and the storing instruction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WriteRecord {
    pub time_ps: u64,
    pub pc: u32,
    pub addr: u32,
    pub value: u32,
}

/// Why a Unicorn run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Why {
    /// The next peripheral event.
    Event,
    /// The caller's end time (`run_until`'s `until`).
    Until,
    /// The longest run `run_until` allows.
    Chunk,
    /// After an instruction that may unmask a pending interrupt.
    Unmask,
    /// After a store to a timer, the bxCAN or the SCS.
    Replan,
}

/// Counts of Unicorn runs by what ended them (`State::slices`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Slices {
    pub event: u64,
    pub until: u64,
    pub chunk: u64,
    pub unmask: u64,
    pub replan: u64,
    /// WFI or `b .` reached.
    pub sleep: u64,
    /// An exception return (branch to EXC_RETURN) that the run loop had to act on.
    pub exc_return: u64,
    /// Exception returns done inside the run (`State::return_in_run`): not run ends.
    pub returns_in_run: u64,
    /// Exceptions entered inside the run right after an unmask (`State::enter_in_run`).
    pub entries_in_run: u64,
    /// A fault or anything else.
    pub other: u64,
    /// Runs that stopped past their budget (a block boundary after the point planned),
    /// and by how many instructions: the emulator's event latency beyond the model.
    pub late: u64,
    pub late_sum: u64,
    pub late_max: u64,
}

/// Everything the callbacks reach (boxed: Unicorn holds its address).
pub struct State {
    pub timing: Timing,
    /// Instructions retired.
    pub instructions: u64,
    /// Emulated time at `base_instr`.
    base_ps: u64,
    base_instr: u64,
    /// Picoseconds per instruction at the current clocks.
    instr_ps: f64,
    /// `instructions` at which the current run ends: the block hook stops the run at the
    /// first block boundary at or past it (`on_block`).
    budget: u64,
    /// Instructions of the translation block executing now, counted into `instructions`
    /// when it has run (at the next block's hook, an exception return inside the run, or
    /// the run's end): during a block, time is the block's start (`on_block`).
    block_n: u64,
    /// The block executing now: address, size in bytes, and where in it the last
    /// peripheral access was (`access::Cursor`): time inside the block is its start plus
    /// the instructions before that access.
    block_addr: u32,
    block_size: u32,
    cursor: crate::access::Cursor,
    /// The block executing now ends with an instruction that may unmask an interrupt.
    unmask_end: bool,
    /// The block executing now ends with a WFI; the address after it.
    wfi_end: Option<u32>,
    /// Where a run that ended asleep resumes (`sleep_at`).
    resume_pc: Option<u32>,
    /// What set `budget` last (why the current run will end there).
    budget_why: Why,
    /// The emulated time (ps) the current `run_until` runs to.
    run_end: u64,
    /// Unicorn runs (`uc_emu_start`) by what ended them: the emulator's own cost.
    pub slices: Slices,
    pub scs: Scs,
    pub rcc: Rcc,
    pub flash: Flash,
    pub gpio: [Gpio; 5],
    pub afio: Afio,
    pub exti: Exti,
    /// TIM2, TIM3, TIM4 (index 0..3).
    pub tim: [Tim2; 3],
    pub adc1: Adc,
    pub can: BxCan,
    pub iwdg: Iwdg,
    pub usart1: Usart,
    pub dma1: Dma,
    pub unknown: Vec<UnknownAccess>,
    /// Time (ps) of the first transmit request since the bus last cleared it.
    pub txrq_at: Option<u64>,
    /// `run_until` returns at the first transmit request (the bus's look-ahead).
    pub stop_on_txrq: bool,
    /// All unknown accesses, repeats included.
    pub unknown_count: u64,
    /// Slot timer → TXRQ latencies and TXRQ times (`probe`).
    pub probe: crate::probe::SlotProbe,
    /// Exceptions taken, by exception number.
    pub taken: std::collections::BTreeMap<u16, u64>,
    /// Exception entries (time ps, exception number), when `Mcu::trace_exceptions` is on.
    pub entries: Option<Vec<(u64, u16)>>,
    /// Emulated time spent asleep (WFI / sleep-on-exit), ps.
    pub asleep_ps: u64,
    /// Resets (power-on, NRST, watchdog, SYSRESETREQ) since creation.
    pub resets: u32,
    exc_return: bool,
    wfi: bool,
    pub fault: Option<String>,
    dbg_cr: u32,
    /// Bus bit time in ps (from BTR and PCLK1) and the bus clock origin.
    pub bit_ps: u64,
    /// The image's WFI / `b .` / unmask instructions and instruction lengths (`on_block`).
    sites: Sites,
    /// Stores into the ranges given to `Mcu::watch_writes`, in order.
    pub writes: Vec<WriteRecord>,
    /// The SRAM's host memory (`Mcu::sram`, mapped into Unicorn with `uc_mem_map_ptr`).
    sram: *mut u8,
    uc: *mut uc_engine,
}

impl State {
    /// Emulated time now (ps).
    pub fn now(&self) -> u64 {
        self.base_ps + ((self.position() - self.base_instr) as f64 * self.instr_ps) as u64
    }

    /// Instructions retired up to now: those of finished blocks, and inside the block
    /// executing now those before its last peripheral access (`access`).
    fn position(&self) -> u64 {
        self.instructions + u64::from(self.cursor.pos)
    }

    /// Counts the block that has run to its end (`block_n`) into `instructions`.
    fn block_done(&mut self) {
        self.instructions += core::mem::take(&mut self.block_n);
        self.cursor = Default::default();
    }

    /// Matches a peripheral access of the block executing now to its instruction, so
    /// that `now` is the access's time (`access::Cursor`).
    fn locate(&mut self, write: bool, size: u32, addr: u32) {
        let (base, len) = (self.block_addr, self.block_size);
        let sites = &self.sites;
        self.cursor.locate(write, size, addr, len, |off| {
            sites.halfword(base.wrapping_add(off))
        });
    }

    fn retime(&mut self) {
        let now = self.now();
        self.base_ps = now;
        self.base_instr = self.position();
        let ws = f64::from(self.flash.wait_states());
        let cycles = self.timing.cpi + ws * self.timing.per_wait_state;
        self.instr_ps = cycles * PS as f64 / self.rcc.hclk().max(1) as f64;
    }

    /// CPU cycles at time `now` (for SysTick and CYCCNT).
    fn cycles(&self) -> u64 {
        (self.now() as f64 / (PS as f64 / self.rcc.hclk().max(1) as f64)) as u64
    }

    /// Adds `cycles` of core time without instructions (exception entry/return, sleep).
    fn add_time(&mut self, ps: u64) {
        self.base_ps += ps;
    }

    fn pc(&self) -> u32 {
        let mut v: u32 = 0;
        // SAFETY: `uc` is the live engine of this state; `v` is a valid u32 out-parameter.
        unsafe { uc_reg_read(self.uc, REG_PC, (&mut v as *mut u32).cast()) };
        v
    }

    /// The offset in SRAM of `[addr, addr + len)`, if it lies wholly in SRAM.
    fn sram_offset(addr: u32, len: usize) -> Option<usize> {
        let off = addr.checked_sub(SRAM_BASE)? as usize;
        (off.checked_add(len)? <= SRAM_SIZE as usize).then_some(off)
    }

    /// Reads emulated memory into `buf`: SRAM straight from its host memory (no Unicorn
    /// call: `uc_mem_read` looks the region up and copies through the address space, at
    /// every exception return), anything else through Unicorn. Unmapped bytes read as 0.
    fn read_into(&self, addr: u32, buf: &mut [u8]) {
        if let Some(off) = Self::sram_offset(addr, buf.len()) {
            // SAFETY: `sram` is the live SRAM_SIZE-byte buffer of this MCU (`Mcu::sram`)
            // and `off + buf.len() <= SRAM_SIZE`; Unicorn does not run while this copies
            // (callbacks run on the thread that runs the engine).
            unsafe {
                core::ptr::copy_nonoverlapping(self.sram.add(off), buf.as_mut_ptr(), buf.len())
            };
            return;
        }
        // SAFETY: live engine, `buf` writable for its length.
        let e =
            unsafe { uc_mem_read(self.uc, u64::from(addr), buf.as_mut_ptr().cast(), buf.len()) };
        if e != 0 {
            buf.fill(0);
        }
    }

    /// Writes emulated memory: SRAM straight into its host memory, anything else through
    /// Unicorn. A direct write does not invalidate translated code, which is right for
    /// SRAM because no image executes from it (`on_block` faults if one does); and it saves
    /// the page-collection lock (a GTree, malloc/free) of every `uc_mem_write`.
    fn write_from(&mut self, addr: u32, bytes: &[u8]) {
        if let Some(off) = Self::sram_offset(addr, bytes.len()) {
            // SAFETY: as in `read_into`.
            unsafe {
                core::ptr::copy_nonoverlapping(bytes.as_ptr(), self.sram.add(off), bytes.len())
            };
            return;
        }
        // SAFETY: live engine, `bytes` readable for its length. A write to unmapped
        // memory is dropped (as the bus would).
        unsafe { uc_mem_write(self.uc, u64::from(addr), bytes.as_ptr().cast(), bytes.len()) };
    }

    fn bus_bit(&self) -> u64 {
        self.now() / self.bit_ps.max(1)
    }

    fn read(&mut self, addr: u32, size: u32) -> Access {
        let now = self.now();
        let cyc = self.cycles();
        let r = match addr {
            // TIM2/3/4 at 0x4000_0000/0400/0800, clocked by APB1ENR bits 0..2 (§7.3.8).
            0x4000_0000..=0x4000_0BFF => {
                let i = ((addr >> 10) & 3) as usize;
                if self.rcc.apb1enr & (1 << i) == 0 {
                    return Err(addr);
                }
                let clk = self.rcc.tim2clk();
                let t = self.tim.get_mut(i).ok_or(addr)?;
                t.sync(now, clk);
                t.read(addr & 0x3FF)
            }
            0x4001_2400..=0x4001_27FF => self.adc1.read(addr & 0x3FF),
            0x4000_3000..=0x4000_33FF => self.iwdg.read(addr & 0x3FF),
            0x4000_6400..=0x4000_67FF => {
                if self.rcc.apb1enr & APB1_CAN == 0 {
                    return Err(addr);
                }
                let bit = self.bus_bit();
                self.can.tick(bit);
                self.can.read(addr & 0x3FF)
            }
            0x4001_0000..=0x4001_03FF => self.afio.read(addr & 0x3FF),
            0x4001_0400..=0x4001_07FF => self.exti.read(addr & 0x3FF),
            0x4001_0800..=0x4001_1BFF => {
                let port = ((addr - 0x4001_0800) / 0x400) as usize;
                self.gpio.get(port).ok_or(addr)?.read(addr & 0x3FF)
            }
            // USART1 clocked by APB2ENR.USART1EN (bit 14), DMA1 by AHBENR.DMA1EN (bit 0).
            0x4001_3800..=0x4001_3BFF if self.rcc.apb2enr & (1 << 14) != 0 => {
                let pclk2 = self.rcc.pclk2();
                self.usart1.read(addr & 0x3FF, now, pclk2)
            }
            0x4002_0000..=0x4002_03FF if self.rcc.ahbenr & 1 != 0 => self.dma1.read(addr & 0x3FF),
            0x4002_1000..=0x4002_13FF => self.rcc.read(addr & 0x3FF),
            0x4002_2000..=0x4002_23FF => self.flash.read(addr & 0x3FF),
            0xE000_1000..=0xE000_1FFF => self.scs.read_dwt(addr & 0xFFF, cyc),
            0xE000_E000..=0xE000_EFFF => self.scs.read(addr & 0xFFF, cyc),
            // DBGMCU (RM0008 §31.16): IDCODE of a medium-density device, CR.
            0xE004_2000 => Ok(0x2003_6410),
            0xE004_2004 => Ok(self.dbg_cr),
            _ => Err(addr),
        };
        let _ = size;
        r.map_err(|_| addr)
    }

    fn write(&mut self, addr: u32, size: u32, v: u32) -> Access {
        let now = self.now();
        let cyc = self.cycles();
        let r = match addr {
            0x4000_0000..=0x4000_0BFF => {
                let i = ((addr >> 10) & 3) as usize;
                if self.rcc.apb1enr & (1 << i) == 0 {
                    return Err(addr);
                }
                let clk = self.rcc.tim2clk();
                let t = self.tim.get_mut(i).ok_or(addr)?;
                t.sync(now, clk);
                t.write(addr & 0x3FF, v)
            }
            0x4001_2400..=0x4001_27FF => self.adc1.write(addr & 0x3FF, v),
            0x4000_3000..=0x4000_33FF => self.iwdg.write(addr & 0x3FF, v, now),
            0x4000_6400..=0x4000_67FF => {
                if self.rcc.apb1enr & APB1_CAN == 0 {
                    return Err(addr);
                }
                self.bit_ps = (self.can.bit_pclk_cycles() * PS) / self.rcc.pclk1().max(1);
                let bit = self.bus_bit();
                self.can.tick(bit);
                let r = self.can.write(addr & 0x3FF, v, bit);
                self.bit_ps = (self.can.bit_pclk_cycles() * PS) / self.rcc.pclk1().max(1);
                // A transmit request (TIxR with TXRQ): the bus may have to arbitrate.
                let off = addr & 0x3FF;
                if (0x180..0x1B0).contains(&off) && off.is_multiple_of(16) && v & 1 != 0 {
                    self.txrq_at.get_or_insert(now);
                    let in_timer = self.scs.active.contains(&crate::probe::EXC_TIM2);
                    self.probe
                        .txrq(((off - 0x180) / 16) as usize, now, in_timer);
                }
                r
            }
            0x4001_0000..=0x4001_03FF => self.afio.write(addr & 0x3FF, v),
            0x4001_0400..=0x4001_07FF => self.exti.write(addr & 0x3FF, v),
            0x4001_0800..=0x4001_1BFF => {
                let port = ((addr - 0x4001_0800) / 0x400) as usize;
                self.gpio.get_mut(port).ok_or(addr)?.write(addr & 0x3FF, v)
            }
            0x4001_3800..=0x4001_3BFF if self.rcc.apb2enr & (1 << 14) != 0 => {
                let pclk2 = self.rcc.pclk2();
                self.usart1.write(addr & 0x3FF, v, now, pclk2)
            }
            0x4002_0000..=0x4002_03FF if self.rcc.ahbenr & 1 != 0 => {
                self.dma1.write(addr & 0x3FF, v)
            }
            0x4002_1000..=0x4002_13FF => {
                let r = self.rcc.write(addr & 0x3FF, v);
                self.retime();
                r
            }
            0x4002_2000..=0x4002_23FF => {
                let r = self.flash.write(addr & 0x3FF, v);
                self.retime();
                r
            }
            0xE000_1000..=0xE000_1FFF => self.scs.write_dwt(addr & 0xFFF, v, cyc),
            0xE000_E000..=0xE000_EFFF => self.scs.write(addr & 0xFFF, v, size, cyc),
            0xE004_2004 => {
                self.dbg_cr = v;
                Ok(0)
            }
            _ => Err(addr),
        };
        r.map_err(|_| addr)
    }

    /// Interrupt lines of the peripherals into the NVIC (RM0008 §10.1.2, table 63): every
    /// line that is high now sets its IRQ pending. Returns whether TIM2's line rose (the
    /// slot probe's boundary).
    fn raise_lines(&mut self) -> bool {
        let now = self.now();
        let clk = self.rcc.tim2clk();
        let mut tim2_rose = false;
        // TIM2, TIM3, TIM4: IRQ 28, 29, 30.
        for (i, t) in self.tim.iter_mut().enumerate() {
            t.sync(now, clk);
            if i == 0 {
                let before = self.probe.line();
                self.probe.timer_line(t.irq(), now);
                tim2_rose = t.irq() && !before;
            }
            if t.irq() {
                self.scs.set_pending(28 + i);
            }
        }
        let cyc = self.cycles();
        self.scs.sync_systick(cyc);
        let bit = now / self.bit_ps.max(1);
        self.can.tick(bit);
        let lines = self.can.irq_lines();
        for (i, irq) in [
            crate::bxcan::IRQ_TX,
            crate::bxcan::IRQ_RX0,
            crate::bxcan::IRQ_RX1,
            crate::bxcan::IRQ_SCE,
        ]
        .into_iter()
        .enumerate()
        {
            if lines.get(i) == Some(&true) {
                self.scs.set_pending(irq);
            }
        }
        // EXTI lines 0..4 have their own IRQs 6..10 (table 63).
        for line in 0..5 {
            if self.exti.pr & (1 << line) != 0 {
                self.scs.set_pending(6 + line);
            }
        }
        // USART1: IRQ 37; DMA1 channels 4 and 5: IRQ 14 and 15 (table 63).
        if self.usart1.irq(now, self.rcc.pclk2()) {
            self.scs.set_pending(37);
        }
        for (c, irq) in [(3, 14), (4, 15)] {
            if self.dma1.irq(c) {
                self.scs.set_pending(irq);
            }
        }
        tim2_rose
    }

    /// The next time (ps) a peripheral changes an interrupt line by itself.
    fn next_event(&self) -> Option<u64> {
        let now = self.now();
        let mut t: Option<u64> = None;
        let mut at = |x: u64| t = Some(t.map_or(x, |y: u64| y.min(x)));
        for tim in &self.tim {
            if let Some(x) = tim.next_event(now, self.rcc.tim2clk()) {
                at(x);
            }
        }
        let hz = self.rcc.hclk().max(1);
        if let Some(c) = self.scs.systick_due_in() {
            at(now + c * PS / hz);
        }
        if let Some(b) = self.can.next_event() {
            at(b * self.bit_ps);
        }
        if let Some(d) = self.iwdg.deadline {
            at(d);
        }
        if let Some(x) = self.usart1.next_event(now, self.rcc.pclk2()) {
            at(x);
        }
        t
    }

    /// After a store that may move the next event or raise an interrupt line (a timer,
    /// the bxCAN, the SCS), from inside the run: does what the run loop would do at the
    /// next instruction boundary, without ending the run unless that boundary must act.
    /// The lines are raised now (as the loop's `raise_irqs` would after this
    /// instruction, at the same emulated time); the run ends after this instruction
    /// when an exception can be taken, TIM2's line rose (the probe records the core's
    /// state there), a reset was requested, or the bus waits for this transmit request;
    /// else it goes on, shortened if the next event moved earlier. The budget is the one
    /// the loop would compute at that boundary, so timing is unchanged.
    fn after_write(&mut self) {
        let tim2_rose = self.raise_lines();
        let stop = tim2_rose
            || self.scs.reset_request
            || (self.stop_on_txrq && self.txrq_at.is_some())
            || {
                let exec = self.execution_priority();
                self.scs.next_exception(exec).is_some()
            };
        // Inside a block nothing can stop the core (Unicorn checks for a stop only when a
        // block starts): the run ends at the end of this block, `block_n` instructions on.
        let block_end = self.instructions + self.block_n.max(1);
        if stop {
            if block_end < self.budget {
                self.budget = block_end;
                self.budget_why = Why::Replan;
            }
            return;
        }
        if let Some(e) = self.next_event() {
            let left = e.saturating_sub(self.now());
            let n = ((left as f64 / self.instr_ps.max(1.0)) as u64).max(1);
            // `now` is this access's instruction: the event is n instructions from there.
            if self.position() + n < self.budget {
                self.budget = self.position() + n;
                self.budget_why = Why::Event;
            }
        }
    }

    /// The core's execution priority from PRIMASK, FAULTMASK and BASEPRI (B1.5.4): what a
    /// pending exception must beat to be taken now.
    fn execution_priority(&self) -> i16 {
        let primask = self.reg(REG_PRIMASK) & 1 != 0;
        let faultmask = self.reg(REG_FAULTMASK) & 1 != 0;
        let basepri = self.reg(REG_BASEPRI) as u8;
        self.scs.execution_priority(primask, faultmask, basepri)
    }

    fn reg(&self, r: i32) -> u32 {
        let mut v: u32 = 0;
        // SAFETY: `uc` is the live engine of this state; `v` is a valid u32 out-parameter.
        unsafe { uc_reg_read(self.uc, r, (&mut v as *mut u32).cast()) };
        v
    }

    fn unknown_access(&mut self, addr: u32, write: bool) {
        self.unknown_count += 1;
        // One record per (address, direction): the first one, with its PC and time.
        if self
            .unknown
            .iter()
            .any(|u| u.addr == addr && u.write == write)
        {
            return;
        }
        let rec = UnknownAccess {
            addr,
            pc: self.pc(),
            write,
            time_ps: self.now(),
        };
        self.unknown.push(rec);
    }
}

extern "C" fn mmio_read(_uc: *mut uc_engine, off: u64, size: u32, ud: *mut c_void) -> u64 {
    // SAFETY: `ud` is the `State` box registered with this region; Unicorn calls back on
    // the thread running `uc_emu_start`, while `Mcu` holds no other borrow of it.
    let st = unsafe { &mut *ud.cast::<State>() };
    let addr = region_base(off);
    st.locate(false, size, addr);
    match st.read(addr, size) {
        Ok(v) => u64::from(v >> (8 * (addr & 3))),
        Err(a) => {
            st.unknown_access(a, false);
            0
        }
    }
}

extern "C" fn mmio_write(_uc: *mut uc_engine, off: u64, size: u32, v: u64, ud: *mut c_void) {
    // SAFETY: as in `mmio_read`.
    let st = unsafe { &mut *ud.cast::<State>() };
    let addr = region_base(off);
    st.locate(true, size, addr);
    // Byte and half-word writes land in their lane of the 32-bit register.
    let lane = 8 * (addr & 3);
    let aligned = addr & !3;
    let v = if size < 4
        && !(0xE000_E400..0xE000_E440).contains(&aligned)
        && !(0xE000_ED18..0xE000_ED24).contains(&aligned)
    {
        let old = st.read(aligned, 4).unwrap_or(0);
        let mask = if size == 1 { 0xFFu32 } else { 0xFFFF } << lane;
        (old & !mask) | (((v as u32) << lane) & mask)
    } else {
        v as u32
    };
    let target = if size < 4
        && ((0xE000_E400..0xE000_E440).contains(&aligned)
            || (0xE000_ED18..0xE000_ED24).contains(&aligned))
    {
        addr
    } else {
        aligned
    };
    if let Err(a) = st.write(target, size, v) {
        st.unknown_access(a, true);
    }
    // A write to a timer, the bxCAN or the NVIC/SysTick may move the next event or pend an
    // interrupt: end this run so `run_until` recomputes its horizon and takes it in time.
    let replan = (0x4000_0000..0x4000_0C00).contains(&aligned)
        || (0x4000_6400..0x4000_6800).contains(&aligned)
        || (0xE000_E000..0xE000_F000).contains(&aligned);
    // Stopping here, inside an instruction, would resume at a stale PC: `after_write`
    // shortens the budget instead, and the block hook stops at the next block.
    if replan {
        st.after_write();
    }
}

/// The absolute address: the per-region callbacks (`read_apb`, `read_sys`, ...) have
/// already added their base to the offset Unicorn passes.
fn region_base(off: u64) -> u32 {
    off as u32
}

/// The one hook on the code (see `sites` for why one, and docs/EMULATOR.md "Time" for
/// why per block): called as each translation block starts, before any of its
/// instructions. It counts the block that has just run, ends the run at the first block
/// boundary at or past the budget, and acts on the image's WFI / `b .` / unmask sites.
///
/// In Unicorn 2.0.1 the block hook is emitted ahead of the block's exit-request check
/// (`translator_loop`, `gen_tb_start`), so a stop requested here ends the run before the
/// block's first instruction: the PC is the block's start, nothing of it ran.
extern "C" fn on_block(uc: *mut uc_engine, addr: u64, size: u32, ud: *mut c_void) {
    // SAFETY: as in `mmio_read`.
    let st = unsafe { &mut *ud.cast::<State>() };
    st.block_done();
    st.wfi_end = None;
    // The block before ended with CPSIE / MSR PRIMASK / MSR BASEPRI (QEMU ends a block
    // after each: they change what may interrupt), and something is pending: the
    // interrupt is taken here, right after it, where the NVIC would — inside the run
    // (`State::enter_in_run`), or by ending the run here when the loop must act. With
    // nothing pending (pending state changes only at run boundaries and in
    // `after_write`, which ends the run itself when an exception can be taken),
    // unmasking lets nothing in: the run goes on.
    if core::mem::take(&mut st.unmask_end) && st.scs.any_pending() && st.instructions < st.budget {
        match st.enter_in_run(addr as u32) {
            Some(true) => {
                st.slices.entries_in_run += 1;
                return;
            }
            Some(false) => {}
            None => {
                st.budget = st.instructions;
                st.budget_why = Why::Unmask;
            }
        }
    }
    if st.instructions >= st.budget {
        let late = st.instructions - st.budget;
        if late > 0 {
            st.slices.late += 1;
            st.slices.late_sum += late;
            st.slices.late_max = st.slices.late_max.max(late);
        }
        // SAFETY: `uc` is the engine calling this hook.
        unsafe { uc_emu_stop(uc) };
        return;
    }
    let addr = addr as u32;
    let block = match st.sites.block(addr, size) {
        Some(b) => b,
        // Code in SRAM: the emulator writes SRAM without invalidating translated code
        // (`State::write_from`), so it cannot run code from there. No image does.
        None if addr.wrapping_sub(SRAM_BASE) < SRAM_SIZE => {
            st.fault = Some(format!("code executing from SRAM at {addr:#010x}"));
            // SAFETY: `uc` is the engine calling this hook.
            unsafe { uc_emu_stop(uc) };
            return;
        }
        // Outside the scanned image (no Triskar2 image goes there): counted from memory.
        None => Block {
            n: count_in_memory(st, addr, size),
            first: None,
            last: None,
        },
    };
    match block.first {
        // `b .`: a spin that only an interrupt leaves (RTIC's idle without an idle task).
        // Equivalent to sleeping: time jumps to the next event, PC stays.
        Some(Site::Spin) => {
            st.instructions += 1;
            return sleep_at(uc, st, addr | 1);
        }
        // WFI: sleep, and resume past the 16-bit WFI (Thumb bit set).
        Some(Site::Wfi) => {
            st.instructions += 1;
            return sleep_at(uc, st, addr + 3);
        }
        _ => {}
    }
    st.block_n = u64::from(block.n);
    st.block_addr = addr;
    st.block_size = size;
    match block.last {
        Some(Site::Unmask) => st.unmask_end = true,
        // A WFI that ends a longer block executes in Unicorn: with no interrupt request
        // of its own (the model takes exceptions, not Unicorn) the core halts and the
        // run ends with the PC after it, which `run_until` reads as sleep.
        Some(Site::Wfi) => st.wfi_end = Some(addr.wrapping_add(size)),
        _ => {}
    }
}

/// Instructions in the `size` bytes at `addr`, read from emulated memory (the slow path
/// of `on_block`, for code outside the image's site table).
fn count_in_memory(st: &State, addr: u32, size: u32) -> u32 {
    let mut bytes = vec![0u8; size as usize];
    st.read_into(addr, &mut bytes);
    let (mut i, mut n) = (0usize, 0u32);
    while let Some(h) = bytes.get(i..i + 2) {
        n += 1;
        let hw = u16::from_le_bytes([
            h.first().copied().unwrap_or(0),
            h.get(1).copied().unwrap_or(0),
        ]);
        i += if crate::sites::is_wide(hw) { 4 } else { 2 };
    }
    n
}

/// Ends the run before the current instruction, asleep, resuming at `pc`.
///
/// The PC is set by `run_until` after the run, not here: in Unicorn 2.0.1 a PC write
/// from a hook restarts the translation loop and cancels a pending stop request
/// (`quit_request` clears `stop_request`), so the core went on executing — the `b .`
/// idle loop spun, one hook call per iteration, until the run's instruction budget
/// ran out, and a WFI behaved as a NOP. Measured before this fix: 3.6 M of psu's
/// 6.9 M instructions in 0.3 s were its `b .`, and every module's busy fraction read
/// ≈ 0.5.
fn sleep_at(uc: *mut uc_engine, st: &mut State, pc: u32) {
    st.wfi = true;
    st.resume_pc = Some(pc);
    // SAFETY: `uc` is the engine calling the hook.
    unsafe { uc_emu_stop(uc) };
}

extern "C" fn on_intr(uc: *mut uc_engine, intno: u32, ud: *mut c_void) {
    // SAFETY: as in `mmio_read`.
    let st = unsafe { &mut *ud.cast::<State>() };
    // The block that branched here has run (the branch was its last instruction).
    st.block_done();
    st.unmask_end = false;
    st.wfi_end = None;
    // A branch to EXC_RETURN (0xFFFFFFxx) faults in Unicorn's thread mode (the region is
    // execute-never): that is the exception return. Anything else is a CPU fault of the image
    // (UDF of a panic, bad instruction): reported, not modelled as HardFault.
    let pc = st.pc();
    if pc >= 0xFFFF_FF00 {
        if st.return_in_run() {
            st.slices.returns_in_run += 1;
            return;
        }
        st.exc_return = true;
    } else {
        st.fault = Some(format!("CPU exception {intno} at pc {pc:#010x}"));
    }
    // SAFETY: `uc` is the engine calling this hook.
    unsafe { uc_emu_stop(uc) };
}

extern "C" fn on_write(
    _uc: *mut uc_engine,
    _kind: i32,
    addr: u64,
    _size: i32,
    value: i64,
    ud: *mut c_void,
) {
    // SAFETY: as in `mmio_read`.
    let st = unsafe { &mut *ud.cast::<State>() };
    let rec = WriteRecord {
        time_ps: st.now(),
        pc: st.pc(),
        addr: addr as u32,
        value: value as u32,
    };
    st.writes.push(rec);
}

extern "C" fn on_unmapped(
    uc: *mut uc_engine,
    kind: i32,
    addr: u64,
    _size: i32,
    _value: i64,
    ud: *mut c_void,
) -> bool {
    // SAFETY: as in `mmio_read`.
    let st = unsafe { &mut *ud.cast::<State>() };
    if addr as u32 >= 0xFFFF_FF00 {
        st.exc_return = true;
    } else {
        st.unknown_access(addr as u32, kind == 20);
        st.fault = Some(format!("unmapped access at {addr:#010x}"));
    }
    // SAFETY: `uc` is the engine calling this hook.
    unsafe { uc_emu_stop(uc) };
    false
}

/// Why `Mcu::new` failed.
#[derive(Debug)]
pub enum EmuError {
    Elf(elf::BadElf),
    Unicorn(&'static str, i32),
}

/// One MCU running one image.
pub struct Mcu {
    pub name: String,
    uc: *mut uc_engine,
    pub st: Box<State>,
    image: Vec<elf::Segment>,
    pub rtt: Option<u32>,
    /// SRAM's host memory (a leaked `Box<[Page]>`, freed by `Drop` after the engine is
    /// closed), mapped into the engine with `uc_mem_map_ptr`: the emulator reads and
    /// writes it without a Unicorn call (`State::read_into`), only through raw pointers.
    sram: *mut [Page],
}

/// One 4 KiB page of host memory backing emulated RAM (Unicorn maps host memory in
/// whole pages, page-aligned).
#[repr(C, align(4096))]
struct Page([u8; 4096]);

fn check(what: &'static str, e: uc_err) -> Result<(), EmuError> {
    if e == 0 {
        Ok(())
    } else {
        Err(EmuError::Unicorn(what, e))
    }
}

impl Drop for Mcu {
    fn drop(&mut self) {
        // SAFETY: `uc` was opened by `new` and is closed once here, before the SRAM it
        // maps is freed; `sram` came from `Box::into_raw` in `new` and is freed once.
        unsafe {
            uc_close(self.uc);
            drop(Box::from_raw(self.sram));
        }
    }
}

impl Mcu {
    /// An MCU with `elf_bytes` programmed into flash, held in reset.
    pub fn new(name: &str, elf_bytes: &[u8], timing: Timing) -> Result<Mcu, EmuError> {
        crate::link_allocator();
        let image = elf::load_segments(elf_bytes).map_err(EmuError::Elf)?;
        let rtt = elf::symbol(elf_bytes, "_SEGGER_RTT").map_err(EmuError::Elf)?;
        let mut uc: *mut uc_engine = core::ptr::null_mut();
        // SAFETY: plain FFI calls with valid out-pointers; `st` is boxed so the address
        // given to Unicorn stays valid for the life of `Mcu`, which closes the engine first.
        unsafe {
            check(
                "uc_open",
                uc_open(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS, &mut uc),
            )?;
            check(
                "cpu model",
                uc_ctl(uc, UC_CTL_CPU_MODEL_WRITE, UC_CPU_ARM_CORTEX_M3),
            )?;
        }
        let pages: Box<[Page]> = (0..SRAM_SIZE / 4096).map(|_| Page([0; 4096])).collect();
        let sram = Box::into_raw(pages);
        let sram_ptr: *mut u8 = sram.cast();
        let mut st = Box::new(State {
            timing,
            instructions: 0,
            base_ps: 0,
            base_instr: 0,
            instr_ps: 0.0,
            budget: 0,
            block_n: 0,
            block_addr: 0,
            block_size: 0,
            cursor: Default::default(),
            unmask_end: false,
            wfi_end: None,
            resume_pc: None,
            budget_why: Why::Until,
            run_end: 0,
            slices: Slices::default(),
            scs: Scs::default(),
            rcc: Rcc::default(),
            flash: Flash::default(),
            gpio: Default::default(),
            afio: Afio::default(),
            exti: Exti::default(),
            tim: [Tim2::new(), Tim2::new(), Tim2::new()],
            adc1: Adc::new(),
            can: BxCan::default(),
            iwdg: Iwdg::new(),
            usart1: Usart::default(),
            dma1: Dma::default(),
            unknown: Vec::new(),
            txrq_at: None,
            stop_on_txrq: false,
            unknown_count: 0,
            probe: crate::probe::SlotProbe::default(),
            taken: Default::default(),
            entries: None,
            asleep_ps: 0,
            resets: 0,
            exc_return: false,
            wfi: false,
            fault: None,
            dbg_cr: 0,
            bit_ps: 1_000_000,
            sites: Sites::scan(&image),
            writes: Vec::new(),
            sram: sram_ptr,
            uc,
        });
        st.retime();
        let ud: *mut c_void = (&mut *st as *mut State).cast();
        // SAFETY: see above.
        unsafe {
            check(
                "map flash",
                uc_mem_map(uc, u64::from(FLASH_BASE), FLASH_SIZE as usize, UC_PROT_ALL),
            )?;
            // Boot from main flash: aliased at 0 (RM0008 §3.4); a copy suffices, flash is read-only.
            check(
                "map alias",
                uc_mem_map(uc, 0, FLASH_SIZE as usize, UC_PROT_ALL),
            )?;
            check(
                "map sram",
                uc_mem_map_ptr(
                    uc,
                    u64::from(SRAM_BASE),
                    SRAM_SIZE as usize,
                    UC_PROT_ALL,
                    sram_ptr.cast(),
                ),
            )?;
            // Peripherals and system: the offset passed to the callbacks is made absolute
            // by mapping each region at its base and adding the base back (`region` fns).
            for &(base, size) in &[(0x4000_0000u64, 0x3_0000usize), (0xE000_0000, 0x10_0000)] {
                let (r, w): (MmioRead, MmioWrite) = if base == 0x4000_0000 {
                    (read_apb, write_apb)
                } else {
                    (read_sys, write_sys)
                };
                check("mmio", uc_mmio_map(uc, base, size, r, ud, w, ud))?;
            }
            // Bit-band aliases (Cortex-M3 TRM §3.7, RM0008 §2.3.2): a word per bit of
            // the peripheral and SRAM regions.
            check(
                "bitband periph",
                uc_mmio_map(
                    uc,
                    0x4200_0000,
                    0x200_0000,
                    read_bb_periph,
                    ud,
                    write_bb_periph,
                    ud,
                ),
            )?;
            check(
                "bitband sram",
                uc_mmio_map(
                    uc,
                    0x2200_0000,
                    0x200_0000,
                    read_bb_sram,
                    ud,
                    write_bb_sram,
                    ud,
                ),
            )?;
            let mut h: uc_hook = 0;
            check(
                "hook block",
                uc_hook_add(uc, &mut h, UC_HOOK_BLOCK, on_block as *mut c_void, ud, 1, 0),
            )?;
            check(
                "hook intr",
                uc_hook_add(uc, &mut h, UC_HOOK_INTR, on_intr as *mut c_void, ud, 1, 0),
            )?;
            check(
                "hook unmapped",
                uc_hook_add(
                    uc,
                    &mut h,
                    UC_HOOK_MEM_UNMAPPED,
                    on_unmapped as *mut c_void,
                    ud,
                    1,
                    0,
                ),
            )?;
        }
        let mut mcu = Mcu {
            name: name.to_string(),
            uc,
            st,
            image,
            rtt,
            sram,
        };
        mcu.reset()?;
        Ok(mcu)
    }

    /// Records every store into `[addr, addr + len)` in `State::writes` (time, PC,
    /// value). For diagnostics: a memory hook sends every access of the MCU through
    /// Unicorn's slow path.
    pub fn watch_writes(&mut self, addr: u32, len: u32) -> Result<(), EmuError> {
        let ud: *mut c_void = (&mut *self.st as *mut State).cast();
        let mut h: uc_hook = 0;
        let end = u64::from(addr) + u64::from(len.max(1)) - 1;
        // SAFETY: live engine; `st` is boxed and outlives the engine (see `new`).
        unsafe {
            check(
                "hook write",
                uc_hook_add(
                    self.uc,
                    &mut h,
                    UC_HOOK_MEM_WRITE,
                    on_write as *mut c_void,
                    ud,
                    u64::from(addr),
                    end,
                ),
            )
        }
    }

    /// Records every exception entry from now on (`State::entries`; diagnostics).
    pub fn trace_exceptions(&mut self) {
        self.st.entries.get_or_insert_with(Vec::new);
    }

    /// Program counter.
    pub fn pc(&self) -> u32 {
        self.reg(REG_PC)
    }

    fn reg(&self, r: i32) -> u32 {
        let mut v: u32 = 0;
        // SAFETY: live engine, valid out-pointer.
        unsafe { uc_reg_read(self.uc, r, (&mut v as *mut u32).cast()) };
        v
    }

    fn set_reg(&mut self, r: i32, v: u32) {
        // SAFETY: live engine, valid in-pointer.
        unsafe { uc_reg_write(self.uc, r, (&v as *const u32).cast()) };
    }

    fn mem_read_u32(&self, addr: u32) -> u32 {
        let mut b = [0u8; 4];
        self.st.read_into(addr, &mut b);
        u32::from_le_bytes(b)
    }

    /// Reads emulated memory (unmapped bytes read as 0).
    pub fn read_mem(&self, addr: u32, len: usize) -> Vec<u8> {
        let mut b = vec![0u8; len];
        self.st.read_into(addr, &mut b);
        b
    }

    /// Writes emulated memory (RAM).
    pub fn write_mem(&mut self, addr: u32, bytes: &[u8]) {
        self.st.write_from(addr, bytes);
    }

    /// One byte arriving on USART1's RX pin (its stop bit ends now): with CR3.DMAR it
    /// goes to DMA1 channel 5 and from there to memory (RM0008 §27.3.13, §13.3.7),
    /// else into RDR. A receiver that is off (or not clocked) loses it.
    pub fn usart_receive(&mut self, byte: u8) {
        let st = &mut self.st;
        if st.rcc.apb2enr & (1 << 14) == 0 || !st.usart1.receiving() {
            st.usart1.rx_lost += 1;
            return;
        }
        if st.usart1.rx_dma() {
            // A DMA that is off or not clocked leaves the request pending: the byte sits
            // in RDR (and the next one overruns), as on the chip.
            let served = if st.rcc.ahbenr & 1 != 0 {
                st.dma1.request(4, USART1_DR)
            } else {
                None
            };
            if let Some(addr) = served {
                self.write_mem(addr, &[byte]);
                return;
            }
        }
        self.st.usart1.rx_byte(byte);
    }

    /// Power-on / system reset (ARMv7-M B1.5.5): peripherals to reset values, image in
    /// flash, SRAM cleared, SP and PC from the vector table at 0. Time goes on.
    pub fn reset(&mut self) -> Result<(), EmuError> {
        let now = self.st.now();
        let st = &mut self.st;
        st.resets += 1;
        st.scs = Scs::default();
        st.rcc = Rcc::default();
        st.flash = Flash::default();
        st.gpio = Default::default();
        st.afio = Afio::default();
        st.exti = Exti::default();
        st.tim = [Tim2::new(), Tim2::new(), Tim2::new()];
        st.adc1 = Adc::new();
        st.can = BxCan::default();
        st.iwdg = Iwdg::new();
        st.usart1 = Usart::default();
        st.dma1 = Dma::default();
        // The core restarts awake, with no exception in progress.
        st.wfi = false;
        st.exc_return = false;
        st.base_ps = now;
        st.base_instr = st.instructions;
        st.retime();
        // SAFETY: `st.sram` is this MCU's SRAM_SIZE-byte buffer (`Mcu::sram`).
        unsafe { core::ptr::write_bytes(self.st.sram, 0, SRAM_SIZE as usize) };
        // SAFETY: live engine; buffers are valid for their lengths.
        unsafe {
            for seg in &self.image {
                check(
                    "load",
                    uc_mem_write(
                        self.uc,
                        u64::from(seg.addr),
                        seg.bytes.as_ptr().cast(),
                        seg.bytes.len(),
                    ),
                )?;
                if seg.addr >= FLASH_BASE && seg.addr < FLASH_BASE + FLASH_SIZE {
                    let alias = u64::from(seg.addr - FLASH_BASE);
                    check(
                        "load alias",
                        uc_mem_write(self.uc, alias, seg.bytes.as_ptr().cast(), seg.bytes.len()),
                    )?;
                }
            }
        }
        let sp = self.mem_read_u32(0);
        let pc = self.mem_read_u32(4);
        self.set_reg(REG_SP, sp);
        self.set_reg(REG_PC, pc & !1);
        self.set_reg(REG_PRIMASK, 0);
        self.set_reg(REG_BASEPRI, 0);
        self.set_reg(REG_LR, 0xFFFF_FFFF);
        Ok(())
    }

    /// Emulated time now (ps).
    pub fn now(&self) -> u64 {
        self.st.now()
    }

    /// `State::raise_irqs`.
    fn raise_irqs(&mut self) {
        self.st.raise_irqs();
    }

    /// `State::exc_return`.
    fn exc_return(&mut self) {
        self.st.exc_return();
    }

    /// `State::take_pending`.
    fn take_pending(&mut self) -> bool {
        self.st.take_pending()
    }

    /// The next time (ps) a peripheral changes an interrupt line by itself.
    pub fn next_event(&self) -> Option<u64> {
        self.st.next_event()
    }

    /// Runs until emulated time `until` (ps), or a fault.
    pub fn run_until(&mut self, until: u64) -> Result<(), String> {
        while self.st.now() < until {
            if let Some(f) = &self.st.fault {
                return Err(f.clone());
            }
            if self.st.stop_on_txrq && self.st.txrq_at.is_some() {
                return Ok(());
            }
            if self.st.iwdg.deadline.is_some_and(|d| d <= self.st.now())
                || self.st.scs.reset_request
            {
                self.reset().map_err(|e| format!("{e:?}"))?;
                continue;
            }
            self.raise_irqs();
            self.take_pending();
            if self.st.wfi {
                let next = self
                    .next_event()
                    .unwrap_or(until)
                    .min(until)
                    .max(self.st.now() + 1);
                let now = self.st.now();
                self.st.add_time(next - now);
                self.st.asleep_ps += next - now;
                continue;
            }
            self.st.plan_run(until);
            let pc = self.reg(REG_PC);
            // `until` = 0, an address no image executes (the vector table's initial SP):
            // at the end of every run Unicorn 2.0.1 invalidates the translated code around
            // the `until` address unless it is 0 (`resume_all_vcpus`), which costs a page
            // collection (a GTree, malloc/free) per run; malloc/free were ≈ 9 % of a
            // perf profile with 0xFFFF_FFFF, part of it from here. A run that does reach
            // address 0 is reported as a fault below.
            // SAFETY: live engine.
            let e = unsafe { uc_emu_start(self.uc, u64::from(pc | 1), 0, 0, 0) };
            // The last block ran to its end unless the hook stopped the run (then
            // `block_n` is 0): count it.
            self.st.block_done();
            self.st.unmask_end = false;
            if let Some(after) = self.st.wfi_end.take() {
                if e == 0 && self.reg(REG_PC) & !1 == after & !1 {
                    self.st.wfi = true;
                }
            }
            let sl = &mut self.st.slices;
            if self.st.exc_return {
                sl.exc_return += 1;
            } else if self.st.wfi {
                sl.sleep += 1;
            } else if self.st.instructions >= self.st.budget {
                match self.st.budget_why {
                    Why::Event => sl.event += 1,
                    Why::Until => sl.until += 1,
                    Why::Chunk => sl.chunk += 1,
                    Why::Unmask => sl.unmask += 1,
                    Why::Replan => sl.replan += 1,
                }
            } else {
                sl.other += 1;
            }
            if let Some(pc) = self.st.resume_pc.take() {
                self.set_reg(REG_PC, pc & !1);
            }
            if self.st.exc_return {
                self.st.exc_return = false;
                self.exc_return();
                continue;
            }
            if let Some(f) = &self.st.fault {
                return Err(format!("{}: {f}", self.name));
            }
            // A branch to address 0 (the `until` above): Unicorn halted before executing
            // there. The chip would fetch the initial SP as an instruction; no image does it.
            if e == 0 && !self.st.wfi && self.reg(REG_PC) & !1 == 0 {
                return Err(format!(
                    "{}: branch to address 0 after {} instructions",
                    self.name, self.st.instructions
                ));
            }
            if e != 0 && !self.st.wfi {
                let pc = self.reg(REG_PC);
                return Err(format!(
                    "{}: CPU fault {e} at pc {pc:#010x} after {} instructions",
                    self.name, self.st.instructions
                ));
            }
        }
        Ok(())
    }
}

/// EPSR.IT of the xPSR: bits 26:25 and 15:10 (ARMv7-M B1.4.2).
const XPSR_IT: u32 = 0x0600_FC00;

/// Exception entry and return, here rather than on `Mcu` so that `on_intr` can do an
/// exception return inside a run (`State::return_in_run`).
impl State {
    /// The instruction budget of the next run, from now towards `until` (ps): up to the
    /// next peripheral event, at most `CHUNK` instructions.
    fn plan_run(&mut self, until: u64) {
        const CHUNK: u64 = 2_000;
        self.run_end = until;
        let event = self.next_event().filter(|&e| e < until);
        let horizon = event.unwrap_or(until);
        let left = horizon.saturating_sub(self.now());
        let n = (left as f64 / self.instr_ps.max(1.0)) as u64;
        self.budget_why = match event {
            _ if n > CHUNK => Why::Chunk,
            Some(_) => Why::Event,
            None => Why::Until,
        };
        // n instructions execute, rounded up to the end of the block that reaches them:
        // the hook of the block after it ends the run.
        self.budget = self.instructions + n.clamp(1, CHUNK);
        self.scs.reschedule = false;
    }

    /// An exception return met inside a run (`on_intr`): done there, and the run goes
    /// on, when `run_until` would start the next run straight after it (no sleep, no
    /// reset, no end of the caller's time, no transmit request the bus waits for). It
    /// does what the loop does between the two runs — the return, the interrupt lines,
    /// tail-chaining into a pending exception, the next budget — at the same emulated
    /// time, so timing is unchanged; what it saves is ending and restarting a Unicorn
    /// run (about a third of all runs ended at an exception return). Returns false, with
    /// nothing done, when the loop must act.
    fn return_in_run(&mut self) -> bool {
        let after = self.now() + self.cycles_ps(self.timing.exception_cycles);
        let loop_needed = after >= self.run_end
            || self.fault.is_some()
            || self.wfi
            || self.resume_pc.is_some()
            || (self.stop_on_txrq && self.txrq_at.is_some())
            || self.scs.reset_request
            || self.iwdg.deadline.is_some_and(|d| d <= after)
            // Sleep-on-exit after the last active exception.
            || (self.scs.active.len() <= 1 && self.scs.sleep_on_exit());
        if loop_needed {
            return false;
        }
        // The PC writes below restart Unicorn's translation loop at the new PC (it sets
        // `quit_request`), which is what a return inside the run needs.
        self.exc_return();
        self.raise_irqs();
        self.take_pending();
        self.plan_run(self.run_end);
        true
    }

    /// A pending exception after an unmask, met by the block hook at the start of the
    /// block at `pc` (nothing of it has run): taken there inside the run when the loop
    /// would only take it and start the next run — what it does between two runs, at
    /// the same emulated time. Some(true): entered (the PC write makes Unicorn restart
    /// at the vector; with a PC write pending, it does not put the PC back to the
    /// block's start). Some(false): nothing can be taken at the current priority, the
    /// run goes on. None: the loop must act (a fault, a reset, the watchdog, a transmit
    /// request the bus waits for).
    fn enter_in_run(&mut self, pc: u32) -> Option<bool> {
        let loop_needed = self.fault.is_some()
            || (self.stop_on_txrq && self.txrq_at.is_some())
            || self.scs.reset_request
            || self.iwdg.deadline.is_some_and(|d| d <= self.now());
        if loop_needed {
            return None;
        }
        let exec = self.execution_priority();
        if self.scs.next_exception(exec).is_none() {
            return Some(false);
        }
        // The block's start is the return address (stacked by `enter`).
        self.set_reg(REG_PC, pc | 1);
        self.take_pending();
        self.plan_run(self.run_end);
        Some(true)
    }

    fn set_reg(&mut self, r: i32, v: u32) {
        // SAFETY: live engine, valid in-pointer.
        unsafe { uc_reg_write(self.uc, r, (&v as *const u32).cast()) };
    }

    fn read_u32(&self, addr: u32) -> u32 {
        let mut b = [0u8; 4];
        self.read_into(addr, &mut b);
        u32::from_le_bytes(b)
    }

    /// Interrupt lines of the peripherals into the NVIC (`State::raise_lines`), and the
    /// core's state for the slot probe when TIM2's line rose.
    fn raise_irqs(&mut self) {
        let core = (
            self.reg(REG_PC),
            self.reg(REG_PRIMASK) & 1 != 0,
            self.reg(REG_BASEPRI) as u8,
        );
        self.raise_lines();
        let active = self.scs.active.last().copied().unwrap_or(0);
        self.probe.core_at_rise(core.0, core.1, core.2, active);
    }

    /// Exception entry (ARMv7-M B1.5.6): stacks R0-R3, R12, LR, return address, xPSR on
    /// the main stack (8-byte aligned, bit 9 of the stacked xPSR records the padding),
    /// LR = EXC_RETURN, PC = vector.
    fn enter(&mut self, exc: u16) {
        let mut sp = self.reg(REG_SP);
        let mut xpsr = self.reg(REG_XPSR);
        let pc = self.reg(REG_PC);
        let frame = [
            self.reg(REG_R0),
            self.reg(REG_R0 + 1),
            self.reg(REG_R0 + 2),
            self.reg(REG_R0 + 3),
            self.reg(REG_R12),
            self.reg(REG_LR),
            pc,
        ];
        if sp & 4 != 0 {
            sp -= 4;
            xpsr |= 1 << 9;
        } else {
            xpsr &= !(1 << 9);
        }
        sp -= 32;
        // One write of the whole frame, straight into SRAM (`State::write_from`).
        let mut bytes = [0u8; 32];
        for (chunk, v) in bytes
            .chunks_exact_mut(4)
            .zip(frame.iter().copied().chain([xpsr | (1 << 24)]))
        {
            chunk.copy_from_slice(&v.to_le_bytes());
        }
        self.write_from(sp, &bytes);
        self.set_reg(REG_SP, sp);
        // The handler starts outside any IT block (B1.5.6: EPSR.IT cleared on entry; the
        // stacked xPSR keeps them for the return). A run can end between two blocks of
        // an IT block (QEMU ends a block at a 1 KiB page boundary), and Unicorn keeps
        // the IT state across the PC write: left set, it would make the handler's first
        // instructions conditional. The exception number stays 0 (see `return_in_run`).
        self.set_reg(REG_XPSR, xpsr & !(XPSR_IT | 0x1FF));
        // Return to thread mode on the main stack, or to handler mode when nested.
        let exc_return = if self.scs.active.is_empty() {
            0xFFFF_FFF9
        } else {
            0xFFFF_FFF1
        };
        self.set_reg(REG_LR, exc_return);
        let vector = self.read_u32(self.scs.vtor + 4 * u32::from(exc));
        // Bit 0 set: Thumb (a PC write also sets Unicorn's Thumb state, see `return_in_run`).
        self.set_reg(REG_PC, vector | 1);
        self.scs.activate(exc);
        *self.taken.entry(exc).or_insert(0) += 1;
        let now = self.now();
        if let Some(e) = self.entries.as_mut() {
            e.push((now, exc));
        }
        let ps = self.cycles_ps(self.timing.exception_cycles);
        self.add_time(ps);
    }

    fn cycles_ps(&self, cycles: u64) -> u64 {
        cycles * PS / self.rcc.hclk().max(1)
    }

    /// Exception return (B1.5.8): unstacks the frame and ends the active exception.
    fn exc_return(&mut self) {
        let sp = self.reg(REG_SP);
        let mut bytes = [0u8; 32];
        self.read_into(sp, &mut bytes);
        let get = |i: usize| {
            bytes
                .get(4 * i..4 * i + 4)
                .and_then(|b| b.try_into().ok())
                .map_or(0, u32::from_le_bytes)
        };
        for (i, r) in [REG_R0, REG_R0 + 1, REG_R0 + 2, REG_R0 + 3, REG_R12, REG_LR]
            .iter()
            .enumerate()
        {
            self.set_reg(*r, get(i));
        }
        self.set_reg(REG_PC, get(6) | 1);
        let xpsr = get(7);
        self.set_reg(REG_XPSR, xpsr & !0x1FF);
        let pad = if xpsr & (1 << 9) != 0 { 4 } else { 0 };
        self.set_reg(REG_SP, sp + 32 + pad);
        self.scs.deactivate();
        if !self.scs.active.contains(&crate::probe::EXC_TIM2) {
            self.probe.timer_isr_done();
        }
        let ps = self.cycles_ps(self.timing.exception_cycles);
        self.add_time(ps);
        if self.scs.active.is_empty() && self.scs.sleep_on_exit() {
            self.wfi = true;
        }
    }

    fn take_pending(&mut self) -> bool {
        let exec = self.execution_priority();
        if let Some(exc) = self.scs.next_exception(exec) {
            self.wfi = false;
            self.enter(exc);
            return true;
        }
        // WFI wakes on any pending interrupt even when masked by PRIMASK (B1.5.19).
        if self.wfi && self.scs.next_exception(256).is_some() {
            self.wfi = false;
        }
        false
    }
}

extern "C" fn read_apb(uc: *mut uc_engine, off: u64, size: u32, ud: *mut c_void) -> u64 {
    mmio_read(uc, off + 0x4000_0000, size, ud)
}
extern "C" fn write_apb(uc: *mut uc_engine, off: u64, size: u32, v: u64, ud: *mut c_void) {
    mmio_write(uc, off + 0x4000_0000, size, v, ud)
}
extern "C" fn read_sys(uc: *mut uc_engine, off: u64, size: u32, ud: *mut c_void) -> u64 {
    mmio_read(uc, off + 0xE000_0000, size, ud)
}
extern "C" fn write_sys(uc: *mut uc_engine, off: u64, size: u32, v: u64, ud: *mut c_void) {
    mmio_write(uc, off + 0xE000_0000, size, v, ud)
}

/// Bit-band alias word `off` → (word address, bit) in the region at `base`.
fn bitband(base: u32, off: u64) -> (u32, u32) {
    let byte = (off / 32) as u32;
    let bit = ((off % 32) / 4) as u32 + 8 * (byte & 3);
    (base + (byte & !3), bit)
}

extern "C" fn read_bb_periph(_uc: *mut uc_engine, off: u64, _size: u32, ud: *mut c_void) -> u64 {
    // SAFETY: as in `mmio_read`.
    let st = unsafe { &mut *ud.cast::<State>() };
    let (addr, bit) = bitband(0x4000_0000, off);
    st.locate(false, 4, 0x4200_0000 + off as u32);
    match st.read(addr, 4) {
        Ok(v) => u64::from((v >> bit) & 1),
        Err(a) => {
            st.unknown_access(a, false);
            0
        }
    }
}

extern "C" fn write_bb_periph(_uc: *mut uc_engine, off: u64, _size: u32, v: u64, ud: *mut c_void) {
    // SAFETY: as in `mmio_read`.
    let st = unsafe { &mut *ud.cast::<State>() };
    let (addr, bit) = bitband(0x4000_0000, off);
    st.locate(true, 4, 0x4200_0000 + off as u32);
    let r = st.read(addr, 4).and_then(|old| {
        let new = if v & 1 != 0 {
            old | (1 << bit)
        } else {
            old & !(1 << bit)
        };
        st.write(addr, 4, new)
    });
    if let Err(a) = r {
        st.unknown_access(a, true);
    }
}

extern "C" fn read_bb_sram(_uc: *mut uc_engine, off: u64, _size: u32, ud: *mut c_void) -> u64 {
    // SAFETY: as in `mmio_read`.
    let st = unsafe { &mut *ud.cast::<State>() };
    let (addr, bit) = bitband(SRAM_BASE, off);
    st.locate(false, 4, 0x2200_0000 + off as u32);
    let mut b = [0u8; 4];
    st.read_into(addr, &mut b);
    u64::from((u32::from_le_bytes(b) >> bit) & 1)
}

extern "C" fn write_bb_sram(_uc: *mut uc_engine, off: u64, _size: u32, v: u64, ud: *mut c_void) {
    // SAFETY: as in `mmio_read`.
    let st = unsafe { &mut *ud.cast::<State>() };
    let (addr, bit) = bitband(SRAM_BASE, off);
    st.locate(true, 4, 0x2200_0000 + off as u32);
    let mut b = [0u8; 4];
    st.read_into(addr, &mut b);
    let old = u32::from_le_bytes(b);
    let new = if v & 1 != 0 {
        old | (1 << bit)
    } else {
        old & !(1 << bit)
    };
    st.write_from(addr, &new.to_le_bytes());
}

#[cfg(test)]
#[path = "mcu_tests.rs"]
mod tests;
