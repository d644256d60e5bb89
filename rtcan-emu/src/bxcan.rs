//! bxCAN of the STM32F103 (RM0008 §24, registers §24.9), as a node on the emulator's bus.
//! Time is in bus bit times (`bit`: bits since power-on), which is also the TTCM timer
//! (§24.7.2: "internal 16-bit counter incremented at each CAN bit time").
use crate::Access;

/// A frame as bxCAN holds it in a mailbox (§24.7.5, §24.9.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RawFrame {
    /// 11-bit standard or 29-bit extended identifier.
    pub id: u32,
    pub ide: bool,
    pub rtr: bool,
    pub dlc: u8,
    pub data: [u8; 8],
}

impl RawFrame {
    /// Arbitration field as a number: lower wins (ISO 11898-1: base ID, then SRR/RTR,
    /// IDE, extended ID, RTR; a standard frame beats an extended one with the same base).
    pub fn arbitration_key(&self) -> u64 {
        if self.ide {
            let base = u64::from(self.id >> 18);
            (base << 21) | (3 << 19) | (u64::from(self.id & 0x3_FFFF) << 1) | u64::from(self.rtr)
        } else {
            (u64::from(self.id & 0x7FF) << 21) | (u64::from(self.rtr) << 20)
        }
    }

    /// The identifier register layout of TIxR/RIxR (§24.9.3): STID/EXID, IDE, RTR.
    fn ir(&self) -> u32 {
        let idbits = if self.ide {
            self.id << 3
        } else {
            self.id << 21
        };
        idbits | (u32::from(self.ide) << 2) | (u32::from(self.rtr) << 1)
    }

    fn from_ir(ir: u32, tdtr: u32, lo: u32, hi: u32) -> RawFrame {
        let ide = ir & 4 != 0;
        let l = lo.to_le_bytes();
        let h = hi.to_le_bytes();
        RawFrame {
            id: if ide { ir >> 3 } else { ir >> 21 },
            ide,
            rtr: ir & 2 != 0,
            dlc: (tdtr & 0xF) as u8,
            data: [l[0], l[1], l[2], l[3], h[0], h[1], h[2], h[3]],
        }
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct TxMailbox {
    tir: u32,
    tdtr: u32,
    tdlr: u32,
    tdhr: u32,
    /// TXRQ set and not completed.
    pending: bool,
    /// Order of the request (TXFP = 1: FIFO priority, §24.7.3).
    seq: u64,
}

#[derive(Clone, Copy, Debug, Default)]
struct RxMailbox {
    rir: u32,
    rdtr: u32,
    rdlr: u32,
    rdhr: u32,
}

#[derive(Clone, Debug, Default)]
struct RxFifo {
    /// Up to three messages, output mailbox first (§24.7.5, figure 232).
    slots: Vec<RxMailbox>,
    full: bool,
    fovr: bool,
}

/// Operating mode (§24.4, figure 223).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Sleep,
    Init,
    Normal,
}

/// Number of filter banks of the STM32F103 (RM0008 §24.7.4: 14 banks, 28 only on the
/// connectivity line).
pub const FILTER_BANKS: usize = 14;

/// One bxCAN.
#[derive(Clone, Debug)]
pub struct BxCan {
    mcr: u32,
    mode: Mode,
    /// Bit time at which a requested leave of init/sleep completes (11 recessive bits, §24.4.2).
    leave_at: Option<u64>,
    msr_irq: u32,
    ier: u32,
    btr: u32,
    tx: [TxMailbox; 3],
    tx_flags: u32,
    /// The mailbox on the bus now (its abort waits for the end, §24.7.3).
    pub transmitting: Option<usize>,
    seq: u64,
    rx: [RxFifo; 2],
    pub tec: u32,
    pub rec: u32,
    lec: u32,
    bus_off: bool,
    /// Bit time at which automatic bus-off recovery completes (ABOM, §24.7.6).
    recover_at: Option<u64>,
    /// TEC, REC and bus-off are the bus's (rtcan-sim's fault confinement, given by
    /// `set_error_state`), not counted here: set when this bxCAN is a node of a bus that
    /// counts them for every controller.
    pub bus_confinement: bool,
    // Filters (§24.9.4).
    fmr: u32,
    fm1r: u32,
    fs1r: u32,
    ffa1r: u32,
    fa1r: u32,
    banks: [[u32; 2]; FILTER_BANKS],
}

impl Default for BxCan {
    fn default() -> Self {
        BxCan {
            mcr: 0x0001_0002,
            mode: Mode::Sleep,
            leave_at: None,
            msr_irq: 0,
            ier: 0,
            btr: 0x0123_0000,
            tx: [TxMailbox::default(); 3],
            tx_flags: 0,
            transmitting: None,
            seq: 0,
            rx: [RxFifo::default(), RxFifo::default()],
            tec: 0,
            rec: 0,
            lec: 0,
            bus_off: false,
            recover_at: None,
            bus_confinement: false,
            fmr: 0x2A1C_0E01,
            fm1r: 0,
            fs1r: 0,
            ffa1r: 0,
            fa1r: 0,
            banks: [[0; 2]; FILTER_BANKS],
        }
    }
}

/// Interrupt lines of the bxCAN (§24.8, figure 235) as NVIC IRQ numbers of the STM32F103
/// (RM0008 §10.1.2, table 63).
pub const IRQ_TX: usize = 19;
pub const IRQ_RX0: usize = 20;
pub const IRQ_RX1: usize = 21;
pub const IRQ_SCE: usize = 22;

impl BxCan {
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// Bit time in PCLK1 cycles: (BRP+1) × (1 + TS1+1 + TS2+1) quanta (§24.7.7).
    pub fn bit_pclk_cycles(&self) -> u64 {
        let brp = u64::from(self.btr & 0x3FF) + 1;
        let ts1 = u64::from((self.btr >> 16) & 0xF) + 1;
        let ts2 = u64::from((self.btr >> 20) & 0x7) + 1;
        brp * (1 + ts1 + ts2)
    }

    /// Advances handshakes and recovery to bit time `bit` with the bus idle since
    /// `idle_since` (both need 11 consecutive recessive bits, §24.4.2, §24.7.6).
    pub fn tick(&mut self, bit: u64) {
        if let Some(at) = self.leave_at {
            if bit >= at {
                self.leave_at = None;
                self.mode = Mode::Normal;
            }
        }
        if let Some(at) = self.recover_at {
            if bit >= at {
                self.recover_at = None;
                self.bus_off = false;
                self.tec = 0;
                self.rec = 0;
                self.msr_irq |= 1 << 2; // ERRI: BOFF changed (§24.9.2)
            }
        }
    }

    /// The next bit time at which `tick` changes something.
    pub fn next_event(&self) -> Option<u64> {
        match (self.leave_at, self.recover_at) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    fn mcr_write(&mut self, v: u32, bit: u64) {
        // RESET (bit 15): master reset, back to sleep with reset values (§24.9.2).
        if v & (1 << 15) != 0 {
            // Where the error counters live is the board's wiring, not a register.
            let bus = self.bus_confinement;
            *self = BxCan::default();
            self.bus_confinement = bus;
            return;
        }
        self.mcr = v & 0x0001_00FF;
        let inrq = v & 1 != 0;
        let sleep = v & 2 != 0;
        if inrq {
            // Enters init at once when the bus is idle (no transmission modelled as in
            // progress between frames, §24.4.1).
            self.mode = Mode::Init;
            self.leave_at = None;
        } else if sleep {
            self.mode = Mode::Sleep;
            self.leave_at = None;
        } else if self.mode != Mode::Normal && self.leave_at.is_none() {
            // Normal mode after 11 consecutive recessive bits (§24.4.2).
            self.leave_at = Some(bit + 11);
        }
    }

    fn msr(&self) -> u32 {
        let inak = u32::from(self.mode == Mode::Init);
        let slak = u32::from(self.mode == Mode::Sleep);
        // RX bit (11) reads recessive (1) on an idle bus; SAMP (10) likewise.
        inak | (slak << 1)
            | self.msr_irq
            | (3 << 10)
            | (u32::from(self.transmitting.is_some()) << 8)
    }

    fn tsr(&self) -> u32 {
        let mut v = self.tx_flags;
        let empty: Vec<usize> = (0..3).filter(|&m| !self.tx_pending(m)).collect();
        for &m in &empty {
            v |= 1 << (26 + m);
        }
        // CODE: number of the next empty mailbox; LOW: lowest-priority pending one when
        // more than one is pending (§24.9.2, CAN_TSR).
        if let Some(&m) = empty.first() {
            v |= (m as u32) << 24;
        }
        let pending: Vec<usize> = (0..3).filter(|&m| self.tx_pending(m)).collect();
        if pending.len() > 1 {
            if let Some(&low) = pending.iter().max_by_key(|&&m| self.tx_rank(m)) {
                v |= 1 << (29 + low);
            }
        }
        v
    }

    fn tx_pending(&self, m: usize) -> bool {
        self.tx.get(m).is_some_and(|b| b.pending)
    }

    /// Transmit priority of mailbox `m` (lower first, §24.7.3): by identifier, equal
    /// identifiers by mailbox number; with TXFP by request order.
    fn tx_rank(&self, m: usize) -> (u64, u64) {
        let Some(b) = self.tx.get(m) else {
            return (u64::MAX, u64::MAX);
        };
        if self.mcr & 4 != 0 {
            (b.seq, m as u64)
        } else {
            let f = RawFrame::from_ir(b.tir, b.tdtr, b.tdlr, b.tdhr);
            (f.arbitration_key(), m as u64)
        }
    }

    /// The mailbox and frame this node offers to arbitration (None unless in normal mode
    /// and not bus-off).
    pub fn tx_candidate(&self) -> Option<(usize, RawFrame)> {
        if self.mode != Mode::Normal || self.bus_off {
            return None;
        }
        let m = (0..3)
            .filter(|&m| self.tx_pending(m))
            .min_by_key(|&m| self.tx_rank(m))?;
        let b = self.tx.get(m)?;
        Some((m, RawFrame::from_ir(b.tir, b.tdtr, b.tdlr, b.tdhr)))
    }

    /// Mailbox `m` won arbitration at SOF bit time `sof`: TTCM stamps TDTxR.TIME (§24.7.2).
    pub fn tx_started(&mut self, m: usize, sof: u64) {
        self.transmitting = Some(m);
        if self.mcr & (1 << 7) != 0 {
            if let Some(b) = self.tx.get_mut(m) {
                b.tdtr = (b.tdtr & 0xFFFF) | ((sof as u32 & 0xFFFF) << 16);
            }
        }
    }

    /// The frame of mailbox `m` ended: `ok` sent (RQCP, TXOK, TME, §24.7.3), else a
    /// transmit error (TERR, TEC += 8, §24.7.6); with NART or a pending abort it is not retried.
    pub fn tx_finished(&mut self, m: usize, ok: bool, bit: u64) {
        self.transmitting = None;
        let shift = 8 * m as u32;
        let abort = self.tx_flags & (1 << (7 + shift)) != 0;
        if ok {
            self.tx_flags = (self.tx_flags & !(0xFF << shift)) | (0b11 << shift);
            if !self.bus_confinement {
                self.tec = self.tec.saturating_sub(1);
            }
            if let Some(b) = self.tx.get_mut(m) {
                b.pending = false;
            }
            return;
        }
        self.lec = 3; // form error stands for "a transmit error" here
        self.msr_irq |= 1 << 2;
        if !self.bus_confinement {
            self.tec += 8;
            if self.tec > 255 {
                self.enter_bus_off(bit);
            }
        }
        if abort || self.mcr & (1 << 4) != 0 || self.bus_off {
            // RQCP with TERR, TXOK clear; the mailbox empties (§24.7.3 "abort", NART).
            self.tx_flags = (self.tx_flags & !(0xFF << shift)) | (0b1001 << shift);
            if let Some(b) = self.tx.get_mut(m) {
                b.pending = false;
            }
        }
    }

    /// Lost arbitration: ALST (§24.9.2); the mailbox stays pending (retransmission).
    pub fn tx_lost(&mut self, m: usize) {
        self.transmitting = None;
        self.tx_flags |= 1 << (2 + 8 * m as u32);
    }

    fn enter_bus_off(&mut self, bit: u64) {
        self.bus_off = true;
        self.msr_irq |= 1 << 2;
        // Pending requests end with TERR when bus-off is entered (none can be sent).
        if self.mcr & (1 << 6) != 0 {
            // ABOM: recovery after 128 × 11 recessive bits (§24.7.6).
            self.recover_at = Some(bit + 128 * 11);
        }
    }

    /// Fault injection: `n` transmit errors (for bus-off tests).
    pub fn inject_tx_errors(&mut self, n: u32, bit: u64) {
        self.tec += 8 * n;
        self.msr_irq |= 1 << 2;
        if self.tec > 255 && !self.bus_off {
            self.enter_bus_off(bit);
        }
    }

    /// The bus's fault confinement for this controller (`bus_confinement`): TEC, REC and
    /// bus-off as ESR shows them (§24.9.2 CAN_ESR); a change of the warning (96),
    /// passive (128) or bus-off level raises ERRI (§24.7.6, §24.9.2 CAN_MSR), as a
    /// bus-off recovery does.
    pub fn set_error_state(&mut self, tec: u16, rec: u16, bus_off: bool) {
        let levels =
            |tec: u32, rec: u32, off: bool| (tec >= 96 || rec >= 96, tec > 127 || rec > 127, off);
        let before = levels(self.tec, self.rec, self.bus_off);
        self.tec = u32::from(tec);
        self.rec = u32::from(rec);
        self.bus_off = bus_off;
        self.recover_at = None;
        if levels(self.tec, self.rec, self.bus_off) != before {
            self.msr_irq |= 1 << 2;
        }
    }

    pub fn is_bus_off(&self) -> bool {
        self.bus_off
    }

    /// A frame on the bus with SOF at bit time `sof`, complete now: filtered into a FIFO
    /// (§24.7.4), stored with FMI and TTCM time, or lost to overrun (§24.7.5).
    pub fn receive(&mut self, f: &RawFrame, sof: u64) {
        if self.mode != Mode::Normal || self.bus_off {
            return;
        }
        if !self.bus_confinement {
            self.rec = self.rec.saturating_sub(1);
        }
        let Some((fifo, fmi)) = self.filter(f) else {
            return;
        };
        let rflm = self.mcr & (1 << 3) != 0;
        let ttcm = self.mcr & (1 << 7) != 0;
        let Some(q) = self.rx.get_mut(fifo) else {
            return;
        };
        let time = if ttcm { (sof as u32 & 0xFFFF) << 16 } else { 0 };
        let lo = u32::from_le_bytes([f.data[0], f.data[1], f.data[2], f.data[3]]);
        let hi = u32::from_le_bytes([f.data[4], f.data[5], f.data[6], f.data[7]]);
        let mb = RxMailbox {
            rir: f.ir(),
            rdtr: u32::from(f.dlc & 0xF) | ((fmi as u32 & 0xFF) << 8) | time,
            rdlr: lo,
            rdhr: hi,
        };
        if q.slots.len() >= 3 {
            q.fovr = true;
            if !rflm {
                // Not locked: the last message stored is overwritten by the new one.
                if let Some(last) = q.slots.last_mut() {
                    *last = mb;
                }
            }
        } else {
            q.slots.push(mb);
            q.full = q.slots.len() == 3;
        }
    }

    /// The FIFO and filter match index accepting `f`, by the priority rules of §24.7.4
    /// (32-bit before 16-bit, list before mask, then lower filter number).
    pub fn filter(&self, f: &RawFrame) -> Option<(usize, usize)> {
        let mut numbers = [0usize; 2];
        let mut best: Option<((u8, u8, usize), usize, usize)> = None;
        // Field layouts of §24.7.4, figure 229.
        let v32 = f.ir();
        let v16 = ((f.id >> if f.ide { 18 } else { 0 }) & 0x7FF) << 5
            | (u32::from(f.rtr) << 4)
            | (u32::from(f.ide) << 3)
            | if f.ide { (f.id >> 15) & 7 } else { 0 };
        for (bank, regs) in self.banks.iter().enumerate() {
            let fifo = ((self.ffa1r >> bank) & 1) as usize;
            let list = self.fm1r & (1 << bank) != 0;
            let wide = self.fs1r & (1 << bank) != 0;
            let count = match (wide, list) {
                (true, false) => 1,
                (true, true) | (false, false) => 2,
                (false, true) => 4,
            };
            let Some(first) = numbers.get_mut(fifo) else {
                continue;
            };
            let base = *first;
            *first += count;
            if self.fa1r & (1 << bank) == 0 {
                continue;
            }
            let [r1, r2] = *regs;
            let hits: Vec<usize> = if wide {
                let mask = |id: u32, m: u32| (v32 ^ id) & m & !1 == 0;
                if list {
                    [r1, r2]
                        .iter()
                        .enumerate()
                        .filter(|(_, &r)| (v32 ^ r) & !1 == 0)
                        .map(|(i, _)| i)
                        .collect()
                } else if mask(r1, r2) {
                    vec![0]
                } else {
                    vec![]
                }
            } else {
                let halves = [r1 & 0xFFFF, r1 >> 16, r2 & 0xFFFF, r2 >> 16];
                if list {
                    (0..4)
                        .filter(|&i| halves.get(i).is_some_and(|&h| h == v16))
                        .collect()
                } else {
                    // Mask mode 16-bit: (id, mask) pairs are (FxR1 low, FxR1 high) and (FxR2 low, FxR2 high).
                    (0..2)
                        .filter(|&i| {
                            let id = halves.get(2 * i).copied().unwrap_or(0);
                            let m = halves.get(2 * i + 1).copied().unwrap_or(0);
                            (v16 ^ id) & m == 0
                        })
                        .collect()
                }
            };
            for h in hits {
                let rank = (u8::from(!wide), u8::from(!list), base + h);
                if best.is_none_or(|(r, _, _)| rank < r) {
                    best = Some((rank, fifo, base + h));
                }
            }
        }
        best.map(|(_, fifo, fmi)| (fifo, fmi))
    }

    /// Interrupt lines now active (§24.8): bit 0 TX, 1 RX0, 2 RX1, 3 SCE.
    pub fn irq_lines(&self) -> [bool; 4] {
        let ier = self.ier;
        let rqcp = self.tx_flags & 0x0001_0101 != 0;
        let fifo = |i: usize, sh: u32| {
            self.rx.get(i).is_some_and(|q| {
                (ier & (1 << sh) != 0 && !q.slots.is_empty())
                    || (ier & (1 << (sh + 1)) != 0 && q.full)
                    || (ier & (1 << (sh + 2)) != 0 && q.fovr)
            })
        };
        let sce = ier & (1 << 15) != 0 && self.msr_irq & (1 << 2) != 0
            || ier & (1 << 16) != 0 && self.msr_irq & (1 << 3) != 0
            || ier & (1 << 17) != 0 && self.msr_irq & (1 << 4) != 0;
        [ier & 1 != 0 && rqcp, fifo(0, 1), fifo(1, 4), sce]
    }

    fn esr(&self) -> u32 {
        let ewgf = u32::from(self.tec >= 96 || self.rec >= 96);
        let epvf = u32::from(self.tec > 127 || self.rec > 127);
        ewgf | (epvf << 1)
            | (u32::from(self.bus_off) << 2)
            | (self.lec << 4)
            | ((self.tec.min(255)) << 16)
            | ((self.rec.min(255)) << 24)
    }

    fn filters_writable(&self, bank: usize) -> bool {
        // Filter registers change only in filter init mode (FINIT) or with the bank
        // inactive (§24.7.4).
        self.fmr & 1 != 0 || self.fa1r & (1 << bank) == 0
    }

    /// Register read at offset `off` from 0x4000_6400 (§24.9).
    pub fn read(&mut self, off: u32) -> Access {
        let tx = |s: &Self, m: usize, r: usize| {
            s.tx.get(m).and_then(|b| {
                [b.tir | u32::from(b.pending), b.tdtr, b.tdlr, b.tdhr]
                    .get(r)
                    .copied()
            })
        };
        Ok(match off {
            0x000 => self.mcr,
            0x004 => self.msr(),
            0x008 => self.tsr(),
            0x00C | 0x010 => {
                let q = self.rx.get(((off - 0x00C) / 4) as usize).ok_or(off)?;
                (q.slots.len() as u32) | (u32::from(q.full) << 3) | (u32::from(q.fovr) << 4)
            }
            0x014 => self.ier,
            0x018 => self.esr(),
            0x01C => self.btr,
            0x180..=0x1AF => {
                let m = ((off - 0x180) / 16) as usize;
                let r = ((off % 16) / 4) as usize;
                tx(self, m, r).ok_or(off)?
            }
            0x1B0..=0x1CF => {
                let q = self.rx.get(((off - 0x1B0) / 16) as usize).ok_or(off)?;
                let mb = q.slots.first().copied().unwrap_or_default();
                match (off % 16) / 4 {
                    0 => mb.rir,
                    1 => mb.rdtr,
                    2 => mb.rdlr,
                    _ => mb.rdhr,
                }
            }
            0x200 => self.fmr,
            0x204 => self.fm1r,
            0x20C => self.fs1r,
            0x214 => self.ffa1r,
            0x21C => self.fa1r,
            0x240..=0x2AF => {
                let bank = ((off - 0x240) / 8) as usize;
                let r = ((off % 8) / 4) as usize;
                self.banks
                    .get(bank)
                    .and_then(|b| b.get(r))
                    .copied()
                    .ok_or(off)?
            }
            _ => return Err(off),
        })
    }

    /// Register write (see `read`); `bit` is the bus time now.
    pub fn write(&mut self, off: u32, v: u32, bit: u64) -> Access {
        match off {
            0x000 => self.mcr_write(v, bit),
            // MSR: ERRI, WKUI, SLAKI are rc_w1.
            0x004 => self.msr_irq &= !(v & 0x1C),
            0x008 => {
                for m in 0..3usize {
                    let shift = 8 * m as u32;
                    // RQCP rc_w1 clears RQCP, TXOK, ALST, TERR (§24.9.2).
                    if v & (1 << shift) != 0 {
                        self.tx_flags &= !(0xF << shift);
                    }
                    // ABRQ: a pending, not transmitting mailbox empties at once with RQCP set, TXOK clear.
                    if v & (1 << (7 + shift)) != 0 && self.tx_pending(m) {
                        if self.transmitting == Some(m) {
                            self.tx_flags |= 1 << (7 + shift);
                        } else if let Some(b) = self.tx.get_mut(m) {
                            b.pending = false;
                            self.tx_flags = (self.tx_flags & !(0xFF << shift)) | (1 << shift);
                        }
                    }
                }
            }
            0x00C | 0x010 => {
                let q = self.rx.get_mut(((off - 0x00C) / 4) as usize).ok_or(off)?;
                if v & (1 << 3) != 0 {
                    q.full = false;
                }
                if v & (1 << 4) != 0 {
                    q.fovr = false;
                }
                // RFOM releases the output mailbox (§24.7.5).
                if v & (1 << 5) != 0 && !q.slots.is_empty() {
                    q.slots.remove(0);
                    q.full = false;
                }
            }
            0x014 => self.ier = v & 0x0003_8F7F,
            0x018 => self.lec = (v >> 4) & 7,
            // BTR is writable in init mode only (§24.9.2).
            0x01C => {
                if self.mode == Mode::Init {
                    self.btr = v & 0xC37F_03FF;
                }
            }
            0x180..=0x1AF => {
                let m = ((off - 0x180) / 16) as usize;
                let r = (off % 16) / 4;
                let pending = self.tx_pending(m);
                self.seq += 1;
                let seq = self.seq;
                let b = self.tx.get_mut(m).ok_or(off)?;
                // A pending mailbox is write-protected (§24.7.3).
                if !pending {
                    match r {
                        0 => {
                            b.tir = v & !1;
                            if v & 1 != 0 {
                                b.pending = true;
                                b.seq = seq;
                                let shift = 8 * m as u32;
                                self.tx_flags &= !(0xFF << shift);
                            }
                        }
                        1 => b.tdtr = (b.tdtr & 0xFFFF_0000) | (v & 0x10F),
                        2 => b.tdlr = v,
                        _ => b.tdhr = v,
                    }
                }
            }
            0x200 => self.fmr = (self.fmr & !1) | (v & 1),
            0x204 => self.fm1r = v & 0x3FFF,
            0x20C => self.fs1r = v & 0x3FFF,
            0x214 => self.ffa1r = v & 0x3FFF,
            0x21C => self.fa1r = v & 0x3FFF,
            0x240..=0x2AF => {
                let bank = ((off - 0x240) / 8) as usize;
                if self.filters_writable(bank) {
                    let r = ((off % 8) / 4) as usize;
                    if let Some(x) = self.banks.get_mut(bank).and_then(|b| b.get_mut(r)) {
                        *x = v;
                    }
                }
            }
            _ => return Err(off),
        }
        Ok(0)
    }
}

#[cfg(test)]
#[path = "bxcan_tests.rs"]
mod tests;
