//! bxCAN adapter, split by interrupt (boards/common `protocol`). bxcan 0.8 configures the
//! peripheral (bit timing, filters, enable), but its data path cannot serve RTCAN:
//! `transmit` picks the mailbox itself, `abort` busy-waits, and received frames carry no
//! timestamp. So the data path uses the registers directly, in four parts owned by four
//! contexts:
//!
//! - `CanTx` (slot-timer resource): writes prepared mailbox images, TXRQ last; aborts.
//! - `CanRx` (CAN RX0 interrupt): FIFO 0 registers + local time into the RX queue.
//! - `CanTxIrq` (CAN TX interrupt): completions into the TX queue.
//! - `CanSce` (status change): error counters; on bus-off every mailbox is aborted at
//!   once, so no sync or HRT frame goes out late after the recovery.
//!
//! The parts touch disjoint registers except TSR, which only takes write-1 requests
//! (ABRQx, RQCPx): no read-modify-write, so no lock between them.
//!
//! RX FIFO overrun policy: **FIFO locked (RFLM = 1)**. When the three FIFO mailboxes are
//! full a new frame is dropped (FOVR, counted, `Engine::on_rx_overrun`) and the frames
//! already stamped stay in order; with RFLM = 0 the newest frame would overwrite the
//! third and reassembly would see a hole in the middle. The RX interrupt empties the
//! FIFO in < 200 instructions at high priority, so an overrun needs that interrupt held
//! off for three back-to-back frames (≥ 141 µs at 1 Mbit/s).
use bxcan::filter::Mask32;
use bxcan::{ExtendedId, Fifo};
use heapless::spsc::Producer;
use rtcan_board_common::protocol::{RxEvent, TxEvent};
use rtcan_board_common::{FilterSet, TxImage, TxPort};
use rtcan_core::driver::{Mailbox, TxResult};
use rtcan_core::time::Nanos;
use stm32f1xx_hal::can::Can;
use stm32f1xx_hal::pac;

type Regs = pac::can::RegisterBlock;

// Register bits (RM0008 §24.9).
const MCR_TTCM: u32 = 1 << 7;
const MCR_RFLM: u32 = 1 << 3;
const TSR_RQCP: u32 = 1; // per mailbox, shifted by 8 * mailbox
const TSR_TXOK: u32 = 1 << 1;
const TSR_ABRQ: u32 = 1 << 7;
const RFR_FMP: u32 = 0b11;
const RFR_FOVR: u32 = 1 << 4;
const RFR_RFOM: u32 = 1 << 5;
const ESR_BOFF: u32 = 1 << 2;
const MSR_ERRI: u32 = 1 << 2;
// IER: TMEIE, FMPIE0, FOVIE0, BOFIE, ERRIE.
const IER_ALL: u32 = 1 | (1 << 1) | (1 << 3) | (1 << 10) | (1 << 15);
/// Polls of the enable request (each at least one register read, ~100 ns) before giving
/// up: 11 recessive bits take 11 µs at 1 Mbit/s, 880 µs at 12.5 kbit/s; a bus held
/// dominant (no transceiver, shorted lines) never lets the controller join.
const ENABLE_POLLS: u32 = 200_000;

/// The controller did not leave initialisation mode: no 11 recessive bits seen (check
/// the transceiver, its supply and the bus termination).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EnableTimeout;

/// Driver-level counters (the engine and the protocol task count the rest).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CanStats {
    /// Bus-off entries (also reported to the engine).
    pub bus_off_entries: u32,
    /// Recoveries from bus-off seen by the status-change interrupt.
    pub bus_off_recoveries: u32,
    /// RX FIFO 0 overruns (also reported to the engine).
    pub rx_overruns: u32,
    /// Events dropped because the protocol task's queue was full.
    pub queue_full: u32,
    /// Transmit error counter at the last error check.
    pub tec: u8,
    /// Receive error counter at the last error check.
    pub rec: u8,
}

/// Change of the bus-off state seen by `CanSce::on_interrupt`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorChange {
    /// Nothing new.
    None,
    /// Entered bus-off (mailboxes aborted, `TxEvent::BusOff` queued).
    BusOff,
    /// Left bus-off (hardware recovery finished).
    Recovered,
}

/// The four parts of the configured controller.
pub struct CanParts<PULL> {
    /// Transmit mailboxes (slot-timer resource).
    pub tx: CanTx<PULL>,
    /// RX FIFO 0 (CAN RX0 interrupt).
    pub rx: CanRx,
    /// TX completions (CAN TX interrupt).
    pub tx_irq: CanTxIrq,
    /// Status change (CAN SCE interrupt).
    pub sce: CanSce,
}

/// Configures `can` for RTCAN with bit timing `btr` (`can_btr!(PCLK1_HZ, bitrate)`) and
/// the acceptance filters (one Mask32 bank each, FIFO 0): extended IDs, TTCM timestamps,
/// FIFO lock mode, automatic retransmission (the engine aborts at window ends), automatic
/// bus-off recovery; enables it (waits, bounded, for 11 recessive bits) and its
/// interrupts.
pub fn configure<PULL>(
    can: Can<pac::CAN, PULL>,
    btr: u32,
    filters: FilterSet,
) -> Result<CanParts<PULL>, EnableTimeout>
where
    Can<pac::CAN, PULL>: bxcan::FilterOwner,
{
    // SAFETY: `can` (moved in and kept in `CanTx`) owns the CAN peripheral; the parts
    // are the only other paths to its registers and touch disjoint ones (see module doc).
    let regs: &'static Regs = unsafe { &*pac::CAN::ptr() };
    let builder = bxcan::Can::builder(can)
        .set_bit_timing(btr)
        .set_automatic_retransmit(true);
    // Still in initialisation mode: time-triggered mode for SOF stamps, FIFO lock mode.
    regs.mcr()
        .modify(|r, w| unsafe { w.bits(r.bits() | MCR_TTCM | MCR_RFLM) });
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
    let mut polls = 0;
    while can.enable_non_blocking().is_err() {
        polls += 1;
        if polls >= ENABLE_POLLS {
            return Err(EnableTimeout);
        }
    }
    regs.ier().write(|w| unsafe { w.bits(IER_ALL) });
    Ok(CanParts {
        tx: CanTx { _can: can, regs },
        rx: CanRx {
            regs,
            overruns: 0,
            queue_full: 0,
        },
        tx_irq: CanTxIrq {
            regs,
            queue_full: 0,
        },
        sce: CanSce {
            regs,
            bus_off: false,
            stats: CanStats::default(),
        },
    })
}

/// Transmit mailboxes.
pub struct CanTx<PULL> {
    _can: bxcan::Can<Can<pac::CAN, PULL>>,
    regs: &'static Regs,
}

/// RX FIFO 0.
pub struct CanRx {
    regs: &'static Regs,
    overruns: u32,
    queue_full: u32,
}

/// TX completions.
pub struct CanTxIrq {
    regs: &'static Regs,
    queue_full: u32,
}

/// Status change: errors, bus-off.
pub struct CanSce {
    regs: &'static Regs,
    bus_off: bool,
    stats: CanStats,
}

// SAFETY (all four): `regs` points at the CAN registers owned through `CanTx::_can`;
// each part only touches its own registers (plus write-1 requests to TSR), and each is
// moved whole into one RTIC context, exactly like moving the PAC's `CAN` token (`Send`).
unsafe impl<PULL: Send> Send for CanTx<PULL> {}
unsafe impl Send for CanRx {}
unsafe impl Send for CanTxIrq {}
unsafe impl Send for CanSce {}

impl<PULL> TxPort for CanTx<PULL> {
    // Inline: the slot-timer interrupt's stores, not a call (issue 10's 3 µs path).
    #[inline(always)]
    fn write(&mut self, mailbox: usize, image: &TxImage) {
        if mailbox >= 3 {
            return;
        }
        let tx = self.regs.tx(mailbox);
        tx.tdtr().write(|w| unsafe { w.bits(image.tdtr) });
        tx.tdlr().write(|w| unsafe { w.bits(image.tdlr) });
        tx.tdhr().write(|w| unsafe { w.bits(image.tdhr) });
        // TXRQ (in the image) last starts the request.
        tx.tir().write(|w| unsafe { w.bits(image.tir) });
    }

    fn abort(&mut self, mask: u8) {
        let mut bits = 0;
        for m in 0..3u32 {
            if mask & (1 << m) != 0 {
                bits |= TSR_ABRQ << (8 * m);
            }
        }
        self.regs.tsr().write(|w| unsafe { w.bits(bits) });
    }

    fn is_bus_off(&self) -> bool {
        self.regs.esr().read().bits() & ESR_BOFF != 0
    }
}

impl CanRx {
    /// CAN RX0 interrupt at local time `now`: every frame of FIFO 0 into `queue` as raw
    /// registers (parsed and stamped by the protocol task). Overruns are queued too.
    pub fn on_interrupt(&mut self, now: Nanos, queue: &mut Producer<'_, RxEvent>) {
        let rfr = self.regs.rfr(0);
        loop {
            let status = rfr.read().bits();
            if status & RFR_FOVR != 0 {
                self.overruns = self.overruns.saturating_add(1);
                rfr.write(|w| unsafe { w.bits(RFR_FOVR) });
                self.push(queue, RxEvent::OVERRUN);
            }
            if status & RFR_FMP == 0 {
                return;
            }
            let mb = self.regs.rx(0);
            let regs = TxImage {
                tir: mb.rir().read().bits(),
                tdtr: mb.rdtr().read().bits(),
                tdlr: mb.rdlr().read().bits(),
                tdhr: mb.rdhr().read().bits(),
            };
            rfr.write(|w| unsafe { w.bits(RFR_RFOM) });
            self.push(queue, RxEvent::frame(regs, now));
        }
    }

    fn push(&mut self, queue: &mut Producer<'_, RxEvent>, e: RxEvent) {
        if queue.enqueue(e).is_err() {
            self.queue_full = self.queue_full.saturating_add(1);
        }
    }

    /// FIFO overruns and queue-full drops so far.
    pub fn drops(&self) -> (u32, u32) {
        (self.overruns, self.queue_full)
    }
}

impl CanTxIrq {
    /// CAN TX interrupt: every completed mailbox and its result into `queue`.
    pub fn on_interrupt(&mut self, queue: &mut Producer<'_, TxEvent>) {
        let tsr = self.regs.tsr().read().bits();
        for m in 0..3u8 {
            let shift = 8 * m as u32;
            if tsr & (TSR_RQCP << shift) == 0 {
                continue;
            }
            // Automatic retransmission is on: a completion without TXOK was aborted.
            let result = if tsr & (TSR_TXOK << shift) != 0 {
                TxResult::Sent
            } else {
                TxResult::Aborted
            };
            // Writing RQCP clears RQCP, TXOK, ALST and TERR of this mailbox.
            self.regs
                .tsr()
                .write(|w| unsafe { w.bits(TSR_RQCP << shift) });
            if queue.enqueue(TxEvent::Done(Mailbox(m), result)).is_err() {
                self.queue_full = self.queue_full.saturating_add(1);
            }
        }
    }
}

impl CanSce {
    /// CAN SCE interrupt: updates TEC/REC; on bus-off entry aborts every mailbox at once
    /// and queues `TxEvent::BusOff`.
    pub fn on_interrupt(&mut self, queue: &mut Producer<'_, TxEvent>) -> ErrorChange {
        self.regs.msr().write(|w| unsafe { w.bits(MSR_ERRI) });
        let esr = self.regs.esr().read().bits();
        self.stats.tec = (esr >> 16) as u8;
        self.stats.rec = (esr >> 24) as u8;
        let off = esr & ESR_BOFF != 0;
        let change = match (self.bus_off, off) {
            (false, true) => {
                // Before anything else: nothing pending may go out after the recovery.
                let all = TSR_ABRQ | (TSR_ABRQ << 8) | (TSR_ABRQ << 16);
                self.regs.tsr().write(|w| unsafe { w.bits(all) });
                self.stats.bus_off_entries = self.stats.bus_off_entries.saturating_add(1);
                if queue.enqueue(TxEvent::BusOff).is_err() {
                    self.stats.queue_full = self.stats.queue_full.saturating_add(1);
                }
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

    /// Driver counters.
    pub fn stats(&self) -> &CanStats {
        &self.stats
    }
}
