//! The modules' hardware behind the shared apps' traits (`triskar2_nodes::app`): what
//! the simulator models with its plant, done here with the peripherals, at register
//! level where the HAL's generic wrappers would only add size.
//!
//! | app | hardware | pins |
//! |---|---|---|
//! | `Motor{1,2,3}App` | [`MotorIo`]: TIM3 encoder mode, TIM4 PWM (20 kHz) | PA6/PA7, PB6/PB7 |
//! | `ProximityApp` | [`RangerIo`]: four Sharp GP2Y0A21 on ADC1 | PA0..PA3 |
//! | `PsuApp` | [`PsuIo`]: battery divider and current sensor on ADC1 | PA0, PA1 |
//! | `GatewayApp` | [`GatewayIo`]: USART1 115 200 Bd, RX by DMA1 ch5 | PA9/PA10 |
use core::cell::UnsafeCell;

use rtcan_board_stm32f103::hal::adc::Adc;
use rtcan_board_stm32f103::hal::gpio::{gpioa, gpiob, Cr};
use rtcan_board_stm32f103::hal::gpio::{Alternate, Analog, PushPull};
use rtcan_board_stm32f103::hal::pac;
use rtcan_board_stm32f103::hal::prelude::*;
use rtcan_board_stm32f103::hal::rcc::{Enable, Rcc, Reset};
use rtcan_core::time::Nanos;
use rtcan_pubsub::Message;
use triskar2_link::Decoder;
use triskar2_nodes::app::{GatewayHw, MotorHw, ProximityHw, PsuHw};
use triskar2_nodes::Twist;

use crate::board::{Board, FromBoard};
use rtcan::robot_toml as msg;

// The gateway forwards exactly the link topics robot.toml declares (`link = "in"|"out"`,
// numbered by the generator): teleop in; odometry, proximity, battery, log out. A topic
// declared for the link that the hooks below do not forward fails the build here, and
// one they forward but robot.toml no longer declares fails at its `msg::link::number::`
// constant.
const _: () = assert!(
    msg::link::IN_COUNT == 1 && msg::link::OUT_COUNT == 4,
    "robot.toml declares link topics the gateway firmware does not forward (examples/triskar2/src/io.rs)"
);

/// The module's hardware as a node task sees it (`fw::Locked`): the RTIC shared
/// resource of the module app, locked around each access, so two nodes of one module
/// share it at the ceiling of the ones that use it (a single user's lock is free).
pub struct Locked<M>(pub M);

impl<M: rtic::Mutex<T = MotorIo>> MotorHw for Locked<M> {
    fn encoder_count(&mut self) -> u16 {
        self.0.lock(|h| h.encoder_count())
    }
    fn set_duty(&mut self, duty: f32) {
        self.0.lock(|h| h.set_duty(duty));
    }
}

impl<M: rtic::Mutex<T = RangerIo>> ProximityHw for Locked<M> {
    fn ranges_m(&mut self) -> [f32; 4] {
        self.0.lock(|h| h.ranges_m())
    }
}

impl<M: rtic::Mutex<T = PsuIo>> PsuHw for Locked<M> {
    fn voltage_v(&mut self) -> f32 {
        self.0.lock(|h| h.voltage_v())
    }
    fn current_a(&mut self) -> f32 {
        self.0.lock(|h| h.current_a())
    }
}

impl<M: rtic::Mutex<T = GatewayIo>> GatewayHw for Locked<M> {
    fn velocity_command(&mut self, now: Nanos) -> Option<Twist> {
        self.0.lock(|h| h.velocity_command(now))
    }
    fn odometry(&mut self, now: Nanos, m: &msg::Odometry) {
        self.0.lock(|h| h.odometry(now, m));
    }
    fn proximity(&mut self, now: Nanos, m: &msg::Proximity) {
        self.0.lock(|h| h.proximity(now, m));
    }
    fn battery(&mut self, now: Nanos, m: &msg::Battery) {
        self.0.lock(|h| h.battery(now, m));
    }
    fn log(&mut self, now: Nanos, m: &msg::LogLine) {
        self.0.lock(|h| h.log(now, m));
    }
}

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
}

impl FromBoard for MotorIo {
    fn from_board(mut b: Board) -> Self {
        MotorIo::new(b.tim3, b.tim4, b.pins.pwm, &mut b.pins.b_crl, &mut b.rcc)
    }
}

impl MotorHw for MotorIo {
    fn encoder_count(&mut self) -> u16 {
        self.tim3.cnt().read().bits() as u16
    }

    /// Duty cycle -1..=1 (sign = direction); anything else (NaN included) stops.
    fn set_duty(&mut self, duty: f32) {
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

    fn from_board(mut b: Board) -> Self {
        Analog4::new(b.adc1, b.pins.adc, &mut b.pins.a_crl, &mut b.rcc)
    }

    /// Input `channel` (0..=3), volts; a failed conversion or another channel reads
    /// NaN, which the apps treat as no reading.
    pub fn volts(&mut self, channel: u8) -> f32 {
        let (a0, a1, a2, a3) = &mut self.pins;
        let adc = &mut self.adc;
        let r: nb::Result<u16, ()> = match channel {
            0 => adc.read(a0),
            1 => adc.read(a1),
            2 => adc.read(a2),
            3 => adc.read(a3),
            _ => return f32::NAN,
        };
        match r {
            Ok(c) => f32::from(c) * VOLTS_PER_COUNT,
            Err(_) => f32::NAN,
        }
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

/// The proximity module's four IR rangers (front, left, back, right on PA0..PA3).
pub struct RangerIo(Analog4);

impl FromBoard for RangerIo {
    fn from_board(b: Board) -> Self {
        RangerIo(Analog4::from_board(b))
    }
}

impl ProximityHw for RangerIo {
    fn ranges_m(&mut self) -> [f32; 4] {
        [0, 1, 2, 3].map(|ch| sharp_distance_m(self.0.volts(ch)))
    }
}

/// PSU: battery voltage divider ratio (24 V pack → ADC range).
pub const BATTERY_DIVIDER: f32 = 11.0;
/// PSU: current sensor output at 0 A, V (bidirectional, ±16 A).
pub const CURRENT_ZERO_V: f32 = 1.65;
/// PSU: current sensor gain, V/A.
pub const CURRENT_V_PER_A: f32 = 0.1;

/// The PSU module's sensors: pack voltage through a divider on PA0, a Hall current
/// sensor on PA1.
pub struct PsuIo(Analog4);

impl FromBoard for PsuIo {
    fn from_board(b: Board) -> Self {
        PsuIo(Analog4::from_board(b))
    }
}

impl PsuHw for PsuIo {
    fn voltage_v(&mut self) -> f32 {
        self.0.volts(0) * BATTERY_DIVIDER
    }
    fn current_a(&mut self) -> f32 {
        (self.0.volts(1) - CURRENT_ZERO_V) / CURRENT_V_PER_A
    }
}

/// Host link bit rate.
pub const LINK_BAUD: u32 = 115_200;
/// A host command older than this is replaced by a stop: a host that went silent
/// (crashed, cable out) must not leave the robot driving (4 forwarding periods).
pub const HOST_TIMEOUT_NS: Nanos = 200_000_000;
/// USART1 RX ring, bytes: 44 ms of a link running flat out; the app drains it at
/// least every 50 ms and the host sends far less (an 18-byte command at 20 Hz).
const RX_RING: usize = 512;

/// The ring DMA1 channel 5 writes USART1's received bytes into.
struct RxRing(UnsafeCell<[u8; RX_RING]>);

// SAFETY: only DMA1 channel 5 writes the ring and only the one `GatewayIo` (which owns
// USART1 and DMA1) reads it, with volatile reads of bytes the DMA already wrote.
unsafe impl Sync for RxRing {}

static RX_RING_BUF: RxRing = RxRing(UnsafeCell::new([0; RX_RING]));

/// The gateway's host link (ROS side, through a USB-serial adapter: the F103's USB
/// cannot run next to CAN). Frames: `triskar2_link`. Host → robot: the velocity
/// command, forwarded by `ros_bridge` as `teleop`; robot → host: odometry, proximity,
/// battery, log. RX runs by DMA into a ring (no interrupt per byte); TX blocks in
/// the app task (87 µs a byte, a few hundred bytes a second).
pub struct GatewayIo {
    usart: pac::USART1,
    dma: pac::DMA1,
    _pins: (gpioa::PA9<Alternate<PushPull>>, gpioa::PA10),
    read: usize,
    decoder: Decoder,
    command: Option<(Twist, Nanos)>,
}

impl FromBoard for GatewayIo {
    fn from_board(mut b: Board) -> Self {
        let (pa9, pa10) = b.pins.usart1;
        let tx = pa9.into_alternate_push_pull(&mut b.pins.a_crh);
        pac::USART1::enable(&mut b.rcc);
        pac::USART1::reset(&mut b.rcc);
        pac::DMA1::enable(&mut b.rcc);
        // USART1 is on APB2 (72 MHz): 625, well within the 16-bit register.
        let brr = (b.rcc.clocks.pclk2().raw() + LINK_BAUD / 2) / LINK_BAUD;
        let brr = u16::try_from(brr).unwrap_or(u16::MAX);
        let usart = b.usart1;
        let dma = b.dma1;
        let ch = dma.ch5();
        // SAFETY (register writes below): RM0008 §13.3, §27.6 configuration values
        // for peripherals this value owns; the DMA targets USART1's data register and
        // the static ring, RX_RING bytes long.
        ch.par()
            .write(|w| unsafe { w.bits(usart.dr().as_ptr() as u32) });
        ch.mar()
            .write(|w| unsafe { w.bits(RX_RING_BUF.0.get() as u32) });
        ch.ndtr().write(|w| unsafe { w.bits(RX_RING as u32) });
        // 8-bit peripheral → memory, memory increment, circular, enabled.
        ch.cr()
            .write(|w| unsafe { w.bits((1 << 7) | (1 << 5) | 1) });
        usart.brr().write(|w| unsafe { w.bits(brr) });
        // DMA on receive; 8N1, UE | TE | RE.
        usart.cr3().write(|w| unsafe { w.bits(1 << 6) });
        usart
            .cr1()
            .write(|w| unsafe { w.bits((1 << 13) | (1 << 3) | (1 << 2)) });
        GatewayIo {
            usart,
            dma,
            _pins: (tx, pa10),
            read: 0,
            decoder: Decoder::new(),
            command: None,
        }
    }
}

impl GatewayIo {
    /// Decodes what the DMA received since the last call; a checked command frame
    /// becomes the current command, stamped `now`.
    fn drain(&mut self, now: Nanos) {
        // NDTR counts down from RX_RING and reloads: the DMA's next write position.
        let left = self.dma.ch5().ndtr().read().bits() as usize;
        let write = RX_RING.saturating_sub(left) % RX_RING;
        while self.read != write {
            // SAFETY: `read` < RX_RING; the byte was written by the DMA (a lap of
            // the ring by the DMA only loses bytes, which the frame check rejects).
            let byte = unsafe {
                RX_RING_BUF
                    .0
                    .get()
                    .cast::<u8>()
                    .add(self.read)
                    .read_volatile()
            };
            self.read = (self.read + 1) % RX_RING;
            if let Some((msg::link::number::TELEOP, payload)) = self.decoder.push(byte) {
                match msg::Twist::decode(payload) {
                    Some(t) => {
                        let cmd = Twist {
                            vx: t.vx,
                            vy: t.vy,
                            wz: t.wz,
                        };
                        self.command = Some((cmd, now));
                    }
                    None => defmt::warn!("command frame of {} bytes", payload.len()),
                }
            }
        }
    }

    /// Writes one link frame of `m` (blocking).
    fn send<T: Message>(&mut self, topic: u8, m: &T) {
        let mut wire = [0u8; triskar2_link::MAX_PAYLOAD];
        let Some(payload) = wire.get_mut(..T::SIZE) else {
            return;
        };
        m.encode(payload);
        let mut frame = [0u8; triskar2_link::MAX_PAYLOAD + triskar2_link::OVERHEAD];
        let Some(n) = triskar2_link::encode(topic, payload, &mut frame) else {
            return;
        };
        for &byte in frame.iter().take(n) {
            // TXE (bit 7): the data register took the previous byte.
            while self.usart.sr().read().bits() & (1 << 7) == 0 {}
            self.usart
                .dr()
                .write(|w| unsafe { w.bits(u16::from(byte)) });
        }
    }
}

impl GatewayHw for GatewayIo {
    /// The host's latest command while fresh, a stop once it is stale, nothing before
    /// the host ever sent one.
    fn velocity_command(&mut self, now: Nanos) -> Option<Twist> {
        self.drain(now);
        let (cmd, at) = self.command?;
        Some(if now.saturating_sub(at) <= HOST_TIMEOUT_NS {
            cmd
        } else {
            Twist::ZERO
        })
    }
    fn odometry(&mut self, _now: Nanos, m: &msg::Odometry) {
        self.send(msg::link::number::ODOMETRY, m);
    }
    fn proximity(&mut self, _now: Nanos, m: &msg::Proximity) {
        self.send(msg::link::number::PROXIMITY, m);
    }
    fn battery(&mut self, _now: Nanos, m: &msg::Battery) {
        self.send(msg::link::number::BATTERY, m);
    }
    fn log(&mut self, _now: Nanos, m: &msg::LogLine) {
        self.send(msg::link::number::LOG, m);
    }
}
