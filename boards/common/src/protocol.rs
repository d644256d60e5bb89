//! The split interrupt architecture, HAL-free so the STM32F103 firmware and the QEMU
//! board run the same code (and QEMU measures it):
//!
//! | context | priority | work |
//! |---|---|---|
//! | slot timer | highest | `SlotCore::on_commit`: apply the `SlotPlan` (TXRQ of the prepared frame, aborts) |
//! | CAN RX | high | move FIFO registers + local time into a lock-free queue (`RxEvent`) |
//! | CAN TX, SCE | high | move completions into a queue; bus-off: abort every mailbox at once |
//! | protocol task | below them | `Protocol`: SOF mapping, `Engine::on_rx` (reassembly, delivery, sync correction), completions, EDF refill, `Engine::poll` of the next wake-up *ahead of time* into the plan |
//! | SysTick, app | lowest | app, monotonic |
//!
//! The engine never runs in the slot-timer interrupt: the protocol task calls
//! `Engine::poll(at)` for the next wake-up `at` up to `lead_ns` early, through a
//! controller (`Gate`) that stages every load and abort into the armed plan instead of
//! touching the hardware, then publishes the plan with the compare at `at`. The slot
//! clock is the local clock model: a boundary never waits for the sync frame's
//! processing, which corrects the model for the later slots. Until the plan is committed
//! the engine already stands at `at`, so whatever it loads meanwhile (a refill after a
//! completion) is staged too and never starts before `at`.
//!
//! The slot-timer side (`SlotCore`: timer, plan, TX port) is one resource shared with the
//! slower contexts through short critical sections (`Lock`; RTIC priority ceilings): each
//! stages or writes one mailbox, reads the clock's registers, or publishes the plan with
//! the compare's register writes; every computation (frame images, the compare value,
//! nanoseconds from ticks) happens outside them. The blocking of the slot timer is the
//! longest of them, the QEMU row `critical_section_slot`, a term of
//! `slot_boundary_to_txrq`. Nothing in them waits for the clock: an alarm whose time
//! passed while it was armed is raised in software afterwards (`SlotTimerHw::rescue`),
//! and the interrupt, not the protocol task, applies the plan.
use crate::slot_plan::{SlotPlan, StagedAbort};
use crate::sof::{valid_bits_min, SofClock};
use crate::tx_image::{TxImage, TxPort};
use crate::wide_clock::{Arm, WideClock};
use core::marker::PhantomData;
use rtcan_core::confinement::ErrorState;
use rtcan_core::driver::{Controller, Host, Mailbox, TxResult};
use rtcan_core::engine::Engine;
use rtcan_core::frame::Frame;
use rtcan_core::time::Nanos;
use rtcan_core::timing::{worst_case_bits, INTERMISSION_BITS};

/// A `Controller` behind a trait object (for `Protocol::run`'s pump callback, e.g.
/// `ModuleHost::pump`, which takes `&mut impl Controller`).
pub struct DynController<'a>(pub &'a mut dyn Controller);

impl Controller for DynController<'_> {
    fn load(&mut self, mailbox: Mailbox, frame: &Frame) {
        self.0.load(mailbox, frame)
    }
    fn abort(&mut self, mailbox: Mailbox) {
        self.0.abort(mailbox)
    }
}

/// The two alarms of the slot timer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Alarm {
    /// The commit compare: the slot-timer interrupt applies the published plan.
    Commit,
    /// The prepare alarm: the slot-timer interrupt only pends the protocol task.
    Prepare,
}

/// How to set an alarm, decided from a clock reading outside the critical section that
/// applies it (`SlotTimerHw::arm`), for a 16-bit compare extended by `WideClock`: the
/// 64-bit comparisons happen here, the section only writes registers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AlarmSetting {
    /// No alarm (interrupt off).
    Off,
    /// The target is due already: raise the compare event in software.
    Due,
    /// Compare register value of the target tick `at_ticks`.
    Compare {
        /// Compare register value.
        value: u16,
        /// Target tick.
        at_ticks: u64,
    },
    /// Beyond the compare's range: re-evaluated at the half-period events.
    Later {
        /// Target tick.
        at_ticks: u64,
    },
}

impl AlarmSetting {
    /// The setting for target tick `at_ticks` (`u64::MAX`: none) when the clock read
    /// `now_ticks`. If the clock passes the target before the compare is written, the
    /// match is lost: the caller reads the clock after arming and calls `rescue`.
    pub const fn new(at_ticks: u64, now_ticks: u64) -> Self {
        if at_ticks == u64::MAX {
            return AlarmSetting::Off;
        }
        match WideClock::arm(at_ticks, now_ticks) {
            Arm::Due => AlarmSetting::Due,
            Arm::Compare(value) => AlarmSetting::Compare { value, at_ticks },
            Arm::Later => AlarmSetting::Later { at_ticks },
        }
    }
}

/// The local clock and the two alarms of the slot timer. What runs in the protocol
/// task's critical sections (`ticks`, `arm`, `rescue`) reads or writes registers;
/// conversions and 64-bit comparisons happen outside (`ns_of`, `ticks_of`,
/// `AlarmSetting::new`).
pub trait SlotTimerHw {
    /// Local time in timer ticks: the counter and its software extension, no conversion.
    fn ticks(&self) -> u64;
    /// Local time of tick `ticks`, ns.
    fn ns_of(ticks: u64) -> Nanos;
    /// Local time, ns.
    fn now(&self) -> Nanos {
        Self::ns_of(self.ticks())
    }
    /// Timer ticks of local time `at`, rounded up (it may divide, a library call on the
    /// Cortex-M3).
    fn ticks_of(at: Nanos) -> u64;
    /// Applies `setting` to `alarm`: register writes only.
    fn arm(&mut self, alarm: Alarm, setting: AlarmSetting);
    /// The clock read `at_ticks` or later after `arm(alarm, at_ticks, _)`: if the alarm is
    /// still armed and has not fired, its match was lost; raise it (the interrupt runs as
    /// if it matched).
    fn rescue(&mut self, alarm: Alarm);
}

/// The resource of the slot-timer interrupt.
pub struct SlotCore<T, P> {
    /// Local clock and alarms.
    pub timer: T,
    /// The prepared wake-up.
    pub plan: SlotPlan,
    /// Transmit mailboxes.
    pub tx: P,
}

impl<T: SlotTimerHw, P: TxPort> SlotCore<T, P> {
    /// The commit compare matched: apply the published plan. True if one was (then pend
    /// the protocol task, which prepares the next wake-up). Inline: the interrupt's path.
    #[inline(always)]
    pub fn on_commit(&mut self) -> bool {
        self.plan.commit(&mut self.tx)
    }
}

/// Exclusive access to a resource shared with a higher priority (an RTIC lock).
pub trait Lock<C> {
    /// Runs `f` with the resource, higher priorities that share it held off.
    fn lock<R>(&mut self, f: impl FnOnce(&mut C) -> R) -> R;
}

/// `Lock` for a resource nothing else runs against (tests, single-context models).
pub struct Direct<'a, C>(pub &'a mut C);

impl<C> Lock<C> for Direct<'_, C> {
    fn lock<R>(&mut self, f: impl FnOnce(&mut C) -> R) -> R {
        f(self.0)
    }
}

/// What the CAN RX interrupt queues for the protocol task: FIFO mailbox registers (RIR,
/// RDTR, RDLR, RDHR, the layout of a `TxImage`) and the local time the interrupt read
/// them, or an overrun. A plain 24-byte struct, not an enum: the interrupt's copy into
/// the queue is a few stores (an enum cost 90 more instructions at opt-level z).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RxEvent {
    /// The registers; `RIR = u32::MAX` (bit 0 is reserved, always 0 in a received
    /// frame) marks an overrun.
    pub regs: TxImage,
    /// Local time of the RX interrupt, ns.
    pub now: Nanos,
}

impl RxEvent {
    /// The FIFO overran (bxCAN FOVR).
    pub const OVERRUN: RxEvent = RxEvent {
        regs: TxImage {
            tir: u32::MAX,
            tdtr: 0,
            tdlr: 0,
            tdhr: 0,
        },
        now: 0,
    };

    /// A received frame's registers at local time `now`.
    pub const fn frame(regs: TxImage, now: Nanos) -> Self {
        RxEvent { regs, now }
    }

    /// True for the overrun marker.
    pub const fn is_overrun(&self) -> bool {
        self.regs.tir == u32::MAX
    }
}

/// What the CAN TX and status-change interrupts queue for the protocol task.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TxEvent {
    /// A mailbox completed (automatic retransmission on: without TXOK it was aborted).
    Done(Mailbox, TxResult),
    /// The controller entered bus-off (the interrupt already aborted every mailbox).
    BusOff,
}

/// Counters of the protocol task (the engine counts protocol-level events).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProtocolStats {
    /// Standard-ID or remote frames: not RTCAN, dropped.
    pub rx_foreign: u32,
    /// Wake-ups the protocol task reached after they were due (then run directly).
    pub late_prepares: u32,
    /// Loads held back while bus-off or not yet re-synchronised after it.
    pub muted_loads: u32,
    /// Bus-off entries handled.
    pub bus_off: u32,
}

/// Where a received frame's SOF time comes from, chosen per board.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stamps {
    /// bxCAN time-triggered mode: the 16-bit bit-time stamp of the SOF (`SofClock`);
    /// error: the best RX latency plus stuff bits seen.
    Ttcm,
    /// For controllers without (working) TTCM: the RX interrupt's time minus the frame's
    /// worst-case length to its valid point. Error: between −(maximum stuff bits) and
    /// +(this interrupt's latency), per frame — larger, and the timing check must count it.
    RxTime,
}

/// Transmit state after a bus-off.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mute {
    /// Transmitting normally.
    Off,
    /// Bus-off: wait for the hardware recovery.
    UntilRecovery,
    /// Recovered: the engine forgot its slot clock and listens (§5.7); transmit again
    /// once a sync re-synchronised it, or (master-capable) once it took the sync over.
    UntilSync,
}

/// The protocol task's state besides the engine and the host.
pub struct Protocol {
    sof: SofClock,
    stamps: Stamps,
    bit_ns: Nanos,
    lead_ns: Nanos,
    g: GateState,
}

/// What the engine's controller (`Gate`) reads and updates besides the slot-timer
/// resource, in one struct: a `Gate` is then two pointers, built in a few instructions
/// on every receive, completion and prepare (issue 10: the sync path's budget).
struct GateState {
    /// Mailboxes to report `Aborted` to the engine (staged loads cancelled or held back).
    synthetic: u8,
    /// Mailboxes whose load is held back (muted), in the engine's view loaded.
    parked: u8,
    mute: Mute,
    stats: ProtocolStats,
}

/// The engine's controller inside the protocol task: loads and aborts go to the armed
/// plan, to the hardware when none is armed, nowhere while muted.
struct Gate<'a, L, T, P> {
    slot: &'a mut L,
    _core: PhantomData<fn() -> (T, P)>,
    g: &'a mut GateState,
}

impl<L, T, P> Controller for Gate<'_, L, T, P>
where
    L: Lock<SlotCore<T, P>>,
    T: SlotTimerHw,
    P: TxPort,
{
    // Out of line: the engine loads from several places; one copy keeps the images small.
    #[inline(never)]
    fn load(&mut self, mailbox: Mailbox, frame: &Frame) {
        let m = mailbox.0 as usize;
        if m >= rtcan_core::driver::MAILBOXES {
            return;
        }
        if self.g.mute != Mute::Off {
            self.g.parked |= 1 << m;
            self.g.stats.muted_loads = self.g.stats.muted_loads.saturating_add(1);
            return;
        }
        // The image is computed outside the critical section.
        let image = TxImage::of(frame);
        self.slot.lock(|c| {
            if !c.plan.stage_load(m, image) {
                c.tx.write(m, &image);
            }
        });
    }

    #[inline(never)]
    fn abort(&mut self, mailbox: Mailbox) {
        let m = mailbox.0 as usize;
        if m >= rtcan_core::driver::MAILBOXES {
            return;
        }
        let bit = 1u8 << m;
        if self.g.parked & bit != 0 {
            self.g.parked &= !bit;
            self.g.synthetic |= bit;
            return;
        }
        // Bus-off: every mailbox was aborted at once (`on_bus_off`) and the plan dropped;
        // the engine's aborts, one per mailbox it had loaded, are done already and their
        // completions come from the hardware. Writing them again would abort one by one.
        let bus_off = self.g.mute == Mute::UntilRecovery;
        let cancelled = self.slot.lock(|c| match c.plan.stage_abort(m) {
            StagedAbort::Cancelled => true,
            StagedAbort::Deferred => false,
            StagedAbort::NotArmed => {
                if !bus_off {
                    c.tx.abort(bit);
                }
                false
            }
        });
        if cancelled {
            self.g.synthetic |= bit;
        }
    }
}

impl Protocol {
    /// Bit time `bit_ns`, drift bound `drift_ppm` between local and bus clock (SOF
    /// mapping), and how early a wake-up is prepared, `lead_ns` (above the protocol task's
    /// worst response time: its longest step plus what preempts it).
    pub const fn new(bit_ns: u32, drift_ppm: u32, lead_ns: Nanos) -> Self {
        Protocol {
            sof: SofClock::new(bit_ns, drift_ppm),
            stamps: Stamps::Ttcm,
            bit_ns: bit_ns as Nanos,
            lead_ns,
            g: GateState {
                synthetic: 0,
                parked: 0,
                mute: Mute::Off,
                stats: ProtocolStats {
                    rx_foreign: 0,
                    late_prepares: 0,
                    muted_loads: 0,
                    bus_off: 0,
                },
            },
        }
    }

    /// The same with SOF times from `stamps` (default: TTCM).
    pub const fn with_stamps(mut self, stamps: Stamps) -> Self {
        self.stamps = stamps;
        self
    }

    /// Counters.
    pub const fn stats(&self) -> &ProtocolStats {
        &self.g.stats
    }

    /// The SOF clock (TTCM offset estimate).
    pub const fn sof_clock(&self) -> &SofClock {
        &self.sof
    }

    /// True while transmissions are held back after a bus-off.
    pub fn is_muted(&self) -> bool {
        self.g.mute != Mute::Off
    }

    fn gate<'a, L, T, P>(&'a mut self, slot: &'a mut L) -> Gate<'a, L, T, P> {
        Gate {
            slot,
            _core: PhantomData,
            g: &mut self.g,
        }
    }

    /// One queued RX event: SOF time from the TTCM stamp (bounds, no bit stuffing), then
    /// `Engine::on_rx` (sync correction, reassembly, delivery).
    pub fn on_rx_event<L, T, P, H, const RX: usize, const A: usize, const Q: usize>(
        &mut self,
        event: &RxEvent,
        engine: &mut Engine<'_, RX, A, Q>,
        host: &mut H,
        slot: &mut L,
    ) where
        L: Lock<SlotCore<T, P>>,
        T: SlotTimerHw,
        P: TxPort,
        H: Host,
    {
        if event.is_overrun() {
            engine.on_rx_overrun();
            return;
        }
        let (regs, now) = (event.regs, event.now);
        let Some(frame) = regs.frame() else {
            self.g.stats.rx_foreign = self.g.stats.rx_foreign.saturating_add(1);
            return;
        };
        let sof = match self.stamps {
            Stamps::Ttcm => {
                self.sof
                    .sof((regs.tdtr >> 16) as u16, valid_bits_min(frame.dlc()), now)
            }
            Stamps::RxTime => {
                let bits = worst_case_bits(frame.dlc()) - INTERMISSION_BITS - 1;
                now.saturating_sub(bits as Nanos * self.bit_ns)
            }
        };
        let mut gate = self.gate(slot);
        engine.on_rx(&frame, sof, &mut gate, host);
        if frame.id().is_sync() && self.g.mute == Mute::UntilSync && engine.is_synced() {
            // Re-synchronised after a bus-off: transmit again from the next wake-up.
            self.g.mute = Mute::Off;
            self.release_parked(slot);
        }
    }

    /// A TX completion moved out of the CAN TX interrupt.
    pub fn on_tx_done<L, T, P, H, const RX: usize, const A: usize, const Q: usize>(
        &mut self,
        mailbox: Mailbox,
        result: TxResult,
        engine: &mut Engine<'_, RX, A, Q>,
        host: &mut H,
        slot: &mut L,
    ) where
        L: Lock<SlotCore<T, P>>,
        T: SlotTimerHw,
        P: TxPort,
        H: Host,
    {
        let now = T::ns_of(slot.lock(|c| c.timer.ticks()));
        let mut gate = self.gate(slot);
        engine.on_tx_done(mailbox, result, now, &mut gate, host);
    }

    /// One queued TX event.
    pub fn on_tx_event<L, T, P, H, const RX: usize, const A: usize, const Q: usize>(
        &mut self,
        event: &TxEvent,
        engine: &mut Engine<'_, RX, A, Q>,
        host: &mut H,
        slot: &mut L,
    ) where
        L: Lock<SlotCore<T, P>>,
        T: SlotTimerHw,
        P: TxPort,
        H: Host,
    {
        match *event {
            TxEvent::Done(m, r) => self.on_tx_done(m, r, engine, host, slot),
            TxEvent::BusOff => self.on_bus_off(engine, host, slot),
        }
    }

    /// Bus-off seen (status-change interrupt, after it aborted every mailbox): the plan
    /// is dropped so no sync or HRT frame goes out late after the recovery, every mailbox
    /// is aborted in one write, and nothing is transmitted until the controller recovered
    /// and the engine re-synchronised on two syncs or (master-capable, after listening for
    /// its takeover time) took the sync over (docs/PROTOCOL.md §5.6, §5.7).
    #[cold]
    #[inline(never)]
    pub fn on_bus_off<L, T, P, H, const RX: usize, const A: usize, const Q: usize>(
        &mut self,
        engine: &mut Engine<'_, RX, A, Q>,
        host: &mut H,
        slot: &mut L,
    ) where
        L: Lock<SlotCore<T, P>>,
        T: SlotTimerHw,
        P: TxPort,
        H: Host,
    {
        let cancelled = slot.lock(|c| {
            // The status-change interrupt may have blocked it already; blocked until the
            // module transmits again.
            c.plan.block();
            let cancelled = c.plan.disarm();
            c.tx.abort(0b111);
            cancelled
        });
        self.g.synthetic |= cancelled;
        self.g.mute = Mute::UntilRecovery;
        self.g.stats.bus_off = self.g.stats.bus_off.saturating_add(1);
        // The engine counts it, steps down if it was the master and stays silent until
        // it re-synchronised (docs/PROTOCOL.md §5.7). bxCAN's TEC saturates at bus-off.
        let now = T::ns_of(slot.lock(|c| c.timer.ticks()));
        let off = ErrorState {
            tec: 255,
            rec: 0,
            bus_off: true,
        };
        engine.on_error_state(now, off, &mut self.gate(slot), host);
    }

    #[cold]
    #[inline(never)]
    fn release_parked<L, T, P>(&mut self, slot: &mut L)
    where
        L: Lock<SlotCore<T, P>>,
        T: SlotTimerHw,
        P: TxPort,
    {
        // Held-back frames were placed for slots that are over: never send them late.
        self.g.synthetic |= self.g.parked;
        self.g.parked = 0;
        slot.lock(|c| c.plan.unblock());
    }

    /// Everything but RX and completions: mute state, cancelled loads reported as
    /// aborted, the host's queued SRT/NRT messages (`pump`), and the next wake-up: run
    /// late ones at once, prepare one within `lead_ns`, else arm the prepare alarm.
    pub fn run<L, T, P, H, const RX: usize, const A: usize, const Q: usize>(
        &mut self,
        engine: &mut Engine<'_, RX, A, Q>,
        host: &mut H,
        slot: &mut L,
        pump: &mut dyn FnMut(&mut Engine<'_, RX, A, Q>, &mut H, Nanos, &mut dyn Controller),
    ) where
        L: Lock<SlotCore<T, P>>,
        T: SlotTimerHw,
        P: TxPort,
        H: Host,
    {
        if self.g.mute == Mute::Off && slot.lock(|c| c.plan.is_blocked()) {
            // The status-change interrupt blocked the plan but its event was lost (queue
            // full): handle the bus-off now.
            self.on_bus_off(engine, host, slot);
        }
        if self.g.mute == Mute::UntilRecovery && !slot.lock(|c| c.tx.is_bus_off()) {
            // Recovered (128 × 11 recessive bits): the engine listens again from now.
            let now = T::ns_of(slot.lock(|c| c.timer.ticks()));
            engine.on_error_state(now, ErrorState::default(), &mut self.gate(slot), host);
            // A master steps down at bus-off and listens first (PROTOCOL §5.6, §5.7):
            // like a slave, it transmits again after a sync, its own after a takeover.
            self.g.mute = Mute::UntilSync;
        }
        self.unmute_on_takeover(engine, slot);
        self.report_synthetic(engine, host, slot);
        let now = T::ns_of(slot.lock(|c| c.timer.ticks()));
        pump(engine, host, now, &mut self.gate(slot));
        self.report_synthetic(engine, host, slot);
        self.prepare(engine, host, slot);
    }

    /// Recovered and listening, the engine took the sync over (nobody else sent one for
    /// its takeover time, §5.6): its own sync defines the slots, it transmits again.
    fn unmute_on_takeover<L, T, P, const RX: usize, const A: usize, const Q: usize>(
        &mut self,
        engine: &Engine<'_, RX, A, Q>,
        slot: &mut L,
    ) where
        L: Lock<SlotCore<T, P>>,
        T: SlotTimerHw,
        P: TxPort,
    {
        if self.g.mute == Mute::UntilSync && engine.is_master() {
            self.g.mute = Mute::Off;
            self.release_parked(slot);
        }
    }

    fn report_synthetic<L, T, P, H, const RX: usize, const A: usize, const Q: usize>(
        &mut self,
        engine: &mut Engine<'_, RX, A, Q>,
        host: &mut H,
        slot: &mut L,
    ) where
        L: Lock<SlotCore<T, P>>,
        T: SlotTimerHw,
        P: TxPort,
        H: Host,
    {
        // One pass over the mask: a report may refill (and so park or stage again), which
        // is reported on the next run, so this cannot loop.
        let mask = core::mem::replace(&mut self.g.synthetic, 0);
        for m in 0..rtcan_core::driver::MAILBOXES as u8 {
            if mask & (1 << m) != 0 {
                self.on_tx_done(Mailbox(m), TxResult::Aborted, engine, host, slot);
            }
        }
    }

    /// Prepares the next wake-up if it is within `lead_ns` (and no plan is armed): stages
    /// what `Engine::poll` loads and aborts for it, then publishes the plan with its
    /// commit compare in one short critical section.
    pub fn prepare<L, T, P, H, const RX: usize, const A: usize, const Q: usize>(
        &mut self,
        engine: &mut Engine<'_, RX, A, Q>,
        host: &mut H,
        slot: &mut L,
    ) where
        L: Lock<SlotCore<T, P>>,
        T: SlotTimerHw,
        P: TxPort,
        H: Host,
    {
        // Bounded: each pass handles one wake-up that is already due, and a wake-up in the
        // future ends the loop; the bound only guards against a clock that stands still.
        for _ in 0..16 {
            let (now_ticks, armed) = slot.lock(|c| (c.timer.ticks(), c.plan.is_armed()));
            if armed {
                return;
            }
            let now = T::ns_of(now_ticks);
            let at = engine.next_wakeup();
            if at == Nanos::MAX {
                slot.lock(|c| c.timer.arm(Alarm::Prepare, AlarmSetting::Off));
                return;
            }
            // The takeover happens in a `poll` below (the engine then starts its first
            // cycle a slot later): prepare that cycle's sync normally.
            self.unmute_on_takeover(engine, slot);
            // Muted (bus-off): no plan (nothing may be applied); the engine runs at its
            // wake-ups and whatever it loads is held back by the gate.
            let muted = self.g.mute != Mute::Off;
            if at <= now {
                if !muted {
                    // Too late to prepare: run it now, loading directly.
                    self.g.stats.late_prepares = self.g.stats.late_prepares.saturating_add(1);
                }
                engine.poll(now, &mut self.gate(slot), host);
                continue;
            }
            let lead = if muted { 0 } else { self.lead_ns };
            if at - now > lead {
                let ticks = T::ticks_of(at - lead);
                let setting = AlarmSetting::new(ticks, now_ticks);
                slot.lock(|c| c.timer.arm(Alarm::Prepare, setting));
                Self::rescue_if_passed(slot, Alarm::Prepare, ticks);
                return;
            }
            let ticks = T::ticks_of(at);
            slot.lock(|c| c.plan.arm(at));
            engine.poll(at, &mut self.gate(slot), host);
            // `now_ticks` is older than `at` (checked above), so the compare is never
            // "due" here; if `at` passed while the engine ran, `rescue` raises it.
            let setting = AlarmSetting::new(ticks, now_ticks);
            let published = slot.lock(|c| {
                let staged = c.plan.publish();
                if staged {
                    c.timer.arm(Alarm::Commit, setting);
                }
                staged
            });
            if published {
                Self::rescue_if_passed(slot, Alarm::Commit, ticks);
            }
            return;
        }
    }

    /// After arming `alarm` at `at_ticks`: if the clock has reached it meanwhile, the
    /// compare may have been written after the counter passed it; `rescue` raises it
    /// then. Two short sections (a clock read, then the check), not one long one.
    fn rescue_if_passed<L, T, P>(slot: &mut L, alarm: Alarm, at_ticks: u64)
    where
        L: Lock<SlotCore<T, P>>,
        T: SlotTimerHw,
        P: TxPort,
    {
        if slot.lock(|c| c.timer.ticks()) >= at_ticks {
            slot.lock(|c| c.timer.rescue(alarm));
        }
    }
}
