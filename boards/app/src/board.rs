//! Start-up common to every module: clock tree (HSE 8 MHz → SYSCLK 72 MHz, PCLK1
//! 36 MHz, the constants of `rtcan_board_stm32f103`), bxCAN on PA11/PA12 at the robot's
//! bit rate (`btr`) with the module's acceptance filters, the slot timer on TIM2. What is left
//! goes to the module's hardware ([`FromBoard`]: Triskar2's examples/triskar2/src/io.rs, or
//! [`NoHw`] in a scaffolded image whose nodes have no drivers yet).
use rtcan_board_stm32f103::hal::afio::{self, AfioExt};
use rtcan_board_stm32f103::hal::can::CanExt;
use rtcan_board_stm32f103::hal::gpio::Floating;
use rtcan_board_stm32f103::hal::gpio::{gpioa, gpiob, Cr, GpioExt};
use rtcan_board_stm32f103::hal::pac;
use rtcan_board_stm32f103::hal::prelude::*;
use rtcan_board_stm32f103::hal::rcc::{self, Rcc};
use rtcan_board_stm32f103::hal::watchdog::IndependentWatchdog;
use rtcan_board_stm32f103::{configure, CanParts, FilterSet, SlotTimer, PCLK1_HZ, TIM2_CLOCK_HZ};

use crate::SYSCLK_HZ;

/// Pins left for the modules, with their port configuration registers.
pub struct Pins {
    /// ADC1 channels 0..3: IR rangers (proximity), battery voltage/current (psu).
    pub adc: (gpioa::PA0, gpioa::PA1, gpioa::PA2, gpioa::PA3),
    /// TIM3 CH1/CH2: motor encoder A/B (input, floating).
    pub encoder: (gpioa::PA6, gpioa::PA7),
    /// USART1 TX/RX: gateway host link.
    pub usart1: (gpioa::PA9, gpioa::PA10),
    /// TIM4 CH1/CH2: H-bridge PWM forward/reverse.
    pub pwm: (gpiob::PB6, gpiob::PB7),
    /// Port A low configuration register (PA0..PA7).
    pub a_crl: Cr<'A', false>,
    /// Port A high configuration register (PA8..PA15).
    pub a_crh: Cr<'A', true>,
    /// Port B low configuration register (PB0..PB7).
    pub b_crl: Cr<'B', false>,
}

/// What the engine's driver gets from the common start-up.
pub struct Bus {
    /// CAN controller, enabled, filters programmed, split by interrupt.
    pub can: CanParts<Floating>,
    /// TIM2 slot timer, running.
    pub timer: SlotTimer,
    /// Independent watchdog, running (`WATCHDOG_MS`): feed it from the app task.
    pub watchdog: IndependentWatchdog,
}

/// Watchdog period: twice the app task's longest sleep (`run::MAX_SLEEP_MS`).
pub const WATCHDOG_MS: u32 = 2_000;
/// Polls of HSERDY before giving up (the crystal starts in ~2 ms; a poll is > 100 ns at
/// the 8 MHz HSI the core runs on until then, so this waits > 50 ms).
const HSE_POLLS: u32 = 500_000;

/// What is left for the module's hardware after the common start-up.
pub struct Board {
    /// Clocks and bus enables.
    pub rcc: Rcc,
    /// The pins the module images use (PA11/PA12 are CAN's).
    pub pins: Pins,
    /// Alternate-function remapping.
    pub afio: afio::Parts,
    /// Peripherals left for the module: ADC1 (rangers, battery).
    pub adc1: pac::ADC1,
    /// TIM3 (motor encoder).
    pub tim3: pac::TIM3,
    /// TIM4 (motor PWM).
    pub tim4: pac::TIM4,
    /// USART1 (gateway host link).
    pub usart1: pac::USART1,
    /// DMA1 (gateway host link: USART1 RX on channel 5).
    pub dma1: pac::DMA1,
}

/// A module's hardware, built from what the common start-up left.
pub trait FromBoard {
    /// Configures the peripherals and pins the module uses.
    fn from_board(board: Board) -> Self;
}

/// The hardware of an image whose nodes use none: every pin and peripheral left at
/// its reset state (the default of a workspace written by `rtcan new`).
pub struct NoHw;

impl FromBoard for NoHw {
    fn from_board(_board: Board) -> Self {
        NoHw
    }
}

/// Brings the board up; `btr` = `can_btr!(PCLK1_HZ, BUS.bitrate)` of the robot (computed
/// by the app macro at compile time, so an unreachable bit rate is a compile error),
/// `filters` = the module's `filter_set!(FILTERS)`.
pub fn init(dp: pac::Peripherals, btr: u32, filters: FilterSet) -> (Bus, Board) {
    // Start the crystal with a bounded wait: the HAL's `freeze` waits for HSERDY for
    // ever, which on a board with a dead or missing crystal is a silent hang.
    dp.RCC.cr().modify(|_, w| w.hseon().set_bit());
    let mut polls = 0;
    while dp.RCC.cr().read().hserdy().bit_is_clear() {
        polls += 1;
        if polls >= HSE_POLLS {
            // defmt::panic! logs at error level, then stops (panic-probe).
            defmt::panic!(
                "HSE (8 MHz crystal) not ready after {=u32} polls",
                HSE_POLLS
            );
        }
    }
    let mut flash = dp.FLASH.constrain();
    let mut rcc = dp.RCC.freeze(
        rcc::Config::hse(8.MHz())
            .sysclk(SYSCLK_HZ.Hz())
            .pclk1(PCLK1_HZ.Hz()),
        &mut flash.acr,
    );
    // The CAN bit timing and the slot timer's prescaler are constants computed for
    // this clock tree: refuse to run the bus at a wrong rate.
    if rcc.clocks.pclk1().raw() != PCLK1_HZ || rcc.clocks.pclk1_tim().raw() != TIM2_CLOCK_HZ {
        defmt::panic!(
            "clock tree: PCLK1 {} Hz, TIM2 {} Hz",
            rcc.clocks.pclk1().raw(),
            rcc.clocks.pclk1_tim().raw()
        );
    }
    let mut gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);
    // PB3/PB4/PA15 stay JTAG: SWD (what probe-rs uses) does not need them released.
    let afio = dp.AFIO.constrain(&mut rcc);
    let tx = gpioa.pa12.into_alternate_push_pull(&mut gpioa.crh);
    let can = dp.CAN.can::<Floating>(dp.USB, (tx, gpioa.pa11), &mut rcc);
    let can = match configure(can, btr, filters) {
        Ok(parts) => parts,
        Err(_) => defmt::panic!(
            "CAN did not join the bus (no 11 recessive bits): transceiver, supply, termination?"
        ),
    };
    let timer = match SlotTimer::new(dp.TIM2, &mut rcc, TIM2_CLOCK_HZ) {
        Ok(t) => t,
        // Unreachable with the clock tree checked above (72 MHz = 9 × 8 MHz).
        Err(_) => defmt::panic!("TIM2 clock is not a multiple of the 8 MHz tick"),
    };
    let board = Board {
        rcc,
        pins: Pins {
            adc: (gpioa.pa0, gpioa.pa1, gpioa.pa2, gpioa.pa3),
            encoder: (gpioa.pa6, gpioa.pa7),
            usart1: (gpioa.pa9, gpioa.pa10),
            pwm: (gpiob.pb6, gpiob.pb7),
            a_crl: gpioa.crl,
            a_crh: gpioa.crh,
            b_crl: gpiob.crl,
        },
        afio,
        adc1: dp.ADC1,
        tim3: dp.TIM3,
        tim4: dp.TIM4,
        usart1: dp.USART1,
        dma1: dp.DMA1,
    };
    let mut watchdog = IndependentWatchdog::new(dp.IWDG);
    // Halted by the probe (breakpoint, `probe-rs` attach) the watchdog pauses too.
    watchdog.stop_on_debug(&dp.DBGMCU, true);
    watchdog.start(WATCHDOG_MS.millis());
    (
        Bus {
            can,
            timer,
            watchdog,
        },
        board,
    )
}
