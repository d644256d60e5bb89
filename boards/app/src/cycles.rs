//! Bench build (`--features cycles`): the named interrupt paths of the QEMU rows
//! (`bash boards/run-qemu.sh`, boards/costs/cortex-m3.toml) measured on silicon with the
//! DWT cycle counter, printed over defmt every `PERIOD_S` seconds as
//! `CYCLES <row> max <n> mean <n> samples <n>` (cycles at 72 MHz, so the ratio to the
//! QEMU instruction counts is the real cycles-per-instruction). `slot_boundary_to_txrq`
//! is measured from the compare match itself (TIM2 counter minus CCR1 after the commit,
//! 125 ns = 9 cycles resolution): it includes interrupt entry and any blocking.
//! Without the feature every call here compiles to nothing.
use core::sync::atomic::{AtomicU32, Ordering};

/// Whether this build measures (the `cycles` feature); the app macro reads it, since a
/// `cfg!` in the macro would test the calling crate's features instead.
pub const ENABLED: bool = cfg!(feature = "cycles");

/// Seconds between two printed tables.
pub const PERIOD_S: u32 = 10;

/// Max, sum and count of one path, in cycles (statics: written from several priorities).
pub struct Path {
    name: &'static str,
    max: AtomicU32,
    sum: AtomicU32,
    n: AtomicU32,
}

impl Path {
    const fn new(name: &'static str) -> Self {
        Path {
            name,
            max: AtomicU32::new(0),
            sum: AtomicU32::new(0),
            n: AtomicU32::new(0),
        }
    }

    /// Adds a sample of `cycles`.
    pub fn add(&self, cycles: u32) {
        if cfg!(feature = "cycles") {
            self.max.fetch_max(cycles, Ordering::Relaxed);
            self.sum.fetch_add(cycles, Ordering::Relaxed);
            self.n.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// Adds the cycles since `start` (a `now()` reading).
    pub fn since(&self, start: u32) {
        self.add(now().wrapping_sub(start));
    }

    fn print_and_reset(&self) {
        let max = self.max.swap(0, Ordering::Relaxed);
        let sum = self.sum.swap(0, Ordering::Relaxed);
        let n = self.n.swap(0, Ordering::Relaxed);
        let mean = sum.checked_div(n).unwrap_or(0);
        defmt::info!(
            "CYCLES {=str} max {=u32} mean {=u32} samples {=u32}",
            self.name,
            max,
            mean,
            n
        );
    }
}

/// The slot-timer interrupt.
pub static ISR_SLOT_TIMER: Path = Path::new("isr_slot_timer");
/// The CAN RX interrupt.
pub static ISR_CAN_RX: Path = Path::new("isr_can_rx");
/// The CAN TX interrupt.
pub static ISR_CAN_TX: Path = Path::new("isr_can_tx");
/// One received frame in the protocol task (not a slave's sync).
pub static TASK_RX_PROCESS: Path = Path::new("task_rx_process");
/// A sync frame on a slave in the protocol task.
pub static TASK_SYNC_SLAVE: Path = Path::new("task_sync_slave");
/// One TX completion in the protocol task.
pub static TASK_TX_DONE: Path = Path::new("task_tx_done");
/// Pump and preparation of the next wake-up.
pub static TASK_PREPARE_SLOT: Path = Path::new("task_prepare_slot");
/// Compare match to the end of the commit (interrupt entry, blocking, TXRQ stores).
pub static SLOT_BOUNDARY_TO_TXRQ: Path = Path::new("slot_boundary_to_txrq");

const ALL: [&Path; 8] = [
    &ISR_SLOT_TIMER,
    &ISR_CAN_RX,
    &ISR_CAN_TX,
    &TASK_RX_PROCESS,
    &TASK_SYNC_SLAVE,
    &TASK_TX_DONE,
    &TASK_PREPARE_SLOT,
    &SLOT_BOUNDARY_TO_TXRQ,
];

/// Cycle counter (0 without the feature).
#[inline(always)]
pub fn now() -> u32 {
    if cfg!(feature = "cycles") {
        cortex_m::peripheral::DWT::cycle_count()
    } else {
        0
    }
}

/// Starts the cycle counter (init).
pub fn enable(dcb: &mut cortex_m::peripheral::DCB, dwt: &mut cortex_m::peripheral::DWT) {
    if cfg!(feature = "cycles") {
        dcb.enable_trace();
        dwt.enable_cycle_counter();
    }
}

/// Prints the table (from the app task) every `PERIOD_S` seconds of `now_ns`.
pub fn report(now_ns: u64, last: &mut u64) {
    if !cfg!(feature = "cycles") || now_ns < *last + PERIOD_S as u64 * 1_000_000_000 {
        return;
    }
    *last = now_ns;
    for p in ALL {
        p.print_and_reset();
    }
}
