//! RTCAN on QEMU's `lm3s6965evb` (a Cortex-M3 like the STM32F103): a software CAN bus
//! joining several engine instances in one program, so rtcan-core (and the middleware
//! and node code above it) run on the real Cortex-M3 instruction set. Binaries in
//! `src/bin` are on-target tests (exit code 0/1 through semihosting) and
//! instruction-count benchmarks (`meter`, QEMU `-icount`).
#![no_std]

pub mod bus;
pub mod ceiling;
pub mod meter;
pub mod robot;
pub mod soft_can;
pub mod split;
pub mod test_host;

use cortex_m_semihosting::{debug, hprintln};

pub use bus::{Node, SoftBus, Station};
pub use soft_can::SoftCan;

/// Ends the QEMU run with exit code 0.
pub fn pass() -> ! {
    debug::exit(debug::EXIT_SUCCESS);
    #[allow(clippy::empty_loop)]
    loop {}
}

/// Ends the QEMU run with exit code 1.
pub fn fail() -> ! {
    debug::exit(debug::EXIT_FAILURE);
    #[allow(clippy::empty_loop)]
    loop {}
}

/// Checks `cond`, printing `what` and failing the run (exit code 1) when false.
#[macro_export]
macro_rules! check {
    ($cond:expr, $($what:tt)+) => {
        if !$cond {
            cortex_m_semihosting::hprintln!("FAIL {}: {}", stringify!($cond), format_args!($($what)+));
            $crate::fail();
        }
    };
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    use core::sync::atomic::Ordering::Relaxed;
    if ceiling::VIOLATED.load(Relaxed) {
        // No print: it would take a critical section above the ceiling again.
        if ceiling::VIOLATION_EXPECTED.load(Relaxed) {
            // src/bin/ceiling.rs provoked it: the check worked.
            pass()
        }
        fail()
    }
    hprintln!("PANIC {}", info);
    fail()
}
