//! The protocol task's state (engine, the module's topics as its host, the split
//! architecture's `Protocol`), what the node tasks use to wake it, and the interrupt
//! priorities (RTIC logical, higher preempts; src/module_app.rs):
//!
//! | task | priority | work |
//! |---|---|---|
//! | `slot_timer` (TIM2) | [`SLOT_TIMER_PRIORITY`] = 15, highest | commit the prepared plan: TXRQ of the slot's frame, aborts |
//! | `can_rx`, `can_tx`, `can_sce` | [`CAN_PRIORITY`] = 14 | registers into lock-free queues; bus-off: abort all |
//! | `protocol` (EXTI1) | [`PROTOCOL_PRIORITY`] = 13 | SOF mapping, `Engine::on_rx` / `on_tx_done`, pump, prepare the next wake-up, wake the node tasks |
//! | one task per node | 1..=[`NODE_PRIORITY_LEVELS`] (12) | the node's `poll`, woken at its due time by the protocol task (slot clock) or by a message for it |
//! | `idle` | 0 | feeds the watchdog, sleeps (WFI) |
//! | SysTick (monotonic) | lowest | backs up the node tasks' wake-ups |
//!
//! A node's task priority is the rank of its robot.toml `priority` among the distinct
//! priorities of the robot's nodes (1 = the lowest; Triskar2's 1, 2, 3 stay 1, 2, 3), so
//! every module of a robot agrees and robot.toml's order is kept; a robot with more than
//! `NODE_PRIORITY_LEVELS` distinct priorities fails to build (asserted in each image).
//! The F103's NVIC has 4 priority bits (16 levels): the nodes get 12, and the three above
//! stay below 16 so RTIC's locks stay BASEPRI writes (RTIC masks the highest level with
//! PRIMASK).
//!
//! Only the slot-timer resource (`glue::Core`: TIM2, plan, TX mailboxes) is shared across
//! the interrupt priorities; its critical sections are a few dozen instructions (QEMU row
//! `critical_section_slot`), the blocking of the slot timer. Topics (rtcan-pubsub) are
//! shared by node tasks and the protocol task through `critical_section`: every topic
//! section is a ceiling lock at most at `PROTOCOL_PRIORITY` (the generated apps assert
//! each topic's ceiling, the highest priority of its accessors, against it).
//!
//! Critical sections (`critical_section::with`: the R2P topics and status, the wake-ups in
//! `run`, rtic-time's queue) raise BASEPRI to the protocol task's level,
//! `PROTOCOL_PRIORITY` (boards/stm32f103 `ceiling`, the one source of the number); the
//! slot timer and CAN ISRs are never blocked by them and never enter one (checked on each
//! acquisition). Hence the CAN SCE interrupt leaves its log lines to the protocol task
//! (`note_error_change`).
use core::sync::atomic::{AtomicU8, Ordering};

use heapless::spsc::Consumer;
use rtcan_board_stm32f103::common::protocol::{
    Alarm, AlarmSetting, DynController, Lock, SlotTimerHw,
};
use rtcan_board_stm32f103::common::{Protocol, RxEvent, Stamps, TxEvent};
use rtcan_board_stm32f103::glue::Core;
use rtcan_board_stm32f103::hal::gpio::Floating;
use rtcan_board_stm32f103::hal::pac::{Interrupt, NVIC};
use rtcan_board_stm32f103::slot_timer::SlotTimer;
use rtcan_board_stm32f103::ErrorChange;
use rtcan_core::engine::Engine;
use rtcan_core::id::CanId;
use rtcan_core::time::Nanos;
use rtcan_pubsub::{ModuleHost, SlotGrid};

use crate::cycles;
use crate::run::Wake;

/// RTIC priority of the protocol task (EXTI1), above every node task: the
/// critical-section ceiling (one source: the board crate's `ceiling`; the generated apps
/// assert their literals and topic ceilings against it).
pub use rtcan_board_stm32f103::ceiling::PROTOCOL_PRIORITY;

/// RTIC priority levels of the node tasks (1..=12): every level below the protocol task;
/// the CAN interrupts and the slot timer sit right above it.
pub const NODE_PRIORITY_LEVELS: u8 = PROTOCOL_PRIORITY - 1;
/// RTIC priority of the CAN RX/TX/SCE interrupts: above the protocol task.
pub const CAN_PRIORITY: u8 = PROTOCOL_PRIORITY + 1;
/// RTIC priority of the slot timer (TIM2): the highest, below RTIC's PRIMASK level (16).
pub const SLOT_TIMER_PRIORITY: u8 = CAN_PRIORITY + 1;
const _: () = assert!(SLOT_TIMER_PRIORITY < 16, "the F103's NVIC has 16 levels");

/// Interrupt of the protocol task (unused by the F103's peripherals in these images).
pub const PROTOCOL_INTERRUPT: Interrupt = Interrupt::EXTI1;

/// Error-state changes the CAN SCE interrupt saw since the protocol task last logged
/// them (bits `BUS_OFF`, `RECOVERED`): an atomic, so the interrupt logs nothing itself.
static ERROR_CHANGES: AtomicU8 = AtomicU8::new(0);
const BUS_OFF: u8 = 1;
const RECOVERED: u8 = 2;

/// Called by the CAN SCE interrupt: the protocol task logs `change` on its next run.
pub fn note_error_change(change: ErrorChange) {
    let bit = match change {
        ErrorChange::BusOff => BUS_OFF,
        ErrorChange::Recovered => RECOVERED,
        ErrorChange::None => return,
    };
    ERROR_CHANGES.fetch_or(bit, Ordering::Relaxed);
}

/// Logs the error-state changes noted since the last call (protocol task). One log line
/// for both (each defmt call site costs flash; proximity has a few dozen bytes left).
#[inline(never)]
fn log_error_changes() {
    // A plain load first: the common case (nothing noted) costs no exclusive access.
    if ERROR_CHANGES.load(Ordering::Relaxed) == 0 {
        return;
    }
    let changes = ERROR_CHANGES.swap(0, Ordering::Relaxed);
    defmt::warn!(
        "CAN error state: bus-off {=bool}, recovered {=bool}",
        changes & BUS_OFF != 0,
        changes & RECOVERED != 0
    );
}
/// Capacity of the RX event queue (the FIFO holds 3 frames; the protocol task may be
/// held off by one prepare, < 3 frames at 1 Mbit/s).
pub const RX_QUEUE: usize = 8;
/// Capacity of the TX event queue (3 mailboxes, bus-off).
pub const TX_QUEUE: usize = 8;
/// Drift bound between the local crystal and the bus bit clock, for SOF mapping.
const DRIFT_PPM: u32 = 200;

/// Pends the protocol task (a node published, a queue has events, an alarm fired).
pub fn pend_protocol() {
    NVIC::pend(PROTOCOL_INTERRUPT);
}

/// A node published: the protocol task hands SRT/NRT messages to the engine.
pub fn kick() {
    pend_protocol();
}

/// `Lock` over an RTIC shared-resource proxy.
pub struct Rtic<M>(pub M);

impl<M: rtic::Mutex> Lock<M::T> for Rtic<M> {
    fn lock<R>(&mut self, f: impl FnOnce(&mut M::T) -> R) -> R {
        self.0.lock(f)
    }
}

/// The slot-timer resource of these images.
pub type SlotCore = Core<Floating>;

/// Engine, the module's topics as the engine's host, and the protocol task's state.
pub struct Driver<const RX: usize, const ARENA: usize, const Q: usize> {
    engine: Engine<'static, RX, ARENA, Q>,
    host: ModuleHost<'static>,
    proto: Protocol,
    /// How early the protocol prepares a wake-up (half a slot).
    lead_ns: Nanos,
    /// Local time from which the slot grid in the module's status is refreshed (once a
    /// cycle, and at once when synchronisation is gained or lost).
    grid_until: Nanos,
    grid_synced: bool,
    /// The module's node tasks' wake-ups (the generated app's statics).
    wakes: &'static [Wake],
}

impl<const RX: usize, const ARENA: usize, const Q: usize> Driver<RX, ARENA, Q> {
    /// The driver over the module's generated engine and host, at `bitrate`, preparing
    /// wake-ups half a slot (`slot_ns / 2`) ahead, with SOF times from `stamps`, waking
    /// the node tasks of `wakes` at their due times.
    pub fn new(
        engine: Engine<'static, RX, ARENA, Q>,
        host: ModuleHost<'static>,
        bitrate: u32,
        slot_ns: Nanos,
        stamps: Stamps,
        wakes: &'static [Wake],
    ) -> Self {
        let bit_ns = 1_000_000_000 / bitrate.max(1);
        Driver {
            engine,
            host,
            proto: Protocol::new(bit_ns, DRIFT_PPM, slot_ns / 2).with_stamps(stamps),
            lead_ns: slot_ns / 2,
            grid_until: 0,
            grid_synced: false,
            wakes,
        }
    }

    /// One run of the protocol task: queued RX events (a delivery wakes the node tasks
    /// subscribing to remote topics at once, as the simulator runs them), queued TX
    /// events, then pump and prepare; then the node tasks that are due are woken and the
    /// prepare alarm set for the earliest one that is not.
    pub fn run(
        &mut self,
        rx: &mut Consumer<'_, RxEvent>,
        tx: &mut Consumer<'_, TxEvent>,
        slot: &mut impl Lock<SlotCore>,
    ) {
        log_error_changes();
        let delivered = self.engine.counters().rx_delivered;
        let (e, h, p) = (&mut self.engine, &mut self.host, &mut self.proto);
        while let Some(ev) = rx.dequeue() {
            let t = cycles::now();
            p.on_rx_event(&ev, e, h, slot);
            // From the identifier alone (no frame parse).
            let sync = !ev.is_overrun()
                && CanId::from_raw(ev.regs.tir >> 3).is_some_and(|id| id.is_sync());
            if sync && !e.is_master() {
                cycles::TASK_SYNC_SLAVE.since(t);
                // Bring-up check of the TTCM stamps (docs/BRINGUP.md; DEFMT_LOG=debug).
                defmt::debug!(
                    "sync: ttcm {=u16} offset {=i64}",
                    (ev.regs.tdtr >> 16) as u16,
                    p.sof_clock().offset().unwrap_or(0)
                );
            } else {
                cycles::TASK_RX_PROCESS.since(t);
            }
        }
        while let Some(ev) = tx.dequeue() {
            let t = cycles::now();
            p.on_tx_event(&ev, e, h, slot);
            cycles::TASK_TX_DONE.since(t);
        }
        let t = cycles::now();
        p.run(e, h, slot, &mut |e, h, now, c| {
            h.pump(e, now, &mut DynController(c));
        });
        cycles::TASK_PREPARE_SLOT.since(t);
        let now = slot.lock(|c| c.timer.now());
        self.refresh_grid(now);
        let delivered = self.engine.counters().rx_delivered != delivered;
        let mut earliest = Nanos::MAX;
        for w in self.wakes {
            match w.take_due(now) {
                Ok(_) => w.notify(),
                Err(due) => {
                    if delivered && w.on_delivery() {
                        w.notify();
                    }
                    earliest = earliest.min(due);
                }
            }
        }
        self.alarm(earliest, slot);
    }

    /// The slot grid into the module's status (where synchronous HRT publishers read
    /// their due times), once a cycle: the clock's rate moves it by ns per cycle.
    fn refresh_grid(&mut self, now: Nanos) {
        let synced = self.engine.is_synced();
        if synced == self.grid_synced && now < self.grid_until {
            return;
        }
        let grid = if synced {
            SlotGrid::of_clock(self.engine.clock(), now)
        } else {
            None
        };
        self.grid_synced = synced;
        self.grid_until = grid.map_or(Nanos::MAX, |g| {
            g.start.saturating_add(g.cycle_local.saturating_mul(3) / 2)
        });
        if !synced {
            // Not synchronised: nothing to refresh until that changes.
            self.grid_until = Nanos::MAX;
        }
        self.host.status().set_grid(grid);
    }

    /// Wakes the protocol task (and so a node task) at the earliest due time `due` when that
    /// comes before the protocol's own next run (the prepare alarm, half a slot before
    /// the engine's next wake-up): the prepare alarm is re-armed earlier; the protocol
    /// arms its own again when that run finds nothing to prepare.
    fn alarm(&mut self, due: Nanos, slot: &mut impl Lock<SlotCore>) {
        if due == Nanos::MAX {
            return;
        }
        let next_run = self.engine.next_wakeup().saturating_sub(self.lead_ns);
        if due < next_run {
            // Outside the critical sections: the conversion may divide, the 64-bit
            // compare decision is made on a clock read (`AlarmSetting::new`).
            let ticks = SlotTimer::ticks_of(due);
            let now_ticks = slot.lock(|c| c.timer.ticks());
            let setting = AlarmSetting::new(ticks, now_ticks);
            slot.lock(|c| c.timer.arm(Alarm::Prepare, setting));
            // The counter may have passed `ticks` while the compare was written: raise it.
            if slot.lock(|c| c.timer.ticks()) >= ticks {
                slot.lock(|c| c.timer.rescue(Alarm::Prepare));
            }
        }
    }
}
