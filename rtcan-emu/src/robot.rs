//! The emulated Triskar2 robot: the six images on emulated MCUs, their bus, and the
//! simulator's plants (`rtcan_sim::triskar::physics::Physics`: the same DC motors,
//! omni base, world with its wall, IR rangers and battery the simulator's modules use)
//! connected through the peripheral models:
//!
//! | module | peripheral the image reads/drives | plant |
//! |---|---|---|
//! | motor1..3 | TIM4 CCR1/CCR2 ÷ (ARR+1), PWM forward/reverse (`Tim2::duty`) | motor voltage = duty × battery terminal voltage |
//! | motor1..3 | TIM3 CNT in encoder mode (`Tim2::encoder_step`) | the motor's encoder position, counts |
//! | proximity | ADC1 channels 0..3 | ranger distance → Sharp GP2Y0A21 voltage (inverse of the image's curve) |
//! | psu | ADC1 channels 0, 1 | pack voltage ÷ 11 (divider), 1.65 V + 0.1 V/A × current |
//! | gateway | USART1 RX by DMA1 channel 5 | the host script's teleop commands, `triskar2_link` frames at 115 200 Bd |
//! | gateway | USART1 TX | odometry, proximity, battery and log frames for the host, decoded |
//!
//! The plant advances in the simulator's 1 ms physics ticks; the peripherals' inputs are
//! refreshed at every tick (the simulator reads them at the instant the app polls, so a
//! reading here is up to 1 ms older). Host bytes reach the gateway's USART at the tick
//! after their stop bit.
use std::collections::VecDeque;

use rtcan_core::Nanos;
use rtcan_model::Plan;
use rtcan_sim::candump::Entry;
use rtcan_sim::decode::{plan_catalog, Catalog, Decoded, Decoder};
use rtcan_sim::plant::World;
use rtcan_sim::triskar::physics::{Physics, TICK_NS};
use triskar2_nodes::kinematics::Twist;

pub use crate::bus::raw_to_frame;
use crate::bus::Bus;
use crate::mcu::Mcu;

/// Module names in bus order (robot.toml's module order = the images' module index).
pub const MODULES: [&str; 6] = ["gateway", "motor1", "motor2", "motor3", "proximity", "psu"];
const GATEWAY: usize = 0;
const PROXIMITY: usize = 4;
const PSU: usize = 5;
/// TIM3 (encoder) and TIM4 (PWM) in `State::tim`.
const TIM3: usize = 1;
const TIM4: usize = 2;

/// ps per ns.
const PS_NS: u64 = 1_000;

/// Constants of the images' analog front ends (`examples/triskar2/src/io.rs`).
pub mod analog {
    /// Volts per ADC count (3.3 V / 4095).
    pub const VOLTS_PER_COUNT: f64 = 3.3 / 4095.0;
    /// Battery divider ratio.
    pub const BATTERY_DIVIDER: f64 = 11.0;
    /// Current sensor output at 0 A, V, and its gain, V/A.
    pub const CURRENT_ZERO_V: f64 = 1.65;
    pub const CURRENT_V_PER_A: f64 = 0.1;

    /// The Sharp GP2Y0A21 output at `d` m: the inverse of the image's
    /// `sharp_distance_m` (d = 0.27 V·m / (V − 0.1 V)).
    pub fn sharp_volts(d: f64) -> f64 {
        0.27 / d.max(0.01) + 0.1
    }

    /// The 12-bit conversion of `v` volts (clamped to the 0..3.3 V input range).
    pub fn counts(v: f64) -> u16 {
        (v / VOLTS_PER_COUNT).round().clamp(0.0, 4095.0) as u16
    }
}

/// What the host (ROS side) sends the gateway: as `rtcan_sim::triskar::TriskarConfig`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HostScript {
    /// Forward command, m/s, sent from `from_ns` until `until_ns` (zero outside).
    pub vx: f32,
    pub from_ns: Nanos,
    pub until_ns: Nanos,
    /// One command frame every this many ns (the host sends at 20 Hz, io.rs).
    pub period_ns: Nanos,
}

impl Default for HostScript {
    fn default() -> Self {
        HostScript {
            vx: 0.3,
            from_ns: 500_000_000,
            until_ns: 8_000_000_000,
            period_ns: 50_000_000,
        }
    }
}

impl HostScript {
    fn vx_at(&self, t: Nanos) -> f32 {
        if t >= self.from_ns && t < self.until_ns {
            self.vx
        } else {
            0.0
        }
    }
}

/// What the gateway sent the host over USART1, decoded.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HostRx {
    /// Odometry: (ns the frame's last byte left, x, y, theta).
    pub odometry: Vec<(Nanos, f32, f32, f32)>,
    pub proximity: u32,
    pub battery: u32,
    pub log: u32,
    pub last_log: String,
    /// Frames the link decoder rejected (bad CRC/COBS) or with an unknown topic.
    pub bad: u32,
}

/// Offsets of the payload fields this module reads and writes, from the model.
struct Layout {
    teleop: Option<(usize, usize, usize)>,
    velocity: Option<(usize, usize)>,
    odometry: Option<(usize, usize, usize, usize)>,
}

fn topic_of<'c>(cat: &'c Catalog, name: &str) -> Option<(usize, &'c rtcan_sim::decode::TopicDesc)> {
    cat.topics.iter().enumerate().find(|(_, t)| t.name == name)
}

fn field(cat: &Catalog, topic: &str, f: &str) -> Option<usize> {
    topic_of(cat, topic)?
        .1
        .fields
        .iter()
        .find(|x| x.name == f && x.prim == rtcan_model::Prim::F32 && x.len.is_none())
        .map(|x| x.offset)
}

fn f32_at(p: &[u8], off: usize) -> Option<f32> {
    let b = p.get(off..off + 4)?;
    Some(f32::from_le_bytes([
        *b.first()?,
        *b.get(1)?,
        *b.get(2)?,
        *b.get(3)?,
    ]))
}

/// Link topic numbers of the topics the host side of the emulated robot reads or sends.
struct LinkNumbers {
    teleop: Option<u8>,
    odometry: Option<u8>,
    proximity: Option<u8>,
    battery: Option<u8>,
    log: Option<u8>,
}

/// The robot: MCUs on their bus, the plant, the host.
pub struct EmuRobot {
    pub bus: Bus,
    pub physics: Physics,
    pub script: HostScript,
    pub host_rx: HostRx,
    /// Velocity messages that differ from the last teleop on the bus: limited by
    /// obstacle_avoid (the app counts its overrides; this is that count seen from the wire).
    pub overrides: u32,
    /// Teleop messages on the bus: (SOF of the first fragment, ns; vx).
    pub teleop: Vec<(Nanos, f32)>,
    /// Host bytes on their way to the gateway: (ps their stop bit ends, byte).
    host_tx: VecDeque<(u64, u8)>,
    next_cmd: Nanos,
    link: triskar2_link::Decoder,
    encoder_seen: [i64; 3],
    /// Emulated (global) time the plant has reached, ns.
    t_ns: Nanos,
    /// The robot's topics (leaked once per robot: the bus decoder borrows it for the
    /// robot's whole life).
    cat: &'static Catalog,
    layout: Layout,
    /// The serial link's topic numbers (robot.toml's `link = "in"|"out"`, the plan's
    /// `bridge.link`: the same table the gateway image was generated with).
    link_no: LinkNumbers,
    /// rtcan-sim's bus decoder (reassembles multi-frame topics) and how far into the bus
    /// log it has read.
    decoder: Decoder<'static>,
    decoded: usize,
    last_teleop_vx: Option<f32>,
}

impl EmuRobot {
    /// The six `images` (ELF bytes in `MODULES` order) on a robot facing a wall at
    /// `wall_x_m`, the plant seeded with `seed` (sensor noise).
    pub fn new(
        plan: &Plan,
        mcus: Vec<Mcu>,
        wall_x_m: f64,
        seed: u64,
        script: HostScript,
    ) -> Result<EmuRobot, String> {
        let names: Vec<&str> = plan.modules.iter().map(|m| m.name.as_str()).collect();
        if names != MODULES || mcus.len() != MODULES.len() {
            return Err(format!(
                "expected the Triskar2 modules {MODULES:?}, got {names:?}"
            ));
        }
        let world = World::new().with_wall((wall_x_m, -2.0), (wall_x_m, 2.0));
        let cat: &'static Catalog = Box::leak(Box::new(plan_catalog(plan)));
        let layout = Layout {
            teleop: field(cat, "teleop", "vx")
                .zip(field(cat, "teleop", "vy"))
                .zip(field(cat, "teleop", "wz"))
                .map(|((a, b), c)| (a, b, c)),
            velocity: topic_of(cat, "velocity")
                .map(|(i, _)| i)
                .zip(field(cat, "velocity", "vx")),
            odometry: field(cat, "odometry", "x")
                .zip(field(cat, "odometry", "y"))
                .zip(field(cat, "odometry", "theta"))
                .zip(topic_of(cat, "odometry").map(|(_, t)| usize::from(t.size)))
                .map(|(((x, y), th), n)| (x, y, th, n)),
        };
        if layout.teleop.is_none() || layout.velocity.is_none() || layout.odometry.is_none() {
            return Err("robot.toml lacks the Triskar2 teleop/velocity/odometry fields".into());
        }
        let no = |name: &str| plan.bridge.link_topic(name).map(|t| t.number);
        let link_no = LinkNumbers {
            teleop: no("teleop"),
            odometry: no("odometry"),
            proximity: no("proximity"),
            battery: no("battery"),
            log: no("log"),
        };
        Ok(EmuRobot {
            link_no,
            bus: Bus::new(mcus, 1_000_000),
            physics: Physics::new(world, seed),
            script,
            host_rx: HostRx::default(),
            overrides: 0,
            teleop: Vec::new(),
            host_tx: VecDeque::new(),
            next_cmd: 0,
            link: triskar2_link::Decoder::new(),
            encoder_seen: [0; 3],
            t_ns: 0,
            cat,
            layout,
            decoder: Decoder::new(cat),
            decoded: 0,
            last_teleop_vx: None,
        })
    }

    /// Reads the SRT publication instants from the publishers' RAM from now on
    /// (`publications`: the report's SRT latency is then measured from them); `images`
    /// in `MODULES` order. Returns the SRT topics whose stamps were not found.
    pub fn watch_publications(&mut self, plan: &Plan, images: &[Vec<u8>]) -> Vec<String> {
        let (p, missing) = crate::publications::Publications::locate(plan, images);
        self.bus.publications = Some(p);
        missing
    }

    /// Plant time, ns.
    pub fn now_ns(&self) -> Nanos {
        self.t_ns
    }

    /// Runs MCUs, bus and plant to `until_ns`, one physics tick at a time.
    pub fn run_until(&mut self, until_ns: Nanos) -> Result<(), String> {
        while self.t_ns + TICK_NS <= until_ns {
            let t = self.t_ns + TICK_NS;
            self.bus.run_until(t * PS_NS)?;
            self.tick(t);
        }
        Ok(())
    }

    /// One plant tick at `t` (ns): actuators in, physics, sensors out, host link both ways.
    fn tick(&mut self, t: Nanos) {
        // Motors: H-bridge duty from TIM4 (CH1 forward, CH2 reverse, io.rs).
        for (i, m) in self.bus.mcus.iter().skip(1).take(3).enumerate() {
            let duty =
                m.st.tim
                    .get(TIM4)
                    .map_or(0.0, |tim| tim.duty(0) - tim.duty(1));
            if let Some(d) = self.physics.duty.get_mut(i) {
                *d = duty as f32;
            }
        }
        self.physics.advance_to(t);
        self.t_ns = t;
        for (i, m) in self.bus.mcus.iter_mut().skip(1).take(3).enumerate() {
            let (Some(motor), Some(seen)) =
                (self.physics.motors.get(i), self.encoder_seen.get_mut(i))
            else {
                continue;
            };
            let ticks = motor.encoder_ticks();
            if let Some(tim) = m.st.tim.get_mut(TIM3) {
                tim.encoder_step(ticks - *seen);
            }
            *seen = ticks;
        }
        let ranges = self.physics.ranges_m();
        if let Some(m) = self.bus.mcus.get_mut(PROXIMITY) {
            for (ch, d) in ranges.iter().enumerate() {
                if let Some(x) = m.st.adc1.input.get_mut(ch) {
                    *x = analog::counts(analog::sharp_volts(f64::from(*d)));
                }
            }
        }
        let v = self.physics.battery.terminal_v();
        let a = self.physics.battery.current_a();
        if let Some(m) = self.bus.mcus.get_mut(PSU) {
            let [c0, c1, ..] = &mut m.st.adc1.input;
            *c0 = analog::counts(v / analog::BATTERY_DIVIDER);
            *c1 = analog::counts(analog::CURRENT_ZERO_V + analog::CURRENT_V_PER_A * a);
        }
        self.host_send(t);
        self.host_receive(t);
        self.watch_bus();
    }

    /// The host's commands: a `triskar2_link` teleop frame every `period_ns`, bytes at
    /// 115 200 Bd; delivered to the gateway's USART once their stop bit is in.
    fn host_send(&mut self, t: Nanos) {
        while self.next_cmd <= t {
            let vx = self.script.vx_at(self.next_cmd);
            self.physics.cmd = Some(Twist {
                vx,
                vy: 0.0,
                wz: 0.0,
            });
            let frame = self.teleop_frame(vx);
            self.host_bytes(self.next_cmd, &frame);
            self.next_cmd += self.script.period_ns.max(1);
        }
        while let Some(&(at, b)) = self.host_tx.front() {
            if at > t * PS_NS {
                break;
            }
            self.host_tx.pop_front();
            if let Some(g) = self.bus.mcus.get_mut(GATEWAY) {
                g.usart_receive(b);
            }
        }
    }

    /// The host link frame of a teleop command `vx` (m/s, vy = wz = 0): `triskar2_link`
    /// framing of the teleop payload laid out as robot.toml's `Twist`.
    pub fn teleop_frame(&self, vx: f32) -> Vec<u8> {
        let Some((ox, oy, oz)) = self.layout.teleop else {
            return Vec::new();
        };
        let size = topic_of(self.cat, "teleop").map_or(0, |(_, t)| usize::from(t.size));
        let mut payload = vec![0u8; size];
        for (off, x) in [(ox, vx), (oy, 0.0), (oz, 0.0)] {
            if let Some(b) = payload.get_mut(off..off + 4) {
                b.copy_from_slice(&x.to_le_bytes());
            }
        }
        let Some(number) = self.link_no.teleop else {
            return Vec::new();
        };
        let mut frame = [0u8; triskar2_link::MAX_PAYLOAD + triskar2_link::OVERHEAD];
        let n = triskar2_link::encode(number, &payload, &mut frame).unwrap_or(0);
        frame.get(..n).unwrap_or(&[]).to_vec()
    }

    /// The host sends `bytes` from `at_ns` at 115 200 Bd (after what it already sends).
    pub fn host_bytes(&mut self, at_ns: Nanos, bytes: &[u8]) {
        const BYTE_PS: u64 = 10 * 1_000_000_000_000 / 115_200;
        let start = (at_ns * PS_NS).max(self.host_tx.back().map_or(0, |b| b.0));
        for (k, b) in bytes.iter().enumerate() {
            self.host_tx
                .push_back((start + (k as u64 + 1) * BYTE_PS, *b));
        }
    }

    /// Bytes the gateway transmitted: link frames for the host, decoded.
    fn host_receive(&mut self, _t: Nanos) {
        let Some(g) = self.bus.mcus.get_mut(GATEWAY) else {
            return;
        };
        let bytes = std::mem::take(&mut g.st.usart1.tx);
        let (ox, oy, oth, osize) = self.layout.odometry.unwrap_or((0, 4, 8, 24));
        for (at, b) in bytes {
            let Some((topic, payload)) = self.link.push(b) else {
                continue;
            };
            let rx = &mut self.host_rx;
            let no = &self.link_no;
            let topic = Some(topic);
            match topic {
                t if t == no.odometry && payload.len() == osize => {
                    if let (Some(x), Some(y), Some(th)) = (
                        f32_at(payload, ox),
                        f32_at(payload, oy),
                        f32_at(payload, oth),
                    ) {
                        rx.odometry.push((at / PS_NS, x, y, th));
                    }
                }
                t if t == no.proximity => rx.proximity += 1,
                t if t == no.battery => rx.battery += 1,
                t if t == no.log => {
                    rx.log += 1;
                    // LogLine: level u8, code u16, text [u8; 29] (robot.toml).
                    let text = payload.get(3..).unwrap_or(&[]);
                    let end = text.iter().position(|&c| c == 0).unwrap_or(text.len());
                    rx.last_log = String::from_utf8_lossy(text.get(..end).unwrap_or(&[])).into();
                }
                _ => rx.bad += 1,
            }
        }
    }

    /// Follows teleop and velocity on the bus (for the path table and the overrides).
    fn watch_bus(&mut self) {
        let Some((vel_topic, vel_vx)) = self.layout.velocity else {
            return;
        };
        let teleop = topic_of(self.cat, "teleop").map(|(i, _)| i);
        let tvx = self.layout.teleop.map_or(0, |t| t.0);
        let bit_ns = self.bus.bit_ps / PS_NS;
        for (_, f, sof) in self.bus.log.iter().skip(self.decoded) {
            let Some(frame) = raw_to_frame(f) else {
                continue;
            };
            let e = Entry {
                time_ns: sof * bit_ns,
                iface: String::new(),
                frame,
                standard: false,
            };
            let Some(Decoded::Message {
                topic,
                payload,
                time_ns,
                ..
            }) = self.decoder.push(&e)
            else {
                continue;
            };
            if Some(topic) == teleop {
                self.last_teleop_vx = f32_at(&payload, tvx);
                if let Some(vx) = self.last_teleop_vx {
                    self.teleop.push((time_ns, vx));
                }
            } else if topic == vel_topic {
                let vx = f32_at(&payload, vel_vx).unwrap_or(0.0);
                self.physics.velocity = Some(Twist {
                    vx,
                    vy: 0.0,
                    wz: 0.0,
                });
                if self.last_teleop_vx.is_some_and(|t| (t - vx).abs() > 1e-6) {
                    self.overrides += 1;
                }
            }
        }
        self.decoded = self.bus.log.len();
    }

    /// The frames on the wire as rtcan-sim's bus recorded them (global ns; `end` = end
    /// of EOF, or of the error delimiter for a destroyed frame).
    pub fn wire(&self) -> Vec<rtcan_sim::WireFrame> {
        self.bus.sim.wire.clone()
    }
}
