//! System control space of the Cortex-M3 (ARMv7-M ARM B3.2–B3.4, Cortex-M3 TRM §4 and §8):
//! NVIC, SCB, SysTick and DWT CYCCNT. Unicorn executes instructions but has no NVIC, so
//! pending/active state, priorities and the choice of the next exception live here; the
//! exception entry and return themselves are done by `cpu.rs` on this state.
use crate::Access;

/// External interrupt lines of the STM32F103 (RM0008 §10.1.2, table 63: 60 lines for
/// the connectivity line, 43 used on the performance line; the NVIC registers cover 64).
pub const IRQ_LINES: usize = 64;
/// Exception numbers: IRQ n is exception 16 + n.
pub const EXC_SYSTICK: u16 = 15;
pub const EXC_PENDSV: u16 = 14;
pub const EXC_SVCALL: u16 = 11;
pub const EXC_HARDFAULT: u16 = 3;
/// Priority bits implemented by the STM32F103 (RM0008 §10.1.1: 16 levels, the upper
/// four bits of each 8-bit priority field).
pub const PRIO_MASK: u8 = 0xF0;

/// SCS state: NVIC (B3.4), SCB (B3.2.2), SysTick (B3.3), DWT CYCCNT (C1.8).
#[derive(Clone, Debug)]
pub struct Scs {
    enabled: [bool; IRQ_LINES],
    pending: [bool; IRQ_LINES],
    /// NVIC_IPRn byte per IRQ (masked to the implemented bits).
    irq_prio: [u8; IRQ_LINES],
    /// SHPR1..3: priorities of system exceptions 4..15 (index exception - 4).
    sys_prio: [u8; 12],
    pendsv: bool,
    systick_pending: bool,
    /// Active exceptions, innermost last.
    pub active: Vec<u16>,
    pub vtor: u32,
    /// AIRCR.PRIGROUP (B3.2.6).
    prigroup: u8,
    scr: u32,
    ccr: u32,
    // SysTick (B3.3.2): CSR, RVR, CVR, counted lazily from CPU cycles.
    st_ctrl: u32,
    st_reload: u32,
    st_current: u32,
    /// CPU cycle at which `st_current` was last brought up to date.
    st_synced: u64,
    demcr: u32,
    dwt_ctrl: u32,
    /// CYCCNT is `cycles - cyccnt_base` while enabled.
    cyccnt_base: u64,
    cyccnt_frozen: u32,
    /// A software request that may let an exception in now (STIR/ISPR/ICSR writes).
    pub reschedule: bool,
    /// AIRCR.SYSRESETREQ written (B3.2.6).
    pub reset_request: bool,
}

impl Default for Scs {
    fn default() -> Self {
        Scs {
            enabled: [false; IRQ_LINES],
            pending: [false; IRQ_LINES],
            irq_prio: [0; IRQ_LINES],
            sys_prio: [0; 12],
            pendsv: false,
            systick_pending: false,
            active: Vec::new(),
            vtor: 0,
            prigroup: 0,
            scr: 0,
            ccr: 0x200,
            st_ctrl: 0,
            st_reload: 0,
            st_current: 0,
            st_synced: 0,
            demcr: 0,
            dwt_ctrl: 0x4000_0000,
            cyccnt_base: 0,
            cyccnt_frozen: 0,
            reschedule: false,
            reset_request: false,
        }
    }
}

impl Scs {
    /// Sets IRQ `n` pending (a peripheral's interrupt line went active).
    pub fn set_pending(&mut self, irq: usize) {
        if let Some(p) = self.pending.get_mut(irq) {
            *p = true;
        }
    }

    /// Whether any exception is pending and enabled (whatever its priority): the only
    /// case in which unmasking can let one in.
    pub fn any_pending(&self) -> bool {
        self.pendsv
            || self.systick_pending
            || self
                .pending
                .iter()
                .zip(&self.enabled)
                .any(|(&p, &e)| p && e)
    }

    /// Whether IRQ `n` is pending.
    pub fn is_pending(&self, irq: usize) -> bool {
        self.pending.get(irq).copied().unwrap_or(false)
    }

    /// Priority of exception `exc` (B1.5.4): Reset -3, NMI -2, HardFault -1, others
    /// programmable. Returned as i16 so the fixed ones sort first.
    pub fn priority(&self, exc: u16) -> i16 {
        match exc {
            1 => -3,
            2 => -2,
            3 => -1,
            4..=15 => i16::from(
                self.sys_prio
                    .get(usize::from(exc) - 4)
                    .copied()
                    .unwrap_or(0),
            ),
            _ => i16::from(
                self.irq_prio
                    .get(usize::from(exc) - 16)
                    .copied()
                    .unwrap_or(0),
            ),
        }
    }

    /// Group priority (B1.5.4: the bits above PRIGROUP+1 preempt, the rest only order).
    fn group(&self, prio: i16) -> i16 {
        if prio < 0 {
            return prio;
        }
        let sub_bits = u32::from(self.prigroup) + 1;
        (prio >> sub_bits) << sub_bits
    }

    /// Execution priority (B1.5.4): the highest of the active exceptions' group priorities,
    /// BASEPRI and PRIMASK (0) / FAULTMASK (-1). 256 means thread mode, unmasked.
    pub fn execution_priority(&self, primask: bool, faultmask: bool, basepri: u8) -> i16 {
        let mut p: i16 = 256;
        for &e in &self.active {
            p = p.min(self.group(self.priority(e)));
        }
        let bp = basepri & PRIO_MASK;
        if bp != 0 {
            p = p.min(self.group(i16::from(bp)));
        }
        if primask {
            p = p.min(0);
        }
        if faultmask {
            p = p.min(-1);
        }
        p
    }

    /// The pending exception that preempts at execution priority `exec` (B1.5.4: lower
    /// group priority value wins; equal priority, lower exception number wins).
    pub fn next_exception(&self, exec: i16) -> Option<u16> {
        let mut best: Option<(i16, u16)> = None;
        let mut consider = |exc: u16, prio: i16| {
            if self.group(prio) < exec && best.is_none_or(|(bp, _)| prio < bp) {
                best = Some((prio, exc));
            }
        };
        if self.pendsv {
            consider(EXC_PENDSV, self.priority(EXC_PENDSV));
        }
        if self.systick_pending {
            consider(EXC_SYSTICK, self.priority(EXC_SYSTICK));
        }
        for irq in 0..IRQ_LINES {
            if self.pending.get(irq) == Some(&true) && self.enabled.get(irq) == Some(&true) {
                let exc = 16 + irq as u16;
                consider(exc, self.priority(exc));
            }
        }
        best.map(|(_, e)| e)
    }

    /// Exception entry bookkeeping (B1.5.6): clears pending, marks active.
    pub fn activate(&mut self, exc: u16) {
        match exc {
            EXC_PENDSV => self.pendsv = false,
            EXC_SYSTICK => self.systick_pending = false,
            e if e >= 16 => {
                if let Some(p) = self.pending.get_mut(usize::from(e) - 16) {
                    *p = false;
                }
            }
            _ => {}
        }
        self.active.push(exc);
    }

    /// Exception return bookkeeping (B1.5.8): the innermost active exception ends.
    pub fn deactivate(&mut self) -> Option<u16> {
        self.active.pop()
    }

    /// SysTick clock source cycles per CPU cycle: CSR.CLKSOURCE=1 is the processor clock,
    /// 0 the external reference HCLK/8 on the STM32F103 (RM0008 §7.2, figure 8).
    fn systick_divider(&self) -> u64 {
        if self.st_ctrl & 4 != 0 {
            1
        } else {
            8
        }
    }

    /// Brings SysTick up to CPU cycle `now`; sets COUNTFLAG and pends the exception on
    /// wrap (B3.3.1). Returns true when its exception became pending.
    pub fn sync_systick(&mut self, now: u64) -> bool {
        let div = self.systick_divider();
        if self.st_ctrl & 1 == 0 {
            self.st_synced = now;
            return false;
        }
        let mut t = now.saturating_sub(self.st_synced) / div;
        if t == 0 {
            return false;
        }
        self.st_synced += t * div;
        let rel = u64::from(self.st_reload);
        let mut cur = u64::from(self.st_current);
        if cur == 0 {
            // The tick after 0 loads RVR (B3.3.1); RVR 0 disables the counter.
            if rel == 0 {
                return false;
            }
            t -= 1;
            cur = rel;
        }
        if t < cur {
            self.st_current = (cur - t) as u32;
            return false;
        }
        // Reached 0 at least once: COUNTFLAG, and the exception if TICKINT.
        let rem = (t - cur) % (rel + 1);
        self.st_current = if rem == 0 { 0 } else { (rel + 1 - rem) as u32 };
        self.st_ctrl |= 1 << 16;
        if self.st_ctrl & 2 != 0 {
            self.systick_pending = true;
            return true;
        }
        false
    }

    /// CPU cycles until SysTick next reaches 0 (None if stopped or not interrupting).
    pub fn systick_due_in(&self) -> Option<u64> {
        if self.st_ctrl & 3 != 3 {
            return None;
        }
        let cur = if self.st_current == 0 {
            u64::from(self.st_reload) + 1
        } else {
            u64::from(self.st_current)
        };
        Some(cur * self.systick_divider())
    }

    /// Register read at SCS offset `off` (0xE000_E000 + off), or at DWT/DCB addresses
    /// handled by `read_debug`.
    pub fn read(&mut self, off: u32, now: u64) -> Access {
        let irq_word = |set: &[bool; IRQ_LINES], base: u32| -> u32 {
            let first = ((off - base) / 4 * 32) as usize;
            (0..32).fold(0u32, |acc, b| {
                acc | (u32::from(set.get(first + b).copied().unwrap_or(false)) << b)
            })
        };
        Ok(match off {
            // SysTick CSR/RVR/CVR/CALIB (B3.3.3). Reading CSR clears COUNTFLAG.
            0x010 => {
                self.sync_systick(now);
                let v = self.st_ctrl;
                self.st_ctrl &= !(1 << 16);
                v
            }
            0x014 => self.st_reload,
            0x018 => {
                self.sync_systick(now);
                self.st_current
            }
            // CALIB: no reference calibration value (TENMS 0, SKEW, NOREF clear: 9000 for 1 ms at 9 MHz is RM0008's value).
            0x01C => 9000,
            // NVIC ISER/ICER (B3.4.4/5), ISPR/ICPR (B3.4.6/7), IABR (B3.4.8).
            0x100..=0x107 => irq_word(&self.enabled, 0x100),
            0x180..=0x187 => irq_word(&self.enabled, 0x180),
            0x200..=0x207 => irq_word(&self.pending, 0x200),
            0x280..=0x287 => irq_word(&self.pending, 0x280),
            0x300..=0x307 => {
                let mut act = [false; IRQ_LINES];
                for &e in &self.active {
                    if let Some(a) = act.get_mut(usize::from(e).saturating_sub(16)) {
                        *a = e >= 16;
                    }
                }
                irq_word(&act, 0x300)
            }
            // NVIC_IPR0..15 (B3.4.9), byte per IRQ.
            0x400..=0x43F => {
                let first = (off - 0x400) as usize;
                (0..4).fold(0u32, |acc, i| {
                    acc | u32::from(self.irq_prio.get(first + i).copied().unwrap_or(0)) << (8 * i)
                })
            }
            // CPUID (B3.2.3): Cortex-M3 r1p1 as on the STM32F103 (RM0008 refers to PM0056 §4.4.1).
            0xD00 => 0x411F_C231,
            0xD04 => self.icsr(),
            0xD08 => self.vtor,
            0xD0C => 0xFA05_0000 | (u32::from(self.prigroup) << 8),
            0xD10 => self.scr,
            0xD14 => self.ccr,
            0xD18..=0xD23 => {
                let first = (off - 0xD18) as usize;
                (0..4).fold(0u32, |acc, i| {
                    acc | u32::from(self.sys_prio.get(first + i).copied().unwrap_or(0)) << (8 * i)
                })
            }
            0xD24 => 0,                                         // SHCSR
            0xD28 | 0xD2C | 0xD30 | 0xD34 | 0xD38 | 0xD3C => 0, // fault status/address: no faults modelled
            0xDFC => self.demcr,
            _ => return Err(off),
        })
    }

    fn icsr(&self) -> u32 {
        let vectactive = u32::from(self.active.last().copied().unwrap_or(0));
        let pending = self.next_exception(256).map(u32::from).unwrap_or(0);
        vectactive
            | (pending << 12)
            | (u32::from(self.pending.iter().any(|&p| p)) << 22)
            | (u32::from(self.systick_pending) << 26)
            | (u32::from(self.pendsv) << 28)
    }

    /// Register write (see `read`).
    pub fn write(&mut self, off: u32, value: u32, size: u32, now: u64) -> Access {
        let bits_of = |base: u32| -> (usize, u32) { (((off - base) / 4 * 32) as usize, value) };
        match off {
            0x010 => {
                self.sync_systick(now);
                self.st_ctrl = (self.st_ctrl & (1 << 16)) | (value & 7);
                self.st_synced = now;
            }
            0x014 => self.st_reload = value & 0x00FF_FFFF,
            // Writing CVR clears it and COUNTFLAG (B3.3.5).
            0x018 => {
                self.st_current = 0;
                self.st_ctrl &= !(1 << 16);
                self.st_synced = now;
            }
            0x100..=0x107 | 0x180..=0x187 | 0x200..=0x207 | 0x280..=0x287 => {
                let (base, set, target): (u32, bool, u8) = match off {
                    0x100..=0x107 => (0x100, true, 0),
                    0x180..=0x187 => (0x180, false, 0),
                    0x200..=0x207 => (0x200, true, 1),
                    _ => (0x280, false, 1),
                };
                let (first, v) = bits_of(base);
                let arr = if target == 0 {
                    &mut self.enabled
                } else {
                    &mut self.pending
                };
                for b in 0..32 {
                    if v & (1 << b) != 0 {
                        if let Some(x) = arr.get_mut(first + b) {
                            *x = set;
                        }
                    }
                }
                self.reschedule = true;
            }
            0x400..=0x43F => {
                let first = (off - 0x400) as usize;
                for i in 0..(size as usize).min(4) {
                    if let Some(p) = self.irq_prio.get_mut(first + i) {
                        *p = (value >> (8 * i)) as u8 & PRIO_MASK;
                    }
                }
                self.reschedule = true;
            }
            // ICSR (B3.2.4): PENDSVSET 28, PENDSVCLR 27, PENDSTSET 26, PENDSTCLR 25.
            0xD04 => {
                if value & (1 << 28) != 0 {
                    self.pendsv = true;
                }
                if value & (1 << 27) != 0 {
                    self.pendsv = false;
                }
                if value & (1 << 26) != 0 {
                    self.systick_pending = true;
                }
                if value & (1 << 25) != 0 {
                    self.systick_pending = false;
                }
                self.reschedule = true;
            }
            0xD08 => self.vtor = value & 0xFFFF_FF80,
            // AIRCR (B3.2.6): writes need VECTKEY 0x05FA.
            0xD0C => {
                if value >> 16 == 0x05FA {
                    self.prigroup = ((value >> 8) & 7) as u8;
                    if value & 4 != 0 {
                        self.reset_request = true;
                    }
                }
            }
            0xD10 => self.scr = value & 0x16,
            0xD14 => self.ccr = value & 0x31B,
            0xD18..=0xD23 => {
                let first = (off - 0xD18) as usize;
                for i in 0..(size as usize).min(4) {
                    if let Some(p) = self.sys_prio.get_mut(first + i) {
                        *p = (value >> (8 * i)) as u8 & PRIO_MASK;
                    }
                }
                self.reschedule = true;
            }
            0xD24 | 0xD28 | 0xD2C | 0xD30 => {}
            0xDFC => self.demcr = value,
            // STIR (B3.4.10).
            0xF00 => {
                self.set_pending((value & 0x1FF) as usize);
                self.reschedule = true;
            }
            _ => return Err(off),
        }
        Ok(0)
    }

    /// DWT (0xE000_1000 + off, ARMv7-M C1.8): CTRL and CYCCNT only.
    pub fn read_dwt(&self, off: u32, now: u64) -> Access {
        match off {
            0x000 => Ok(self.dwt_ctrl),
            0x004 => Ok(self.cyccnt(now)),
            _ => Err(off),
        }
    }

    fn cyccnt(&self, now: u64) -> u32 {
        if self.dwt_ctrl & 1 != 0 {
            now.wrapping_sub(self.cyccnt_base) as u32
        } else {
            self.cyccnt_frozen
        }
    }

    pub fn write_dwt(&mut self, off: u32, value: u32, now: u64) -> Access {
        match off {
            0x000 => {
                let frozen = self.cyccnt(now);
                self.dwt_ctrl = (self.dwt_ctrl & 0xF000_0000) | (value & 0x0FFF_FFFF);
                self.cyccnt_frozen = frozen;
                self.cyccnt_base = now.wrapping_sub(u64::from(frozen));
            }
            0x004 => {
                self.cyccnt_frozen = value;
                self.cyccnt_base = now.wrapping_sub(u64::from(value));
            }
            _ => return Err(off),
        }
        Ok(0)
    }

    /// SCR.SLEEPONEXIT (B3.2.7): return from the last handler to thread mode sleeps.
    pub fn sleep_on_exit(&self) -> bool {
        self.scr & 2 != 0
    }
}

#[cfg(test)]
#[path = "scs_tests.rs"]
mod tests;
