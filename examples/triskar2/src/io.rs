//! Module I/O the nodes need, at register level where the HAL's generic wrappers
//! would only add size: the motor's encoder (TIM3 encoder mode) and H-bridge PWM
//! (TIM4), and ADC conversions (rangers, battery). Plain values in, plain values out;
//! the node logic never sees a peripheral.
use rtcan_board_stm32f103::hal::adc::Adc;
use rtcan_board_stm32f103::hal::gpio::{gpioa, gpiob, Cr};
use rtcan_board_stm32f103::hal::gpio::{Alternate, Analog, PushPull};
use rtcan_board_stm32f103::hal::pac;
use rtcan_board_stm32f103::hal::prelude::*;
use rtcan_board_stm32f103::hal::rcc::{Enable, Rcc, Reset};

/// PWM period in timer ticks: 72 MHz / 3600 = 20 kHz (above hearing, fine for DC motors).
const PWM_TOP: u16 = 3600;

/// One DC motor: quadrature encoder on TIM3 (PA6/PA7), H-bridge with two PWM inputs
/// on TIM4 CH1/CH2 (PB6 forward, PB7 reverse).
pub struct MotorIo {
    tim3: pac::TIM3,
    tim4: pac::TIM4,
    _pwm: (
        gpiob::PB6<Alternate<PushPull>>,
        gpiob::PB7<Alternate<PushPull>>,
    ),
}

impl MotorIo {
    /// Configures both timers; the motor starts with zero duty.
    pub fn new(
        tim3: pac::TIM3,
        tim4: pac::TIM4,
        (pb6, pb7): (gpiob::PB6, gpiob::PB7),
        b_crl: &mut Cr<'B', false>,
        rcc: &mut Rcc,
    ) -> Self {
        let pwm = (
            pb6.into_alternate_push_pull(b_crl),
            pb7.into_alternate_push_pull(b_crl),
        );
        pac::TIM3::enable(rcc);
        pac::TIM3::reset(rcc);
        pac::TIM4::enable(rcc);
        pac::TIM4::reset(rcc);
        // SAFETY (all register writes below): plain configuration values of RM0008
        // §15.4 for timers this value owns.
        // TIM3: encoder mode 3 (count on both edges of both inputs), TI1/TI2 direct.
        tim3.ccmr1_input()
            .write(|w| unsafe { w.bits(0b01 | (0b01 << 8)) });
        tim3.smcr().write(|w| unsafe { w.bits(0b011) });
        tim3.arr().write(|w| unsafe { w.bits(0xFFFF) });
        tim3.cr1().write(|w| unsafe { w.bits(1) });
        // TIM4: PWM mode 1 with preload on CH1 and CH2, outputs enabled, 20 kHz.
        tim4.arr()
            .write(|w| unsafe { w.bits(u32::from(PWM_TOP) - 1) });
        tim4.ccmr1_output()
            .write(|w| unsafe { w.bits((0b110 << 4) | (1 << 3) | (0b110 << 12) | (1 << 11)) });
        tim4.ccr1().write(|w| unsafe { w.bits(0) });
        tim4.ccr2().write(|w| unsafe { w.bits(0) });
        tim4.ccer().write(|w| unsafe { w.bits(1 | (1 << 4)) });
        tim4.egr().write(|w| unsafe { w.bits(1) });
        tim4.cr1().write(|w| unsafe { w.bits(1 | (1 << 7)) });
        MotorIo {
            tim3,
            tim4,
            _pwm: pwm,
        }
    }

    /// The free-running 16-bit encoder counter.
    pub fn encoder_count(&self) -> u16 {
        self.tim3.cnt().read().bits() as u16
    }

    /// Duty cycle -1..=1 (sign = direction); anything else (NaN included) stops.
    pub fn set_duty(&mut self, duty: f32) {
        let d = if duty.is_finite() {
            duty.clamp(-1.0, 1.0)
        } else {
            0.0
        };
        // `as` saturates; |d| ≤ 1 keeps it within PWM_TOP.
        let ticks = (d.abs() * f32::from(PWM_TOP)) as u32;
        let (fwd, rev) = if d >= 0.0 { (ticks, 0) } else { (0, ticks) };
        self.tim4.ccr1().write(|w| unsafe { w.bits(fwd) });
        self.tim4.ccr2().write(|w| unsafe { w.bits(rev) });
    }
}

/// ADC1 on PA0..PA3 (12 bit, 3.3 V reference).
pub struct Analog4 {
    adc: Adc<pac::ADC1>,
    pins: (
        gpioa::PA0<Analog>,
        gpioa::PA1<Analog>,
        gpioa::PA2<Analog>,
        gpioa::PA3<Analog>,
    ),
}

/// Volts per ADC count (3.3 V / 4095).
pub const VOLTS_PER_COUNT: f32 = 3.3 / 4095.0;

impl Analog4 {
    /// Takes ADC1 and PA0..PA3 as analog inputs.
    pub fn new(
        adc1: pac::ADC1,
        (a0, a1, a2, a3): (gpioa::PA0, gpioa::PA1, gpioa::PA2, gpioa::PA3),
        crl: &mut Cr<'A', false>,
        rcc: &mut Rcc,
    ) -> Self {
        Analog4 {
            adc: Adc::new(adc1, rcc),
            pins: (
                a0.into_analog(crl),
                a1.into_analog(crl),
                a2.into_analog(crl),
                a3.into_analog(crl),
            ),
        }
    }

    /// The four inputs, volts (a failed conversion reads NaN, which the nodes skip).
    pub fn read_volts(&mut self) -> [f32; 4] {
        let (a0, a1, a2, a3) = &mut self.pins;
        let adc = &mut self.adc;
        let v = |r: nb::Result<u16, ()>| match r {
            Ok(c) => f32::from(c) * VOLTS_PER_COUNT,
            Err(_) => f32::NAN,
        };
        [
            v(adc.read(a0)),
            v(adc.read(a1)),
            v(adc.read(a2)),
            v(adc.read(a3)),
        ]
    }
}

/// Sharp GP2Y0A21 output voltage → distance, m: the datasheet curve is close to
/// d = 0.27 V·m / (V − 0.1 V) over 0.1–0.8 m. Below 0.2 V nothing is in range:
/// reads as infinity, which the proximity node clamps to its maximum range.
pub fn sharp_distance_m(volts: f32) -> f32 {
    if volts > 0.2 {
        0.27 / (volts - 0.1)
    } else {
        f32::INFINITY
    }
}
