//! Code shared by the six Triskar2 module images (src/bin/*.rs). Every image is the
//! same RTIC 2 app (`src/module_app.rs`, included by each bin after naming its module,
//! app and hardware): the module's generated engine and topics of
//! `rtcan::robot_toml` (the same statics the simulator runs), driven by the CAN and
//! slot-timer interrupts (`driver`), and one async task that polls the module's app
//! from `triskar2_nodes::app` on the hardware of `io` — the app code the simulator
//! runs, unchanged. Board start-up: `board`; the app task's sleep and wake-up: `run`.
#![no_std]

pub mod board;
pub mod cycles;
pub mod driver;
pub mod io;
pub mod run;

use defmt_rtt as _;

// Panics: panic-probe (fault, so the probe stops and shows the log). Its `print-defmt`
// (the panic message over defmt) formats the `PanicInfo` with `core::fmt` and keeps every
// panic site's location string: measured +3.9 KiB flash per image (motor1 30 636 →
// 34 576 B, `bash size-check.sh` / llvm-size), over the 32 KiB budget, so it is the feature `panic-message` for bring-up
// builds (`cargo run --release --features panic-message --bin motor1`). The firmware's
// own panics are `defmt::panic!`, which log their formatted message without it.
use panic_probe as _;

// SysTick monotonic at 1 kHz: wakes the app task at its due times. Time stamps and
// the app's clock come from the slot timer instead (125 ns ticks, the clock the
// engine and SOF stamps use).
rtic_monotonics::systick_monotonic!(Mono, 1_000);

/// SYSCLK, Hz (the clock tree of `rtcan_board_stm32f103`).
pub const SYSCLK_HZ: u32 = 72_000_000;

defmt::timestamp!("{=u32:ms}", {
    use rtic_monotonics::Monotonic;
    Mono::now().ticks()
});
