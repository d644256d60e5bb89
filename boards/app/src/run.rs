//! What the module's app task (`src/module_app.rs`) needs around `App::poll`: sleeping
//! until the app's next due time or until a received message reached a local
//! subscriber, whichever comes first, and logging safe-state changes.
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
/// Longest sleep: every app is due at least once a second (the PSU's `battery`), so
/// this only bounds a wrong answer.
const MAX_SLEEP_MS: u32 = 1_000;

/// A flag with the waker of the one task waiting for it (set from the CAN RX
/// interrupt, awaited by the app task).
pub struct Notify {
    raised: Mutex<Cell<bool>>,
    waker: Mutex<Cell<Option<Waker>>>,
}

/// Raised when the engine delivered a received message to the module's topics.
pub static DELIVERED: Notify = Notify::new();

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

/// SysTick ticks to sleep from `now` to the app's next due time `due` (both on the
/// slot timer's clock): rounded up, plus one because the current tick is partly over,
/// so the app is due when it wakes (at most 1 ms late; `Every` keeps its phase).
pub fn sleep_ticks(now: Nanos, due: Nanos) -> u32 {
    let ticks = due.saturating_sub(now).div_ceil(TICK_NS).saturating_add(1);
    u32::try_from(ticks).map_or(MAX_SLEEP_MS, |t| t.min(MAX_SLEEP_MS))
}

/// Sleeps until the app's next due time, or less if a message is delivered meanwhile.
pub async fn sleep_until(now: Nanos, due: Nanos) {
    let at = Mono::now() + sleep_ticks(now, due).millis();
    // A timeout is the normal end: the app is due.
    let _ = Mono::timeout_at(at, DELIVERED.wait()).await;
}

/// Logs the safe-state reason when it changes (the app itself stops its nodes).
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
