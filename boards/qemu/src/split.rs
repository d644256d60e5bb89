//! The firmware's split interrupt architecture (boards/common `protocol`) on the
//! software bus, so QEMU measures the paths the STM32F103 runs: the same `Protocol`,
//! `SlotPlan`, `TxImage` and `SofClock` code, and interrupt bodies that do what the
//! bxCAN/TIM2 handlers do (volatile register reads and writes on a RAM copy of the
//! registers: the same instruction count as the MMIO accesses). Between the handlers the
//! bus model (not measured) moves the register contents to and from `SoftCan`.
//!
//! Each handler and each protocol-task step is measured under its row name
//! (`meter::Kind`); the critical sections the lower priorities take on the slot-timer
//! resource are measured too (`CriticalSection`), as the blocking term of
//! `slot_boundary_to_txrq`.
use crate::bus::Node;
use crate::meter::{systick_now, Kind, Meter, PathMeter};
use crate::soft_can::SoftCan;
use core::ptr::{read_volatile, write_volatile};
use heapless::spsc::Queue;
use heapless::Deque;
use rtcan_board_common::protocol::{
    Alarm, AlarmSetting, DynController, Lock, RxEvent, SlotCore, SlotTimerHw,
};
use rtcan_board_common::wide_clock::WideClock;
use rtcan_board_common::{Protocol, SlotPlan, TxImage, TxPort};
use rtcan_core::driver::{Controller, Host, Mailbox, Token, TxResult, MAILBOXES};
use rtcan_core::engine::Engine;
use rtcan_core::frame::Frame;
use rtcan_core::time::Nanos;

/// Local clock ticks (8 MHz, as TIM2 on the F103).
const TICK_NS: Nanos = 125;
// bxCAN/TIM2 register bits used by the handler bodies.
const SR_CC1IF: u32 = 1 << 1;
const SR_CC3IF: u32 = 1 << 3;
const DIER_CC1IE: u32 = 1 << 1;
const DIER_CC3IE: u32 = 1 << 3;
const RFR_FMP: u32 = 0b11;
const RFR_FOVR: u32 = 1 << 4;
const RFR_RFOM: u32 = 1 << 5;
const TSR_RQCP: u32 = 1;
const TSR_TXOK: u32 = 1 << 1;

/// A RAM copy of the TX mailbox registers, written like bxCAN's.
pub struct ShadowTx {
    regs: [[u32; 4]; MAILBOXES],
    /// Mailboxes whose TXRQ was written since the bus model last looked.
    txrq: u8,
    /// Abort requests since the bus model last looked.
    abrq: u8,
    /// SysTick reading at the first TXRQ write of a slot-timer interrupt: the bus model
    /// sets `None` before the interrupt and `Some(0)` after it, so a write outside it
    /// (the protocol task loading directly) pays the same two-instruction test as the
    /// interrupt and records nothing.
    pub stamp: Option<u32>,
}

impl ShadowTx {
    const fn new() -> Self {
        ShadowTx {
            regs: [[0; 4]; MAILBOXES],
            txrq: 0,
            abrq: 0,
            stamp: Some(0),
        }
    }

    /// The bus model: hands written mailboxes and abort requests to `can`.
    fn sync(&mut self, can: &mut SoftCan) {
        for m in 0..MAILBOXES {
            let bit = 1u8 << m;
            if self.abrq & bit != 0 {
                can.abort(Mailbox(m as u8));
            }
            if self.txrq & bit != 0 {
                if let Some([tir, tdtr, tdlr, tdhr]) = self.regs.get(m).copied() {
                    let img = TxImage {
                        tir,
                        tdtr,
                        tdlr,
                        tdhr,
                    };
                    if let Some(f) = img.frame() {
                        can.load(Mailbox(m as u8), &f);
                    }
                }
            }
        }
        self.txrq = 0;
        self.abrq = 0;
    }
}

impl TxPort for ShadowTx {
    // Inline, as the F103's: the slot-timer interrupt's stores, not a call.
    #[inline(always)]
    fn write(&mut self, mailbox: usize, image: &TxImage) {
        if let Some(r) = self.regs.get_mut(mailbox) {
            let [tir, tdtr, tdlr, tdhr] = r;
            // SAFETY: plain RAM owned by `self`; volatile to keep the stores as MMIO ones.
            unsafe {
                write_volatile(tdtr, image.tdtr);
                write_volatile(tdlr, image.tdlr);
                write_volatile(tdhr, image.tdhr);
                write_volatile(tir, image.tir);
            }
            if self.stamp.is_none() {
                self.stamp = Some(systick_now());
            }
            self.txrq |= 1 << mailbox;
        }
    }
    fn abort(&mut self, mask: u8) {
        // SAFETY: as above.
        unsafe { write_volatile(&mut self.abrq, self.abrq | mask) };
    }
    fn is_bus_off(&self) -> bool {
        false
    }
}

/// TIM2 as the F103 driver uses it: 8 MHz counter extended by `WideClock`, CC1 = commit,
/// CC3 = prepare alarm; registers in RAM, time set by the bus model.
pub struct SimTimer {
    clock: WideClock,
    cnt: u32,
    sr: u32,
    dier: u32,
    ccr1: u32,
    ccr3: u32,
    /// The bus model's view of the alarms: tick of the next match (`u64::MAX`: none). In
    /// ticks, not ns: the critical sections store them, and a product there would count
    /// as the firmware's work.
    commit_at: u64,
    prepare_at: u64,
}

impl SimTimer {
    const fn new() -> Self {
        SimTimer {
            clock: WideClock::new(),
            cnt: 0,
            sr: 0,
            dier: 0,
            ccr1: 0,
            ccr3: 0,
            commit_at: u64::MAX,
            prepare_at: u64::MAX,
        }
    }

    /// The bus model: the counter reads local time `local` (and its half periods were
    /// counted by the interrupt).
    fn set(&mut self, local: Nanos) {
        let ticks = local / TICK_NS;
        self.clock = WideClock::from_half_periods((ticks >> 15) as u32);
        self.cnt = ticks as u16 as u32;
    }

    fn cnt(&self) -> u16 {
        // SAFETY: plain RAM owned by `self`.
        unsafe { read_volatile(&self.cnt) as u16 }
    }

    /// The slot-timer interrupt's flag handling: which alarms fired.
    /// Interrupt entry (the F103 driver's `SlotTimer::flags`): (commit, prepare, sr).
    fn flags(&self) -> (bool, bool, u32) {
        // SAFETY (all accesses here): plain RAM owned by `self`, volatile as registers.
        let sr = unsafe { read_volatile(&self.sr) };
        let dier = unsafe { read_volatile(&self.dier) };
        (
            sr & SR_CC1IF != 0 && dier & DIER_CC1IE != 0,
            sr & SR_CC3IF != 0 && dier & DIER_CC3IE != 0,
            sr,
        )
    }

    /// After the commit (`SlotTimer::acknowledge`); rc_w0 flags modelled as "written 0
    /// clears". No far targets here: the bus model wakes the node at its alarms.
    fn acknowledge(&mut self, commit: bool, prepare: bool, sr: u32) {
        unsafe { write_volatile(&mut self.sr, sr & !(SR_CC1IF | SR_CC3IF)) };
        if commit || prepare {
            let off =
                (if commit { DIER_CC1IE } else { 0 }) | (if prepare { DIER_CC3IE } else { 0 });
            unsafe { write_volatile(&mut self.dier, read_volatile(&self.dier) & !off) };
        }
        // The bus model's view of the alarms.
        if commit {
            self.commit_at = u64::MAX;
        }
        if prepare {
            self.prepare_at = u64::MAX;
        }
    }

    /// Channel bits of `alarm`: (DIER enable, SR flag).
    const fn bits(alarm: Alarm) -> (u32, u32) {
        match alarm {
            Alarm::Commit => (DIER_CC1IE, SR_CC1IF),
            Alarm::Prepare => (DIER_CC3IE, SR_CC3IF),
        }
    }

    fn set_at(&mut self, alarm: Alarm, at: u64) {
        match alarm {
            Alarm::Commit => self.commit_at = at,
            Alarm::Prepare => self.prepare_at = at,
        }
    }

    /// Software compare event (the F103's EGR write): flag and enable; the bus model
    /// runs the interrupt at once.
    fn raise(&mut self, alarm: Alarm) {
        let (ie, flag) = Self::bits(alarm);
        // SAFETY: plain RAM owned by `self`.
        unsafe {
            write_volatile(&mut self.sr, read_volatile(&self.sr) | flag);
            write_volatile(&mut self.dier, read_volatile(&self.dier) | ie);
        }
        self.set_at(alarm, 0);
    }
}

impl SlotTimerHw for SimTimer {
    fn ticks(&self) -> u64 {
        self.clock.ticks(self.cnt())
    }
    fn ns_of(ticks: u64) -> Nanos {
        ticks * TICK_NS
    }
    fn ticks_of(at: Nanos) -> u64 {
        at.div_ceil(TICK_NS)
    }
    // Inline: the alarm is a constant at each call site (as on the F103).
    #[inline(always)]
    fn arm(&mut self, alarm: Alarm, setting: AlarmSetting) {
        let (ie, flag) = Self::bits(alarm);
        let (value, target) = match setting {
            AlarmSetting::Off => {
                // SAFETY: plain RAM owned by `self`.
                unsafe { write_volatile(&mut self.dier, read_volatile(&self.dier) & !ie) };
                self.set_at(alarm, u64::MAX);
                return;
            }
            AlarmSetting::Due => return self.raise(alarm),
            AlarmSetting::Compare { value, at_ticks } => (value, at_ticks),
            // Re-evaluated at the half-period events on the F103; the bus model wakes the
            // node at the target itself.
            AlarmSetting::Later { at_ticks } => (0, at_ticks),
        };
        let ccr = match alarm {
            Alarm::Commit => &mut self.ccr1,
            Alarm::Prepare => &mut self.ccr3,
        };
        // SAFETY: plain RAM owned by `self`.
        unsafe {
            write_volatile(ccr, value as u32);
            write_volatile(&mut self.sr, read_volatile(&self.sr) & !flag);
            write_volatile(&mut self.dier, read_volatile(&self.dier) | ie);
        }
        // The compare matches at that tick (the bus model's event time).
        self.set_at(alarm, target);
    }
    fn rescue(&mut self, alarm: Alarm) {
        let (ie, flag) = Self::bits(alarm);
        // SAFETY: plain RAM owned by `self`.
        let (sr, dier) = unsafe { (read_volatile(&self.sr), read_volatile(&self.dier)) };
        if dier & ie != 0 && sr & flag == 0 {
            self.raise(alarm);
        }
    }
}

/// The slot-timer resource of a `SplitStation`.
pub type Core = SlotCore<SimTimer, ShadowTx>;

/// `Lock` on the slot-timer resource that measures each critical section.
struct MeteredLock<'a> {
    core: &'a mut Core,
    meter: &'a PathMeter,
}

impl Lock<Core> for MeteredLock<'_> {
    fn lock<R>(&mut self, f: impl FnOnce(&mut Core) -> R) -> R {
        let mut f = Some(f);
        let mut r = None;
        let core = &mut *self.core;
        self.meter.measure(Kind::CriticalSection, &mut || {
            if let Some(f) = f.take() {
                r = Some(f(core));
            }
        });
        match r {
            Some(r) => r,
            // `measure` runs its closure once.
            None => unreachable_none(),
        }
    }
}

#[allow(clippy::empty_loop)]
fn unreachable_none() -> ! {
    crate::fail()
}

/// RX FIFO 0 registers in RAM, filled by the bus model.
struct ShadowFifo {
    rfr: u32,
    mb: [u32; 4],
}

/// A module running the split architecture on the software bus.
pub struct SplitStation<'t, 'm, H: Host, const RX: usize, const A: usize, const Q: usize> {
    /// The engine.
    pub engine: Engine<'t, RX, A, Q>,
    /// The host above it.
    pub host: H,
    /// The controller on the bus.
    pub can: SoftCan,
    /// Local clock = bus time + offset.
    pub offset: Nanos,
    /// The slot-timer resource.
    pub core: Core,
    /// The protocol task's state.
    pub proto: Protocol,
    /// TTCM bit counter = bus bits + this.
    counter_offset: u64,
    bit_ns: Nanos,
    fifo: ShadowFifo,
    tsr: u32,
    rxq: Queue<RxEvent, 8>,
    txq: Queue<(u8, TxResult), 4>,
    /// Messages to submit on the next protocol-task run (the app's publications).
    submits: Deque<(u8, Token), 4>,
    meter: &'m PathMeter,
    /// Slot-timer interrupts taken (commits and prepare alarms).
    pub timer_interrupts: u32,
}

impl<'t, 'm, H: Host, const RX: usize, const A: usize, const Q: usize>
    SplitStation<'t, 'm, H, RX, A, Q>
{
    /// A station with local clock `bus + offset`, TTCM counter `bus bits + counter_offset`,
    /// preparing wake-ups `lead_ns` ahead, behind `filters`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        engine: Engine<'t, RX, A, Q>,
        host: H,
        offset: Nanos,
        counter_offset: u64,
        bitrate: u32,
        lead_ns: Nanos,
        filters: &'static [(u32, u32)],
        meter: &'m PathMeter,
    ) -> Self {
        let bit_ns = 1_000_000_000 / bitrate.max(1) as Nanos;
        SplitStation {
            engine,
            host,
            can: SoftCan::with_filters(filters),
            offset,
            core: SlotCore {
                timer: SimTimer::new(),
                plan: SlotPlan::new(),
                tx: ShadowTx::new(),
            },
            proto: Protocol::new(bit_ns as u32, 200, lead_ns),
            counter_offset,
            bit_ns,
            fifo: ShadowFifo { rfr: 0, mb: [0; 4] },
            tsr: 0,
            rxq: Queue::new(),
            txq: Queue::new(),
            submits: Deque::new(),
            meter,
            timer_interrupts: 0,
        }
    }

    /// The app published an SRT/NRT message: queued for the protocol task, which is
    /// pended at once (the firmware's kick); false if the queue is full.
    pub fn publish(&mut self, bus: Nanos, tx: u8, token: Token) -> bool {
        let ok = self.submits.push_back((tx, token)).is_ok();
        self.core.timer.set(bus + self.offset);
        self.protocol_task();
        ok
    }

    /// Start-up: the protocol task's first run (arms the first wake-up).
    pub fn start(&mut self, bus: Nanos) {
        self.core.timer.set(bus + self.offset);
        self.protocol_task();
    }

    /// The protocol task: queued RX events, completions, then `Protocol::run`.
    fn protocol_task(&mut self) {
        let meter = self.meter;
        let mut lock = MeteredLock {
            core: &mut self.core,
            meter,
        };
        while let Some(ev) = self.rxq.dequeue() {
            let sync_on_slave =
                ev.regs.frame().is_some_and(|f| f.id().is_sync()) && !self.engine.is_master();
            let kind = if sync_on_slave {
                Kind::TaskSyncSlave
            } else {
                Kind::TaskRxProcess
            };
            let (p, e, h) = (&mut self.proto, &mut self.engine, &mut self.host);
            meter.measure(kind, &mut || p.on_rx_event(&ev, e, h, &mut lock));
        }
        while let Some((m, r)) = self.txq.dequeue() {
            let (p, e, h) = (&mut self.proto, &mut self.engine, &mut self.host);
            meter.measure(Kind::TaskTxDone, &mut || {
                p.on_tx_done(Mailbox(m), r, e, h, &mut lock)
            });
        }
        let (p, e, h, subs) = (
            &mut self.proto,
            &mut self.engine,
            &mut self.host,
            &mut self.submits,
        );
        meter.measure(Kind::TaskPrepareSlot, &mut || {
            p.run(e, h, &mut lock, &mut |e, h, now, c| {
                while let Some((tx, tok)) = subs.pop_front() {
                    let _ = e.submit(now, tx, tok, &mut DynController(c), h);
                }
            })
        });
        self.core.tx.sync(&mut self.can);
    }

    /// The slot-timer interrupt body: flags, commit, pend the protocol task.
    fn slot_isr(core: &mut Core) -> bool {
        let (commit, prepare, sr) = core.timer.flags();
        // The boundary's TXRQ first, as the F103's `glue::on_slot_timer`.
        let committed = commit && core.on_commit();
        core.timer.acknowledge(commit, prepare, sr);
        committed || prepare
    }
}

impl<H: Host, const RX: usize, const A: usize, const Q: usize> Node
    for SplitStation<'_, '_, H, RX, A, Q>
{
    fn can(&mut self) -> &mut SoftCan {
        &mut self.can
    }
    fn local(&self, bus: Nanos) -> Nanos {
        bus + self.offset
    }
    fn next_wake_bus(&self) -> Nanos {
        let t = &self.core.timer;
        let at = t.commit_at.min(t.prepare_at);
        if at == u64::MAX {
            return Nanos::MAX;
        }
        at.saturating_mul(TICK_NS).saturating_sub(self.offset)
    }
    fn poll(&mut self, bus: Nanos, _meter: &mut dyn Meter) {
        let now = bus + self.offset;
        self.timer_interrupts += 1;
        self.core.timer.set(now);
        let t = &mut self.core.timer;
        if t.commit_at.saturating_mul(TICK_NS) <= now {
            t.sr |= SR_CC1IF;
        }
        if t.prepare_at.saturating_mul(TICK_NS) <= now {
            t.sr |= SR_CC3IF;
        }
        let meter = self.meter;
        let core = &mut self.core;
        core.tx.stamp = None;
        let mut pend = false;
        let start = meter.measure(Kind::IsrSlotTimer, &mut || pend = Self::slot_isr(core));
        // Some: a TXRQ written in the interrupt; outside it the stamp stays `Some(0)`.
        if let Some(stamp) = core.tx.stamp.replace(0) {
            meter.record_to_txrq(start, stamp);
        }
        self.core.tx.sync(&mut self.can);
        if pend {
            self.protocol_task();
        }
    }
    fn rx(&mut self, frame: &Frame, sof: Nanos, now: Nanos, _meter: &mut dyn Meter) {
        // The bus model: the frame in FIFO 0 with its TTCM stamp.
        let img = TxImage::of(frame);
        let time16 = (sof / self.bit_ns + self.counter_offset) as u16 as u32;
        self.fifo.mb = [img.tir, img.tdtr | (time16 << 16), img.tdlr, img.tdhr];
        self.fifo.rfr = 1;
        self.core.timer.set(now + self.offset);
        let (fifo, q, meter) = (&mut self.fifo, &mut self.rxq, self.meter);
        let timer = &self.core.timer;
        // The F103's RX interrupt reads the clock under the slot-timer resource's lock
        // (priority 3 below the slot timer's 4): that read is a critical section too,
        // measured alone (not nested: the meter's own work would count in the row).
        let mut ticks = 0;
        meter.measure(Kind::CriticalSection, &mut || ticks = timer.ticks());
        meter.measure(Kind::IsrCanRx, &mut || {
            can_rx_isr(fifo, SimTimer::ns_of(timer.ticks()), q)
        });
        let _ = ticks;
        self.protocol_task();
    }
    fn tx_done(&mut self, mailbox: Mailbox, result: TxResult, now: Nanos, _meter: &mut dyn Meter) {
        let shift = 8 * mailbox.0 as u32;
        self.tsr |= (TSR_RQCP
            | if result == TxResult::Sent {
                TSR_TXOK
            } else {
                0
            })
            << shift;
        self.core.timer.set(now + self.offset);
        let (tsr, q, meter) = (&mut self.tsr, &mut self.txq, self.meter);
        meter.measure(Kind::IsrCanTx, &mut || can_tx_isr(tsr, q));
        self.protocol_task();
    }
}

/// The CAN RX interrupt body: every frame of FIFO 0 with the local time `now` into the
/// queue.
fn can_rx_isr(fifo: &mut ShadowFifo, now: Nanos, q: &mut Queue<RxEvent, 8>) {
    loop {
        // SAFETY: plain RAM; volatile as the FIFO registers.
        let rfr = unsafe { read_volatile(&fifo.rfr) };
        if rfr & RFR_FOVR != 0 {
            let _ = q.enqueue(RxEvent::OVERRUN);
            unsafe { write_volatile(&mut fifo.rfr, rfr & !RFR_FOVR) };
        }
        if rfr & RFR_FMP == 0 {
            return;
        }
        let [rir, rdtr, rdlr, rdhr] = &fifo.mb;
        let regs = unsafe {
            TxImage {
                tir: read_volatile(rir),
                tdtr: read_volatile(rdtr),
                tdlr: read_volatile(rdlr),
                tdhr: read_volatile(rdhr),
            }
        };
        // Release the mailbox (RFOM); the model's FIFO held one frame.
        unsafe { write_volatile(&mut fifo.rfr, (rfr | RFR_RFOM) & !RFR_FMP & !RFR_RFOM) };
        if q.enqueue(RxEvent::frame(regs, now)).is_err() {
            let _ = q.enqueue(RxEvent::OVERRUN);
        }
    }
}

/// The CAN TX interrupt body: every completed mailbox and its result into the queue.
fn can_tx_isr(tsr: &mut u32, q: &mut Queue<(u8, TxResult), 4>) {
    // SAFETY: plain RAM; volatile as TSR.
    let status = unsafe { read_volatile(tsr) };
    for m in 0..MAILBOXES as u32 {
        let shift = 8 * m;
        if status & (TSR_RQCP << shift) != 0 {
            // Automatic retransmission is on: a completion without TXOK was aborted.
            let r = if status & (TSR_TXOK << shift) != 0 {
                TxResult::Sent
            } else {
                TxResult::Aborted
            };
            unsafe { write_volatile(tsr, read_volatile(tsr) & !((TSR_RQCP | TSR_TXOK) << shift)) };
            let _ = q.enqueue((m as u8, r));
        }
    }
}
