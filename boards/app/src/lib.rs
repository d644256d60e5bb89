//! What every STM32F103 module image shares, whatever the robot: the RTIC 2 app
//! ([`module_app!`], one task per node at its robot.toml priority, invoked through the
//! module's generated `<module>_app!`), board start-up ([`board`]), the protocol task's
//! state and the priorities ([`driver`]), the node tasks' sleep and wake-up ([`run`]), the bench counters ([`cycles`]), the SysTick monotonic,
//! defmt over RTT and the panic handler. Triskar2 (examples/triskar2) and the workspaces
//! `rtcan new` writes link the same code, so a fix here reaches every robot.
#![no_std]

pub mod board;
pub mod cycles;
pub mod driver;
mod module_app;
pub mod run;

use defmt_rtt as _;

// Panics: panic-probe (fault, so the probe stops and shows the log). Its `print-defmt`
// (the panic message over defmt) formats the `PanicInfo` with `core::fmt` and keeps every
// panic site's location string: measured +3.9 KiB flash per image (motor1 30 636 →
// 34 576 B, `bash size-check.sh` / llvm-size), over the 32 KiB budget, so it is a feature
// of the image crates for bring-up builds (`cargo run --release --features panic-message
// --bin motor1`). The firmware's own panics are `defmt::panic!`, which log their
// formatted message without it.
use panic_probe as _;

// SysTick monotonic at 1 kHz: backs up the node tasks' wake-ups (the protocol task
// wakes them at their due times through the slot timer's prepare alarm, `run::Wake`)
// and stamps defmt lines. Time stamps and the nodes' clock come from the slot timer
// (125 ns ticks, the clock the engine and SOF stamps use).
rtic_monotonics::systick_monotonic!(Mono, 1_000);

/// SYSCLK, Hz (the clock tree of `rtcan_board_stm32f103`).
pub const SYSCLK_HZ: u32 = 72_000_000;

defmt::timestamp!("{=u32:ms}", {
    use rtic_monotonics::Monotonic;
    Mono::now().ticks()
});

/// The module's hardware as a node task sees it: the RTIC shared resource `hw` of the
/// module app, locked around each access. A crate giving its nodes hardware defines its
/// own `Locked` (so it may implement the nodes' hardware traits for it) and re-exports it
/// as `fw::Locked`; nodes without hardware (the `rtcan new` default) take this one.
pub struct Locked<M>(pub M);
