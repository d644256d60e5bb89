//! The node loops, as async functions the RTIC software tasks of each image await.
//! Each takes its topics (publishers, subscribers), its I/O and a clock; node logic
//! is `triskar2_nodes`, unchanged from the simulator. Loops are periodic on the
//! SysTick monotonic; time stamps and node time come from `now` (the slot timer's
//! clock, so stamps of local and received messages compare).
use rtcan_core::time::Nanos;
use rtcan_pubsub::{Message, Node, NodeState, Publisher, Subscriber, SystemStatus};
use rtic_monotonics::fugit::ExtU32;
use rtic_monotonics::Monotonic;
use triskar2_nodes as nodes;

use crate::io::{sharp_distance_m, Analog4, MotorIo};
use crate::robot::{Battery, Encoder, LogLine, Odometry, Proximity, Twist, WheelSpeeds};
use crate::Mono;

/// Encoder counts per wheel revolution: 512-line encoder × 4 (quadrature) × 19:1 gear.
pub const COUNTS_PER_WHEEL_REV: f32 = 512.0 * 4.0 * 19.0;
/// A teleop command older than this is not followed (obstacle_avoid sends a stop).
pub const TELEOP_TIMEOUT_NS: Nanos = 100_000_000;
/// PSU: battery voltage divider ratio (24 V pack → ADC range).
pub const BATTERY_DIVIDER: f32 = 11.0;
/// PSU: current sensor, volts at 0 A and volts per ampere (bidirectional, ±16 A).
pub const CURRENT_ZERO_V: f32 = 1.65;
/// PSU: current sensor gain.
pub const CURRENT_V_PER_A: f32 = 0.1;

/// Fixed-rate wake-ups without drift (the next deadline advances by the period).
pub struct Ticker {
    next: <Mono as Monotonic>::Instant,
    period: <Mono as Monotonic>::Duration,
}

impl Ticker {
    /// Every `ms` milliseconds from now.
    pub fn every_ms(ms: u32) -> Self {
        Ticker {
            next: Mono::now(),
            period: ms.millis(),
        }
    }

    /// Waits for the next period.
    pub async fn tick(&mut self) {
        self.next += self.period;
        Mono::delay_until(self.next).await;
    }
}

/// The node lifecycle per period: applies the safe-state rule (a running node stops
/// when the system requires it) and starts the node once the reason is gone. Node
/// logic that moves something needs a fresh command after a restart (`MotorNode`).
pub fn node_runs(node: &Node, status: &SystemStatus) -> bool {
    match node.update(status) {
        NodeState::Run => true,
        NodeState::Init | NodeState::Stop => node.start(status),
        NodeState::Fail => false,
    }
}

/// The newest queued message (older ones are consumed: a controller wants the latest).
fn latest<T: Message, const N: usize, const S: usize, const Q: usize>(
    sub: &Subscriber<'static, T, N, S, Q>,
) -> Option<(T, Nanos)> {
    let mut last = None;
    while let Some(m) = sub.try_recv() {
        last = Some((*m, m.stamp()));
    }
    last
}

fn to_node(t: Twist) -> nodes::Twist {
    nodes::Twist {
        vx: t.vx,
        vy: t.vy,
        wz: t.wz,
    }
}

fn from_node(t: nodes::Twist) -> Twist {
    Twist {
        vx: t.vx,
        vy: t.vy,
        wz: t.wz,
    }
}

/// `motor_ctrlN` (200 Hz): wheel `wheel` of `wheel_setpoints`, encoder → speed, PID →
/// PWM, publishes `encoderN`. Stops the motor in the safe state.
#[allow(clippy::too_many_arguments)]
pub async fn motor_ctrl<
    const N1: usize,
    const S1: usize,
    const Q1: usize,
    const N2: usize,
    const S2: usize,
    const Q2: usize,
>(
    wheel: usize,
    node: &Node,
    status: &SystemStatus,
    setpoints: Subscriber<'static, WheelSpeeds, N1, S1, Q1>,
    encoder: Publisher<'static, Encoder, N2, S2, Q2>,
    io: &mut MotorIo,
    mut now: impl FnMut() -> Nanos,
) -> ! {
    let mut motor = nodes::MotorNode::new(nodes::MotorConfig::TRISKAR2);
    let mut speed = nodes::EncoderSpeed::new(COUNTS_PER_WHEEL_REV);
    let mut measured = 0.0;
    let mut ticker = Ticker::every_ms(5);
    loop {
        ticker.tick().await;
        let t = now();
        motor.set_safe(!node_runs(node, status));
        while let Some(m) = setpoints.try_recv() {
            if let Some(&w) = m.w.get(wheel) {
                motor.on_setpoint(m.stamp(), w);
            }
        }
        if let Some(s) = speed.step(t, io.encoder_count()) {
            measured = s;
        }
        let out = motor.step(t, measured);
        io.set_duty(out.duty);
        // HRT: latched for the slot; a full pool is counted in the topic's stats.
        let _ = encoder.send(
            Encoder {
                ticks: speed.ticks(),
                speed: measured,
            },
            t,
        );
    }
}

/// `kinematics` (100 Hz): `velocity` → inverse kinematics → `wheel_setpoints`.
pub async fn kinematics<
    const N1: usize,
    const S1: usize,
    const Q1: usize,
    const N2: usize,
    const S2: usize,
    const Q2: usize,
>(
    node: &Node,
    status: &SystemStatus,
    velocity: Subscriber<'static, Twist, N1, S1, Q1>,
    setpoints: Publisher<'static, WheelSpeeds, N2, S2, Q2>,
    mut now: impl FnMut() -> Nanos,
) -> ! {
    let mut ik = nodes::InverseKinematicsNode::new(nodes::KinematicsConfig::TRISKAR2);
    let mut ticker = Ticker::every_ms(10);
    loop {
        ticker.tick().await;
        let t = now();
        if let Some((v, stamp)) = latest(&velocity) {
            ik.on_velocity(stamp, to_node(v));
        }
        // Not running (safe state): command the wheels to stand still.
        let w = if node_runs(node, status) {
            ik.step(t)
        } else {
            [0.0; 3]
        };
        let _ = setpoints.send(WheelSpeeds { w }, t);
    }
}

/// `odometry` (50 Hz): the three `encoderN` speeds → forward kinematics → `odometry`.
#[allow(clippy::too_many_arguments)]
pub async fn odometry<
    const N1: usize,
    const S1: usize,
    const Q1: usize,
    const N2: usize,
    const S2: usize,
    const Q2: usize,
    const N3: usize,
    const S3: usize,
    const Q3: usize,
    const N4: usize,
    const S4: usize,
    const Q4: usize,
>(
    node: &Node,
    status: &SystemStatus,
    encoders: (
        Subscriber<'static, Encoder, N1, S1, Q1>,
        Subscriber<'static, Encoder, N2, S2, Q2>,
        Subscriber<'static, Encoder, N3, S3, Q3>,
    ),
    odometry: Publisher<'static, Odometry, N4, S4, Q4>,
    mut now: impl FnMut() -> Nanos,
) -> ! {
    const PERIOD_MS: u32 = 20;
    let mut odo = nodes::OdometryNode::new(nodes::TRISKAR2, PERIOD_MS as Nanos * 1_000_000);
    let mut wheels = [0.0f32; 3];
    let mut ticker = Ticker::every_ms(PERIOD_MS);
    loop {
        ticker.tick().await;
        let t = now();
        let (e1, e2, e3) = &encoders;
        for (w, e) in wheels.iter_mut().zip([latest(e1), latest(e2), latest(e3)]) {
            if let Some((e, _)) = e {
                *w = e.speed;
            }
        }
        if !node_runs(node, status) {
            continue;
        }
        let out = odo.step(t, wheels);
        let _ = odometry.send(
            Odometry {
                x: out.pose.x,
                y: out.pose.y,
                theta: out.pose.theta,
                vx: out.twist.vx,
                vy: out.twist.vy,
                wz: out.twist.wz,
            },
            t,
        );
    }
}

/// `ir_ranger` (25 Hz): four Sharp rangers → median + EMA filter → `proximity`.
pub async fn ir_ranger<const N: usize, const S: usize, const Q: usize>(
    node: &Node,
    status: &SystemStatus,
    adc: &mut Analog4,
    proximity: Publisher<'static, Proximity, N, S, Q>,
    mut now: impl FnMut() -> Nanos,
) -> ! {
    let mut filter = nodes::ProximityNode::new(nodes::ProximityConfig::TRISKAR2);
    let mut ticker = Ticker::every_ms(40);
    loop {
        ticker.tick().await;
        // Sensing is harmless: keep measuring in the safe state too.
        let _ = node_runs(node, status);
        let out = filter.step(adc.read_volts().map(sharp_distance_m));
        let _ = proximity.send(
            Proximity {
                range_mm: out.range_mm(),
            },
            now(),
        );
    }
}

/// `obstacle_avoid` (50 Hz): latest `teleop` (stop when older than 100 ms) limited by
/// the latest `proximity` ranges → `velocity`.
#[allow(clippy::too_many_arguments)]
pub async fn obstacle_avoid<
    const N1: usize,
    const S1: usize,
    const Q1: usize,
    const N2: usize,
    const S2: usize,
    const Q2: usize,
    const N3: usize,
    const S3: usize,
    const Q3: usize,
>(
    node: &Node,
    status: &SystemStatus,
    teleop: Subscriber<'static, Twist, N1, S1, Q1>,
    proximity: Subscriber<'static, Proximity, N2, S2, Q2>,
    velocity: Publisher<'static, Twist, N3, S3, Q3>,
    mut now: impl FnMut() -> Nanos,
) -> ! {
    let avoid = nodes::ObstacleAvoidance::new(nodes::AvoidanceConfig::TRISKAR2);
    let mut command: Option<(Twist, Nanos)> = None;
    // Until the rangers report, assume an obstacle everywhere: no motion.
    let mut ranges = [0.0f32; nodes::SENSOR_COUNT];
    let mut ticker = Ticker::every_ms(20);
    loop {
        ticker.tick().await;
        let t = now();
        if let Some(c) = latest(&teleop) {
            command = Some(c);
        }
        if let Some((p, _)) = latest(&proximity) {
            ranges = nodes::mm_to_m(p.range_mm);
        }
        let wanted = match command {
            Some((c, at)) if t.saturating_sub(at) <= TELEOP_TIMEOUT_NS => to_node(c),
            _ => nodes::Twist::ZERO,
        };
        let out = if node_runs(node, status) {
            avoid.filter(wanted, ranges).twist
        } else {
            nodes::Twist::ZERO
        };
        // SRT: a deadline miss is counted by the topic (`take_deadline_missed`).
        let _ = velocity.send(from_node(out), t);
    }
}

/// Text of a log line, NUL padded.
fn text(s: &str) -> [u8; 29] {
    let mut out = [0u8; 29];
    for (o, b) in out.iter_mut().zip(s.bytes()) {
        *o = b;
    }
    out
}

/// `battery_monitor` (10 Hz sampling, `battery` at 1 Hz, a `log` line when the low
/// flag changes).
pub async fn battery_monitor<
    const N1: usize,
    const S1: usize,
    const Q1: usize,
    const N2: usize,
    const S2: usize,
    const Q2: usize,
>(
    node: &Node,
    status: &SystemStatus,
    adc: &mut Analog4,
    battery: Publisher<'static, Battery, N1, S1, Q1>,
    log: Publisher<'static, LogLine, N2, S2, Q2>,
    mut now: impl FnMut() -> Nanos,
) -> ! {
    let mut monitor = nodes::BatteryNode::new(nodes::BatteryConfig::TRISKAR2);
    let mut ticker = Ticker::every_ms(100);
    let mut low = false;
    let mut n: u32 = 0;
    loop {
        ticker.tick().await;
        let t = now();
        let [v, i, ..] = adc.read_volts();
        let s = monitor.step(
            t,
            v * BATTERY_DIVIDER,
            (i - CURRENT_ZERO_V) / CURRENT_V_PER_A,
        );
        if !node_runs(node, status) {
            continue;
        }
        n = n.wrapping_add(1);
        if n.is_multiple_of(10) {
            // NRT: refused while the engine queue is full; the next second retries.
            let _ = battery.send(
                Battery {
                    mv: s.mv(),
                    ma: s.ma(),
                    pct: s.pct(),
                },
                t,
            );
        }
        if s.low != low {
            low = s.low;
            let line = if low {
                LogLine {
                    level: 2,
                    code: 1,
                    text: text("battery low"),
                }
            } else {
                LogLine {
                    level: 1,
                    code: 2,
                    text: text("battery ok"),
                }
            };
            let _ = log.send(line, t);
        }
    }
}

/// Writes one link frame of `msg` to `write` (the gateway's serial TX).
pub fn link_frame<T: Message>(topic: u8, msg: &T, mut write: impl FnMut(&[u8])) {
    let mut wire = [0u8; triskar2_link::MAX_PAYLOAD];
    let Some(payload) = wire.get_mut(..T::SIZE) else {
        return;
    };
    msg.encode(payload);
    let mut frame = [0u8; triskar2_link::MAX_PAYLOAD + triskar2_link::OVERHEAD];
    if let Some(n) = triskar2_link::encode(topic, payload, &mut frame) {
        if let Some(f) = frame.get(..n) {
            write(f);
        }
    }
}

/// `ros_bridge`, host-bound half (100 Hz): everything the gateway subscribes to goes
/// out on the serial link. (The teleop half runs in the USART RX interrupt.)
#[allow(clippy::too_many_arguments)]
pub async fn ros_bridge<
    const N1: usize,
    const S1: usize,
    const Q1: usize,
    const N2: usize,
    const S2: usize,
    const Q2: usize,
    const N3: usize,
    const S3: usize,
    const Q3: usize,
    const N4: usize,
    const S4: usize,
    const Q4: usize,
>(
    node: &Node,
    status: &SystemStatus,
    odometry: Subscriber<'static, Odometry, N1, S1, Q1>,
    proximity: Subscriber<'static, Proximity, N2, S2, Q2>,
    battery: Subscriber<'static, Battery, N3, S3, Q3>,
    log: Subscriber<'static, LogLine, N4, S4, Q4>,
    mut write: impl FnMut(&[u8]),
) -> ! {
    use triskar2_link::topic;
    let mut ticker = Ticker::every_ms(10);
    loop {
        ticker.tick().await;
        let _ = node_runs(node, status);
        while let Some(m) = odometry.try_recv() {
            link_frame(topic::ODOMETRY, &*m, &mut write);
        }
        while let Some(m) = proximity.try_recv() {
            link_frame(topic::PROXIMITY, &*m, &mut write);
        }
        while let Some(m) = battery.try_recv() {
            link_frame(topic::BATTERY, &*m, &mut write);
        }
        while let Some(m) = log.try_recv() {
            link_frame(topic::LOG, &*m, &mut write);
        }
    }
}

/// Every module's lowest-priority housekeeping (100 Hz): logs the safe-state reason
/// when it changes. (The master's heartbeat is aged by the engine's `CycleStart`
/// event through `ModuleHost`, on the bus clock.)
pub async fn supervisor(status: &SystemStatus) -> ! {
    let mut ticker = Ticker::every_ms(10);
    let mut last = None;
    loop {
        ticker.tick().await;
        let reason = status.safe_reason();
        if reason != last {
            match reason {
                Some(r) => defmt::warn!("safe state required: {}", r),
                None => defmt::info!("safe state cleared"),
            }
            last = reason;
        }
    }
}
