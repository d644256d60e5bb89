//! bxCAN adapter. bxcan 0.8 configures the peripheral (bit timing, filters, enable), but
//! its data path cannot serve RTCAN: `transmit` picks the mailbox itself, `abort` busy-waits
//! until the abort completes, and received frames carry no timestamp. So the data path
//! uses the registers directly: the engine names the mailbox, abort only requests
//! (completion comes back through the TX interrupt) and each RX frame carries its SOF time
//! from time-triggered mode (TTCM, see `rtcan_board_common::sof`).
use bxcan::filter::Mask32;
use bxcan::{ExtendedId, Fifo};
use rtcan_board_common::{FilterSet, SofClock};
use rtcan_core::driver::{Controller, Mailbox, TxResult};
use rtcan_core::frame::Frame;
use rtcan_core::id::CanId;
use rtcan_core::time::Nanos;
use rtcan_core::timing::{exact_bits, INTERMISSION_BITS};
use stm32f1xx_hal::can::Can;
use stm32f1xx_hal::pac;

type Regs = pac::can::RegisterBlock;

// Register bits (RM0008 §24.9).
const MCR_TTCM: u32 = 1 << 7;
const TSR_RQCP: u32 = 1; // per mailbox, shifted by 8 * mailbox
const TSR_TXOK: u32 = 1 << 1;
const TSR_ABRQ: u32 = 1 << 7;
const TIR_TXRQ: u32 = 1;
const RIR_IDE: u32 = 1 << 2;
const RIR_RTR: u32 = 1 << 1;
const RFR_FMP: u32 = 0b11;
const RFR_FOVR: u32 = 1 << 4;
const RFR_RFOM: u32 = 1 << 5;
const ESR_BOFF: u32 = 1 << 2;
const MSR_ERRI: u32 = 1 << 2;
// IER: TMEIE, FMPIE0, FOVIE0, BOFIE, ERRIE.
const IER_ALL: u32 = 1 | (1 << 1) | (1 << 3) | (1 << 10) | (1 << 15);
/// Drift bound between the local crystal and the bus bit clock, for SOF mapping.
const DRIFT_PPM: u32 = 200;

/// Driver-level counters (the engine counts protocol-level events).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CanStats {
    /// Bus-off entries (also reported to the engine).
    pub bus_off_entries: u32,
    /// Recoveries from bus-off (automatic bus-off management, 128 x 11 recessive bits).
    pub bus_off_recoveries: u32,
    /// RX FIFO 0 overruns (also reported to the engine).
    pub rx_overruns: u32,
    /// Frames with a standard ID or RTR bit: not RTCAN, dropped.
    pub rx_foreign: u32,
    /// Transmit error counter at the last error check.
    pub tec: u8,
    /// Receive error counter at the last error check.
    pub rec: u8,
}

/// Change of the bus-off state seen by `BxCan::check_errors`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorChange {
    /// Nothing new.
    None,
    /// Entered bus-off (the glue tells the engine: `Engine::on_error_state`).
    BusOff,
    /// Left bus-off (hardware recovery finished).
    Recovered,
}

/// The bxCAN of an STM32F103, configured for RTCAN: extended IDs, TTCM timestamps,
/// automatic retransmission (the engine aborts at window ends), automatic bus-off recovery.
pub struct BxCan<PULL> {
    _can: bxcan::Can<Can<pac::CAN, PULL>>,
    regs: &'static Regs,
    abort_requested: [bool; 3],
    sof: SofClock,
    bus_off: bool,
    overrun: bool,
    stats: CanStats,
}

// SAFETY: `regs` points at the CAN registers this value owns through `_can` (moved in,
// never handed out); it is only dereferenced through `&mut self` or `&self` of this
// value, so moving the adapter to another context (an RTIC resource) moves the only
// access path with it, exactly like moving the PAC's `CAN` token, which is `Send`.
unsafe impl<PULL: Send> Send for BxCan<PULL> {}

impl<PULL> BxCan<PULL>
where
    Can<pac::CAN, PULL>: bxcan::FilterOwner,
{
    /// Configures `can` with bit timing `btr` (`can_btr!(PCLK1_HZ, bitrate)`) and the
    /// acceptance filters (one Mask32 bank each, FIFO 0), enables it (waits for 11
    /// recessive bits, once, at start-up) and its interrupts. `bitrate` must be the one
    /// `btr` was computed for (timestamps are in bit times).
    pub fn new(can: Can<pac::CAN, PULL>, btr: u32, bitrate: u32, filters: FilterSet) -> Self {
        // SAFETY: `can` (moved in and kept) owns the CAN peripheral; this reference is the
        // only other path to its registers and is used only by this value.
        let regs: &'static Regs = unsafe { &*pac::CAN::ptr() };
        let builder = bxcan::Can::builder(can)
            .set_bit_timing(btr)
            .set_automatic_retransmit(true);
        // Still in initialisation mode: enable time-triggered mode for SOF timestamps.
        regs.mcr()
            .modify(|r, w| unsafe { w.bits(r.bits() | MCR_TTCM) });
        let mut can = builder.leave_disabled();
        {
            let mut banks = can.modify_filters();
            banks.clear();
            for (i, &(id, mask)) in filters.pairs().iter().enumerate() {
                // `FilterSet` checked both to be 29-bit values, so these are `Some`.
                if let (Some(id), Some(mask)) = (ExtendedId::new(id), ExtendedId::new(mask)) {
                    banks.enable_bank(i as u8, Fifo::Fifo0, Mask32::frames_with_ext_id(id, mask));
                }
            }
        }
        while can.enable_non_blocking().is_err() {}
        regs.ier().write(|w| unsafe { w.bits(IER_ALL) });
        let bit_ns = 1_000_000_000 / bitrate.max(1);
        BxCan {
            _can: can,
            regs,
            abort_requested: [false; 3],
            sof: SofClock::new(bit_ns, DRIFT_PPM),
            bus_off: false,
            overrun: false,
            stats: CanStats::default(),
        }
    }
}

impl<PULL> BxCan<PULL> {
    /// The next completed mailbox and its result (TX interrupt); clears its flags.
    pub fn tx_completion(&mut self) -> Option<(Mailbox, TxResult)> {
        let tsr = self.regs.tsr().read().bits();
        for (m, aborting) in self.abort_requested.iter_mut().enumerate() {
            let shift = 8 * m as u32;
            if tsr & (TSR_RQCP << shift) != 0 {
                let result = if tsr & (TSR_TXOK << shift) != 0 {
                    TxResult::Sent
                } else if *aborting {
                    TxResult::Aborted
                } else {
                    TxResult::Failed
                };
                *aborting = false;
                // Writing RQCP clears RQCP, TXOK, ALST and TERR of this mailbox.
                self.regs
                    .tsr()
                    .write(|w| unsafe { w.bits(TSR_RQCP << shift) });
                return Some((Mailbox(m as u8), result));
            }
        }
        None
    }

    /// The next received RTCAN frame of FIFO 0 and its SOF local time (RX interrupt at
    /// local time `now`). Standard-ID and remote frames are dropped and counted.
    pub fn receive(&mut self, now: Nanos) -> Option<(Frame, Nanos)> {
        let rfr = self.regs.rfr(0);
        loop {
            let status = rfr.read().bits();
            if status & RFR_FOVR != 0 {
                self.overrun = true;
                self.stats.rx_overruns = self.stats.rx_overruns.saturating_add(1);
                rfr.write(|w| unsafe { w.bits(RFR_FOVR) });
            }
            if status & RFR_FMP == 0 {
                return None;
            }
            let mb = self.regs.rx(0);
            let rir = mb.rir().read().bits();
            let rdtr = mb.rdtr().read().bits();
            let lo = mb.rdlr().read().bits().to_le_bytes();
            let hi = mb.rdhr().read().bits().to_le_bytes();
            rfr.write(|w| unsafe { w.bits(RFR_RFOM) });
            let id = if rir & RIR_IDE != 0 && rir & RIR_RTR == 0 {
                CanId::from_raw(rir >> 3)
            } else {
                None
            };
            let dlc = (rdtr & 0xF).min(8) as u8;
            let data = [lo[0], lo[1], lo[2], lo[3], hi[0], hi[1], hi[2], hi[3]];
            match id.and_then(|id| Frame::from_parts(id, dlc, data)) {
                Some(frame) => {
                    // The RX interrupt is raised when the frame becomes valid, at the
                    // last-but-one EOF bit: frame length minus intermission minus one bit.
                    let bits = exact_bits(&frame).saturating_sub(INTERMISSION_BITS + 1);
                    let sof = self.sof.sof((rdtr >> 16) as u16, bits, now);
                    return Some((frame, sof));
                }
                None => self.stats.rx_foreign = self.stats.rx_foreign.saturating_add(1),
            }
        }
    }

    /// True once after an RX FIFO overrun (tell the engine: `Engine::on_rx_overrun`).
    pub fn take_overrun(&mut self) -> bool {
        core::mem::replace(&mut self.overrun, false)
    }

    /// Reads the error state (status-change interrupt, and once per slot so a recovery is
    /// seen within a slot): updates TEC/REC and reports a bus-off entry or recovery.
    pub fn check_errors(&mut self) -> ErrorChange {
        self.regs.msr().write(|w| unsafe { w.bits(MSR_ERRI) });
        let esr = self.regs.esr().read().bits();
        self.stats.tec = (esr >> 16) as u8;
        self.stats.rec = (esr >> 24) as u8;
        let off = esr & ESR_BOFF != 0;
        let change = match (self.bus_off, off) {
            (false, true) => {
                self.stats.bus_off_entries = self.stats.bus_off_entries.saturating_add(1);
                ErrorChange::BusOff
            }
            (true, false) => {
                self.stats.bus_off_recoveries = self.stats.bus_off_recoveries.saturating_add(1);
                ErrorChange::Recovered
            }
            _ => ErrorChange::None,
        };
        self.bus_off = off;
        change
    }

    /// True while the controller is bus-off (as of the last `check_errors`).
    pub fn is_bus_off(&self) -> bool {
        self.bus_off
    }

    /// Driver counters.
    pub fn stats(&self) -> &CanStats {
        &self.stats
    }
}

impl<PULL> Controller for BxCan<PULL> {
    fn load(&mut self, mailbox: Mailbox, frame: &Frame) {
        let m = mailbox.0 as usize;
        if m >= 3 {
            return;
        }
        let tx = self.regs.tx(m);
        let d = frame.raw_data();
        tx.tdtr().write(|w| unsafe { w.bits(frame.dlc() as u32) });
        tx.tdlr()
            .write(|w| unsafe { w.bits(u32::from_le_bytes([d[0], d[1], d[2], d[3]])) });
        tx.tdhr()
            .write(|w| unsafe { w.bits(u32::from_le_bytes([d[4], d[5], d[6], d[7]])) });
        // Extended ID in TIR[31:3], IDE set, data frame; TXRQ last starts the request.
        tx.tir()
            .write(|w| unsafe { w.bits((frame.id().raw() << 3) | RIR_IDE | TIR_TXRQ) });
    }

    fn abort(&mut self, mailbox: Mailbox) {
        let m = mailbox.0 as usize;
        if let Some(flag) = self.abort_requested.get_mut(m) {
            *flag = true;
            self.regs
                .tsr()
                .write(|w| unsafe { w.bits(TSR_ABRQ << (8 * m as u32)) });
        }
    }
}
