//! Code shared by the six Triskar2 module images (src/bin/*.rs, one RTIC 2 app each):
//! the robot's tables and topics (`robot`), the board start-up (`board`), the engine
//! driver the hardware tasks call (`driver`), module I/O (`io`) and the node loops that
//! run as async software tasks (`tasks`). Node logic itself is `triskar2_nodes`.
#![no_std]

pub mod board;
pub mod driver;
pub mod io;
pub mod robot;
pub mod tasks;

use defmt_rtt as _;
use panic_probe as _;

// SysTick monotonic at 1 kHz: wakes the periodic node loops. Time stamps come from the
// slot timer's clock instead (125 ns ticks, the clock the engine and SOF stamps use).
rtic_monotonics::systick_monotonic!(Mono, 1_000);

/// SYSCLK, Hz (the clock tree of `rtcan_board_stm32f103`).
pub const SYSCLK_HZ: u32 = 72_000_000;

defmt::timestamp!("{=u32:ms}", {
    use rtic_monotonics::Monotonic;
    Mono::now().ticks()
});

/// Logs a failed `spawn` from `init` (cannot happen: each task is spawned once).
pub fn spawned<E>(result: Result<(), E>, task: &str) {
    if result.is_err() {
        defmt::error!("task {} was already running", task);
    }
}
