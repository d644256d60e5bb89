//! What each node task (`src/module_app.rs`) needs around its `poll`: sleeping until
//! the node's next due time or until a message for it arrived, whichever comes first
//! ([`Wake`], one per node task), and logging safe-state changes.
use core::cell::Cell;
use core::future::poll_fn;
use core::task::{Poll, Waker};

use critical_section::Mutex;
use rtcan_core::time::Nanos;
use rtcan_pubsub::{SafeReason, SystemStatus};
use rtic_monotonics::fugit::ExtU32;
use rtic_monotonics::Monotonic;

use crate::Mono;

/// Nanoseconds in one SysTick tick (1 ms).
const TICK_NS: Nanos = 1_000_000;
/// Longest sleep: every node is due at least once a second (the PSU's `battery`), so
/// this only bounds a wrong answer.
const MAX_SLEEP_MS: u32 = 1_000;

/// A flag with the waker of the one task waiting for it (set from the protocol task or
/// a local publisher's task, awaited by one node task: all at or below the
/// critical-section ceiling).
pub struct Notify {
    raised: Mutex<Cell<bool>>,
    waker: Mutex<Cell<Option<Waker>>>,
}

/// One node task's wake-up. Its next due time on the slot timer's clock (`Nanos::MAX`:
/// none) is written by the task before it sleeps and read by the protocol task, which
/// wakes the earliest of them through the slot timer's prepare alarm (125 ns ticks)
/// rather than the 1 ms SysTick: a synchronous HRT publisher (R2P §3.4.5) runs its lead
/// time before its slot, not up to 2 ms after (docs/EMULATOR.md "Findings"). The flag is
/// raised at that time, when the engine delivered a message and the node subscribes to a
/// topic published on another module (`on_delivery`), and by the task of a local node
/// publishing a topic it subscribes to.
pub struct Wake {
    due: Mutex<Cell<Nanos>>,
    notify: Notify,
    on_delivery: bool,
}

impl Wake {
    /// Nothing due; `on_delivery`: woken by the engine's deliveries (the node subscribes
    /// to a remote topic).
    pub const fn new(on_delivery: bool) -> Self {
        Wake {
            due: Mutex::new(Cell::new(Nanos::MAX)),
            notify: Notify::new(),
            on_delivery,
        }
    }

    /// Whether the engine's deliveries wake it.
    pub const fn on_delivery(&self) -> bool {
        self.on_delivery
    }

    /// The node's due time if it has come at `now` (then cleared: one wake per due
    /// time), else `Err(due)` (`Nanos::MAX`: none).
    pub fn take_due(&self, now: Nanos) -> Result<Nanos, Nanos> {
        critical_section::with(|cs| {
            let d = self.due.borrow(cs);
            let due = d.get();
            if due <= now {
                d.set(Nanos::MAX);
                Ok(due)
            } else {
                Err(due)
            }
        })
    }

    /// Wakes the node's task now.
    pub fn notify(&self) {
        self.notify.notify();
    }

    /// Sleeps until the node's next due time `due`, or less if it is notified meanwhile.
    /// The protocol task wakes it at `due` on the slot clock; the SysTick timeout (at
    /// most 2 ms later) only backs that up.
    pub async fn sleep_until(&self, now: Nanos, due: Nanos) {
        critical_section::with(|cs| self.due.borrow(cs).set(due));
        crate::driver::pend_protocol();
        let at = Mono::now() + sleep_ticks(now, due).millis();
        // A timeout is the normal end: the node is due.
        let _ = Mono::timeout_at(at, self.notify.wait()).await;
    }
}

impl Notify {
    /// Lowered, nobody waiting.
    pub const fn new() -> Self {
        Notify {
            raised: Mutex::new(Cell::new(false)),
            waker: Mutex::new(Cell::new(None)),
        }
    }

    /// Raises the flag and wakes the waiting task.
    pub fn notify(&self) {
        let waker = critical_section::with(|cs| {
            self.raised.borrow(cs).set(true);
            self.waker.borrow(cs).take()
        });
        if let Some(w) = waker {
            w.wake();
        }
    }

    /// Completes once the flag is raised (at once if it already is), lowering it.
    pub async fn wait(&self) {
        poll_fn(|cx| {
            critical_section::with(|cs| {
                if self.raised.borrow(cs).replace(false) {
                    Poll::Ready(())
                } else {
                    self.waker.borrow(cs).set(Some(cx.waker().clone()));
                    Poll::Pending
                }
            })
        })
        .await
    }
}

impl Default for Notify {
    fn default() -> Self {
        Self::new()
    }
}

/// SysTick ticks to sleep from `now` to a node's next due time `due` (both on the slot
/// timer's clock): rounded up, plus one because the current tick is partly over, so the
/// node is due when it wakes (at most 1 ms late; `Every` keeps its phase).
pub fn sleep_ticks(now: Nanos, due: Nanos) -> u32 {
    let ticks = due.saturating_sub(now).div_ceil(TICK_NS).saturating_add(1);
    u32::try_from(ticks).map_or(MAX_SLEEP_MS, |t| t.min(MAX_SLEEP_MS))
}

/// Logs the safe-state reason when it changes (the nodes themselves stop).
#[derive(Default)]
pub struct SafeLog {
    last: Option<SafeReason>,
}

impl SafeLog {
    /// No reason seen yet.
    pub const fn new() -> Self {
        SafeLog { last: None }
    }

    /// Logs `status`'s reason if it changed since the last call.
    pub fn update(&mut self, status: &SystemStatus) {
        let reason = status.safe_reason();
        if reason == self.last {
            return;
        }
        match reason {
            Some(r) => defmt::warn!("safe state required: {}", r),
            None => defmt::info!("safe state cleared"),
        }
        self.last = reason;
    }
}
