//! STM32F103 peripherals other than bxCAN (RM0008), each register cited to its section.
//! Time is in picoseconds of emulated time (`now`); clocks come from `Rcc`.
use crate::Access;

/// Picoseconds per second.
pub const PS: u64 = 1_000_000_000_000;
/// HSI and the board's HSE crystal (8 MHz, RM0008 §7.2).
pub const HSI_HZ: u64 = 8_000_000;
pub const HSE_HZ: u64 = 8_000_000;

/// Reset and clock control (RM0008 §7.3).
#[derive(Clone, Debug)]
pub struct Rcc {
    cr: u32,
    cfgr: u32,
    cir: u32,
    apb2rstr: u32,
    apb1rstr: u32,
    pub ahbenr: u32,
    pub apb2enr: u32,
    pub apb1enr: u32,
    bdcr: u32,
    csr: u32,
    /// Fault injection: the crystal never starts (HSERDY stays 0).
    pub hse_dead: bool,
}

impl Default for Rcc {
    fn default() -> Self {
        Rcc {
            cr: 0x0000_0083,
            cfgr: 0,
            cir: 0,
            apb2rstr: 0,
            apb1rstr: 0,
            ahbenr: 0x14,
            apb2enr: 0,
            apb1enr: 0,
            bdcr: 0,
            csr: 0x0C00_0000,
            hse_dead: false,
        }
    }
}

/// APB1ENR bits (§7.3.8): TIM2EN 0, CANEN 25, PWREN 28, BKPEN 27.
pub const APB1_TIM2: u32 = 1;
pub const APB1_CAN: u32 = 1 << 25;

impl Rcc {
    /// SYSCLK in Hz from SWS and the PLL configuration (§7.2, figure 8).
    pub fn sysclk(&self) -> u64 {
        match (self.cfgr >> 2) & 3 {
            1 => HSE_HZ,
            2 => {
                let src = if self.cfgr & (1 << 16) == 0 {
                    HSI_HZ / 2
                } else if self.cfgr & (1 << 17) != 0 {
                    HSE_HZ / 2
                } else {
                    HSE_HZ
                };
                let mul = u64::from(((self.cfgr >> 18) & 0xF) + 2).min(16);
                src * mul
            }
            _ => HSI_HZ,
        }
    }

    /// HCLK (AHB prescaler HPRE, §7.3.2).
    pub fn hclk(&self) -> u64 {
        let hpre = (self.cfgr >> 4) & 0xF;
        let div = if hpre < 8 {
            1
        } else {
            [2, 4, 8, 16, 64, 128, 256, 512]
                .get((hpre - 8) as usize)
                .copied()
                .unwrap_or(1)
        };
        self.sysclk() / div
    }

    fn apb_div(bits: u32) -> u64 {
        if bits < 4 {
            1
        } else {
            1 << (bits - 3)
        }
    }

    /// PCLK1 (PPRE1, §7.3.2).
    pub fn pclk1(&self) -> u64 {
        self.hclk() / Self::apb_div((self.cfgr >> 8) & 7)
    }

    /// PCLK2 (PPRE2, §7.3.2): USART1's clock.
    pub fn pclk2(&self) -> u64 {
        self.hclk() / Self::apb_div((self.cfgr >> 11) & 7)
    }

    /// TIM2 clock: PCLK1, ×2 when the APB1 prescaler is not 1 (§7.2).
    pub fn tim2clk(&self) -> u64 {
        let d = Self::apb_div((self.cfgr >> 8) & 7);
        if d == 1 {
            self.pclk1()
        } else {
            self.pclk1() * 2
        }
    }

    pub fn read(&self, off: u32) -> Access {
        Ok(match off {
            0x00 => self.cr,
            0x04 => self.cfgr,
            0x08 => self.cir,
            0x0C => self.apb2rstr,
            0x10 => self.apb1rstr,
            0x14 => self.ahbenr,
            0x18 => self.apb2enr,
            0x1C => self.apb1enr,
            0x20 => self.bdcr,
            0x24 => self.csr,
            _ => return Err(off),
        })
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access {
        match off {
            // CR (§7.3.1): the ready flags follow the enables at once (oscillator start-up
            // time is not modelled, except a dead crystal).
            0x00 => {
                let mut cr = (v & 0x010D_00F9) | (self.cr & 0xFF00);
                if v & 1 != 0 {
                    cr |= 2;
                }
                if v & (1 << 16) != 0 && !self.hse_dead {
                    cr |= 1 << 17;
                }
                // PLLRDY once PLLON with its source running.
                let src_ok = self.cfgr & (1 << 16) == 0 || cr & (1 << 17) != 0;
                if v & (1 << 24) != 0 && src_ok {
                    cr |= 1 << 25;
                }
                self.cr = cr;
            }
            // CFGR (§7.3.2): SWS follows SW when the selected source is ready.
            0x04 => {
                let sw = v & 3;
                let ready = match sw {
                    0 => self.cr & 2 != 0,
                    1 => self.cr & (1 << 17) != 0,
                    2 => self.cr & (1 << 25) != 0,
                    _ => false,
                };
                let sws = if ready { sw } else { (self.cfgr >> 2) & 3 };
                self.cfgr = (v & 0x077F_FFF3) | (sws << 2);
            }
            0x08 => self.cir = v & 0x1F00,
            0x0C => self.apb2rstr = v,
            0x10 => self.apb1rstr = v,
            0x14 => self.ahbenr = v,
            0x18 => self.apb2enr = v,
            0x1C => self.apb1enr = v,
            0x20 => self.bdcr = v,
            0x24 => {
                self.csr = (self.csr & 0xFC00_0000 & !(v & (1 << 24)))
                    | (v & 1)
                    | u32::from(v & 1 != 0) << 1
            }
            _ => return Err(off),
        }
        Ok(0)
    }
}

/// Flash interface (RM0008 §3.3.3, PM0075 for the programming registers).
#[derive(Clone, Debug)]
pub struct Flash {
    acr: u32,
}

impl Default for Flash {
    fn default() -> Self {
        Flash { acr: 0x30 }
    }
}

impl Flash {
    /// ACR.LATENCY: wait states (§3.3.3).
    pub fn wait_states(&self) -> u32 {
        self.acr & 7
    }

    pub fn read(&self, off: u32) -> Access {
        Ok(match off {
            0x00 => self.acr,
            0x0C => 0,           // SR
            0x10 => 0x80,        // CR: LOCK
            0x1C => 0x03FF_FFFC, // OBR
            0x20 => 0xFFFF_FFFF, // WRPR
            _ => return Err(off),
        })
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access {
        match off {
            // PRFTBS (bit 5) mirrors PRFTBE (bit 4).
            0x00 => self.acr = (v & 0x1F) | ((v & 0x10) << 1),
            _ => return Err(off),
        }
        Ok(0)
    }
}

/// One GPIO port (RM0008 §9.2). `input` holds the levels driven from outside.
#[derive(Clone, Debug)]
pub struct Gpio {
    crl: u32,
    crh: u32,
    pub odr: u32,
    pub input: u32,
    lckr: u32,
}

impl Default for Gpio {
    fn default() -> Self {
        Gpio {
            crl: 0x4444_4444,
            crh: 0x4444_4444,
            odr: 0,
            input: 0,
            lckr: 0,
        }
    }
}

impl Gpio {
    /// Pins configured as outputs (MODE != 00, §9.2.1/9.2.2).
    fn outputs(&self) -> u32 {
        (0..16).fold(0, |acc, p| {
            let cr = if p < 8 { self.crl } else { self.crh };
            let mode = (cr >> (4 * (p % 8))) & 3;
            acc | (u32::from(mode != 0) << p)
        })
    }

    pub fn read(&self, off: u32) -> Access {
        Ok(match off {
            0x00 => self.crl,
            0x04 => self.crh,
            // IDR (§9.2.3): outputs read back their ODR level.
            0x08 => ((self.odr & self.outputs()) | (self.input & !self.outputs())) & 0xFFFF,
            0x0C => self.odr,
            0x10 | 0x14 => 0,
            0x18 => self.lckr,
            _ => return Err(off),
        })
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access {
        match off {
            0x00 => self.crl = v,
            0x04 => self.crh = v,
            0x0C => self.odr = v & 0xFFFF,
            // BSRR (§9.2.5): set low half, reset high half; set wins.
            0x10 => self.odr = (self.odr & !(v >> 16)) | (v & 0xFFFF),
            0x14 => self.odr &= !(v & 0xFFFF),
            0x18 => self.lckr = v & 0x1_FFFF,
            _ => return Err(off),
        }
        Ok(0)
    }
}

/// AFIO (RM0008 §9.4) and EXTI (§10.3), register files only (no pin events modelled).
#[derive(Clone, Debug, Default)]
pub struct Afio {
    regs: [u32; 8],
}

impl Afio {
    pub fn read(&self, off: u32) -> Access {
        match off {
            0x00..=0x1C if off.is_multiple_of(4) && off != 0x18 => {
                self.regs.get((off / 4) as usize).copied().ok_or(off)
            }
            _ => Err(off),
        }
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access {
        match off {
            0x00..=0x1C if off.is_multiple_of(4) && off != 0x18 => {
                // MAPR SWJ_CFG (bits 26:24) is write-only (§9.4.2).
                let v = if off == 4 { v & !(7 << 24) } else { v };
                let r = self.regs.get_mut((off / 4) as usize).ok_or(off)?;
                *r = v;
                Ok(0)
            }
            _ => Err(off),
        }
    }
}

/// EXTI (RM0008 §10.3): IMR, EMR, RTSR, FTSR, SWIER, PR.
#[derive(Clone, Debug, Default)]
pub struct Exti {
    pub imr: u32,
    emr: u32,
    rtsr: u32,
    ftsr: u32,
    pub pr: u32,
}

impl Exti {
    pub fn read(&self, off: u32) -> Access {
        Ok(match off {
            0x00 => self.imr,
            0x04 => self.emr,
            0x08 => self.rtsr,
            0x0C => self.ftsr,
            0x10 => 0,
            0x14 => self.pr,
            _ => return Err(off),
        })
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access {
        match off {
            0x00 => self.imr = v & 0xF_FFFF,
            0x04 => self.emr = v & 0xF_FFFF,
            0x08 => self.rtsr = v & 0xF_FFFF,
            0x0C => self.ftsr = v & 0xF_FFFF,
            // SWIER (§10.3.5): sets the pending bit of unmasked lines.
            0x10 => self.pr |= v & self.imr,
            // PR is rc_w1 (§10.3.6).
            0x14 => self.pr &= !v,
            _ => return Err(off),
        }
        Ok(0)
    }
}

/// A general-purpose timer TIM2..TIM4, up-counting (RM0008 §15.3.2, registers §15.4):
/// counter, prescaler with preload, auto-reload, four compare channels, update/compare
/// flags and interrupts. In encoder mode (SMCR.SMS = 1..3, §15.3.12) the counter follows
/// the encoder inputs instead of the clock: the plant moves it with `encoder_step`.
#[derive(Clone, Debug, Default)]
pub struct Tim2 {
    cr1: u32,
    cr2: u32,
    smcr: u32,
    pub dier: u32,
    pub sr: u32,
    ccmr: [u32; 2],
    ccer: u32,
    cnt: u32,
    psc: u32,
    /// Active prescaler (PSC is preloaded at the update event, §15.3.1).
    psc_active: u32,
    /// Prescaler counter: timer-clock cycles into the current counter tick.
    psc_cnt: u64,
    arr: u32,
    ccr: [u32; 4],
    /// Time (ps) the counter state was last brought up to date.
    synced: u64,
    /// Part of a timer-clock cycle carried over, in ps·Hz (less than 10^12).
    carry: u64,
    /// Time (ps) CR1.CEN last went from 0 to 1: the origin of a clock the image keeps
    /// by counting this timer's ticks (the slot timer's `now`, message stamps).
    pub started_ps: Option<u64>,
}

impl Tim2 {
    pub fn new() -> Self {
        Tim2 {
            arr: 0xFFFF,
            ..Default::default()
        }
    }

    fn running(&self) -> bool {
        self.cr1 & 1 != 0 && !self.encoder_mode()
    }

    /// SMCR.SMS = 001, 010, 011: encoder modes 1..3 (§15.4.3).
    pub fn encoder_mode(&self) -> bool {
        (1..=3).contains(&(self.smcr & 7))
    }

    /// Encoder edges (signed count, §15.3.12): the counter moves modulo ARR+1.
    pub fn encoder_step(&mut self, edges: i64) {
        if self.cr1 & 1 == 0 || !self.encoder_mode() {
            return;
        }
        let period = i64::from(self.arr) + 1;
        self.cnt = (i64::from(self.cnt) + edges).rem_euclid(period) as u32;
    }

    /// Compare value of channel `ch` (0..4) and ARR: the PWM duty an H-bridge sees.
    pub fn pwm(&self, ch: usize) -> (u32, u32) {
        (self.ccr.get(ch).copied().unwrap_or(0), self.arr)
    }

    /// Fraction of the period output `ch` (0..4) is high (§15.3.10, edge-aligned PWM,
    /// up-counting): PWM mode 1 (OCxM = 110) high while CNT < CCRx, mode 2 (111) the
    /// complement, with CCxE set and the counter enabled; 0 otherwise (output off,
    /// frozen or forced modes). CCRx preload (OCxPE) is not modelled: a new compare
    /// value counts at once instead of at the next update (at most one PWM period).
    pub fn duty(&self, ch: usize) -> f64 {
        let ccmr = self.ccmr.get(ch / 2).copied().unwrap_or(0) >> (8 * (ch % 2));
        let mode = (ccmr >> 4) & 7;
        if self.cr1 & 1 == 0 || self.ccer & (1 << (4 * ch)) == 0 || ccmr & 3 != 0 {
            return 0.0;
        }
        let period = f64::from(self.arr) + 1.0;
        let high = f64::from(self.ccr.get(ch).copied().unwrap_or(0)).min(period) / period;
        match mode {
            0b110 => high,
            0b111 => 1.0 - high,
            _ => 0.0,
        }
    }

    /// Brings the counter to time `now` with timer clock `clk_hz`, setting UIF/CCxIF for
    /// every update and compare match passed (§15.3.2, §15.3.9).
    pub fn sync(&mut self, now: u64, clk_hz: u64) {
        let elapsed = now.saturating_sub(self.synced);
        self.synced = now;
        if !self.running() || clk_hz == 0 {
            self.carry = 0;
            return;
        }
        // Exact: timer-clock cycles = elapsed × clk / 10^12, remainder carried (ps·Hz).
        let total = u128::from(elapsed) * u128::from(clk_hz) + u128::from(self.carry);
        let cycles = (total / u128::from(PS)) as u64;
        self.carry = (total % u128::from(PS)) as u64;
        let div = u64::from(self.psc_active) + 1;
        let total = self.psc_cnt + cycles;
        let ticks = total / div;
        self.psc_cnt = total % div;
        self.advance(ticks);
    }

    fn advance(&mut self, ticks: u64) {
        if ticks == 0 {
            return;
        }
        let period = u64::from(self.arr) + 1;
        let cnt = u64::from(self.cnt);
        // Compare matches: CCRx reached by any of the counts cnt+1 ..= cnt+ticks (mod period).
        for (i, &c) in self.ccr.iter().enumerate() {
            let c = u64::from(c);
            if c > u64::from(self.arr) {
                continue;
            }
            let dist = (c + period - cnt) % period;
            let dist = if dist == 0 { period } else { dist };
            if ticks >= dist {
                self.sr |= 1 << (1 + i);
            }
        }
        let to_wrap = period - cnt;
        if ticks >= to_wrap {
            self.sr |= 1; // UIF
            self.psc_active = self.psc;
        }
        self.cnt = ((cnt + ticks) % period) as u32;
    }

    /// Time (ps) of the next flag the enabled interrupts wait for, from `now`.
    pub fn next_event(&self, now: u64, clk_hz: u64) -> Option<u64> {
        if !self.running() || clk_hz == 0 || self.dier & 0x1F == 0 {
            return None;
        }
        let period = u64::from(self.arr) + 1;
        let cnt = u64::from(self.cnt);
        let mut ticks = if self.dier & 1 != 0 {
            period - cnt
        } else {
            u64::MAX
        };
        for (i, &c) in self.ccr.iter().enumerate() {
            if self.dier & (1 << (1 + i)) != 0 && u64::from(c) <= u64::from(self.arr) {
                let d = (u64::from(c) + period - cnt) % period;
                ticks = ticks.min(if d == 0 { period } else { d });
            }
        }
        let div = u64::from(self.psc_active) + 1;
        let cycles = (ticks * div).saturating_sub(self.psc_cnt);
        let need = (u128::from(cycles) * u128::from(PS)).saturating_sub(u128::from(self.carry));
        Some(now + need.div_ceil(u128::from(clk_hz)) as u64)
    }

    /// The TIM2 interrupt line (§15.4.4 DIER and §15.4.5 SR).
    pub fn irq(&self) -> bool {
        self.sr & self.dier & 0x5F != 0
    }

    pub fn read(&self, off: u32) -> Access {
        Ok(match off {
            0x00 => self.cr1,
            0x04 => self.cr2,
            0x08 => self.smcr,
            0x0C => self.dier,
            0x10 => self.sr,
            0x14 => 0,
            0x18 | 0x1C => self
                .ccmr
                .get(((off - 0x18) / 4) as usize)
                .copied()
                .unwrap_or(0),
            0x20 => self.ccer,
            0x24 => self.cnt,
            0x28 => self.psc,
            0x2C => self.arr,
            0x34..=0x40 => self
                .ccr
                .get(((off - 0x34) / 4) as usize)
                .copied()
                .unwrap_or(0),
            0x48 | 0x4C => 0,
            _ => return Err(off),
        })
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access {
        match off {
            0x00 => {
                // `sync` brought `synced` to the time of this write.
                if self.cr1 & 1 == 0 && v & 1 != 0 {
                    self.started_ps = Some(self.synced);
                }
                self.cr1 = v & 0x3FF;
            }
            0x04 => self.cr2 = v & 0xF8,
            0x08 => self.smcr = v & 0xFFF7,
            0x0C => self.dier = v & 0x5F5F,
            // SR flags are rc_w0 (§15.4.5): writing 0 clears, 1 leaves.
            0x10 => self.sr &= v | !0x1E5F,
            // EGR (§15.4.6): UG re-initialises counter and prescaler and sets UIF
            // (URS = 0); CCxG set CCxIF.
            0x14 => {
                if v & 1 != 0 {
                    self.cnt = 0;
                    self.psc_cnt = 0;
                    self.psc_active = self.psc;
                    if self.cr1 & (1 << 2) == 0 {
                        self.sr |= 1;
                    }
                }
                self.sr |= v & 0x1E;
            }
            0x18 | 0x1C => {
                if let Some(r) = self.ccmr.get_mut(((off - 0x18) / 4) as usize) {
                    *r = v & 0xFFFF;
                }
            }
            0x20 => self.ccer = v & 0x3333,
            0x24 => self.cnt = v & 0xFFFF,
            0x28 => self.psc = v & 0xFFFF,
            0x2C => self.arr = v & 0xFFFF,
            0x34..=0x40 => {
                if let Some(r) = self.ccr.get_mut(((off - 0x34) / 4) as usize) {
                    *r = v & 0xFFFF;
                }
            }
            0x48 | 0x4C => {}
            _ => return Err(off),
        }
        Ok(0)
    }
}

/// Independent watchdog (RM0008 §19.4), clocked by the LSI (40 kHz, §7.2.5).
#[derive(Clone, Debug, Default)]
pub struct Iwdg {
    unlocked: bool,
    pr: u32,
    rlr: u32,
    /// Reset time (ps) once started.
    pub deadline: Option<u64>,
}

const LSI_HZ: u64 = 40_000;

impl Iwdg {
    pub fn new() -> Self {
        Iwdg {
            rlr: 0xFFF,
            ..Default::default()
        }
    }

    fn timeout_ps(&self) -> u64 {
        (u64::from(self.rlr) + 1) * (4 << self.pr.min(6)) * PS / LSI_HZ
    }

    pub fn read(&self, off: u32) -> Access {
        Ok(match off {
            0x04 => self.pr,
            0x08 => self.rlr,
            0x0C => 0, // SR: PVU/RVU, updates take effect at once here
            _ => return Err(off),
        })
    }

    pub fn write(&mut self, off: u32, v: u32, now: u64) -> Access {
        match off {
            // KR (§19.4.1): 0x5555 unlocks PR/RLR, 0xAAAA reloads, 0xCCCC starts.
            0x00 => match v & 0xFFFF {
                0x5555 => self.unlocked = true,
                0xAAAA => {
                    self.unlocked = false;
                    if self.deadline.is_some() {
                        self.deadline = Some(now + self.timeout_ps());
                    }
                }
                0xCCCC => {
                    self.unlocked = false;
                    self.deadline = Some(now + self.timeout_ps());
                }
                _ => self.unlocked = false,
            },
            0x04 if self.unlocked => self.pr = v & 7,
            0x08 if self.unlocked => self.rlr = v & 0xFFF,
            0x04 | 0x08 => {}
            _ => return Err(off),
        }
        Ok(0)
    }
}

// USART1 and DMA1: `serial.rs`.

/// ADC1 (RM0008 §11, registers §11.12): single regular conversions started by SWSTART or
/// by writing ADON again (§11.3.1); a conversion completes at once with the level the
/// plant set for the channel of SQR3.SQ1 (conversion time not modelled). Calibration
/// (CAL, RSTCAL) completes at once.
#[derive(Clone, Debug, Default)]
pub struct Adc {
    sr: u32,
    cr1: u32,
    cr2: u32,
    smpr: [u32; 2],
    jofr: [u32; 4],
    htr: u32,
    ltr: u32,
    sqr: [u32; 3],
    jsqr: u32,
    dr: u32,
    /// 12-bit input level per channel, driven by the plant.
    pub input: [u16; 18],
}

impl Adc {
    pub fn new() -> Self {
        Adc {
            htr: 0xFFF,
            ..Default::default()
        }
    }

    fn convert(&mut self) {
        let ch = (self.sqr.get(2).copied().unwrap_or(0) & 0x1F) as usize;
        self.dr = u32::from(self.input.get(ch).copied().unwrap_or(0) & 0xFFF);
        self.sr |= 0x12; // EOC, STRT
    }

    pub fn read(&mut self, off: u32) -> Access {
        Ok(match off {
            0x00 => self.sr,
            0x04 => self.cr1,
            0x08 => self.cr2,
            0x0C | 0x10 => self
                .smpr
                .get(((off - 0x0C) / 4) as usize)
                .copied()
                .unwrap_or(0),
            0x14..=0x20 => self
                .jofr
                .get(((off - 0x14) / 4) as usize)
                .copied()
                .unwrap_or(0),
            0x24 => self.htr,
            0x28 => self.ltr,
            0x2C..=0x34 => self
                .sqr
                .get(((off - 0x2C) / 4) as usize)
                .copied()
                .unwrap_or(0),
            0x38 => self.jsqr,
            0x3C..=0x48 => 0,
            // Reading DR clears EOC (§11.12.1).
            0x4C => {
                self.sr &= !2;
                self.dr
            }
            _ => return Err(off),
        })
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access {
        match off {
            0x00 => self.sr &= v | !0x1F,
            0x04 => self.cr1 = v & 0x00CF_FFFF,
            0x08 => {
                let was_on = self.cr2 & 1 != 0;
                // CAL (bit 2) and RSTCAL (bit 3) clear when done, SWSTART/JSWSTART (22/21)
                // when the conversion starts (§11.12.3): all at once here.
                self.cr2 = v & 0x009E_E90B & !0xC;
                let swstart = v & (1 << 22) != 0 && self.cr2 & (7 << 17) == (7 << 17);
                if (was_on && v & 1 != 0 && v & 0xC == 0 && v & (1 << 22) == 0) || swstart {
                    self.convert();
                }
            }
            0x0C | 0x10 => {
                if let Some(r) = self.smpr.get_mut(((off - 0x0C) / 4) as usize) {
                    *r = v;
                }
            }
            0x14..=0x20 => {
                if let Some(r) = self.jofr.get_mut(((off - 0x14) / 4) as usize) {
                    *r = v & 0xFFF;
                }
            }
            0x24 => self.htr = v & 0xFFF,
            0x28 => self.ltr = v & 0xFFF,
            0x2C..=0x34 => {
                if let Some(r) = self.sqr.get_mut(((off - 0x2C) / 4) as usize) {
                    *r = v;
                }
            }
            0x38 => self.jsqr = v,
            _ => return Err(off),
        }
        Ok(0)
    }
}

#[cfg(test)]
#[path = "periph_tests.rs"]
mod tests;
