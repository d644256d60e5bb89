//! The gateway's side of the serial link, HAL-free, on the simulated robot: what the
//! Triskar2 gateway firmware does with `triskar2_link` (examples/triskar2/src/io.rs),
//! run against `rtcan_sim::live` so the host side can be tested end to end over a real
//! pty. Robot → host: every message of a `link = "out"` topic the bus carries;
//! host → robot: the `link = "in"` topics, published by the gateway on the bus (numbers
//! and directions from robot.toml through the plan, as the firmware's generated
//! `rtcan::robot_toml::link`). Both ways, the host channels' bus frames (parameters,
//! firmware update; `triskar2_link::BUS_FRAME`): from the host onto the bus if they are
//! NRT frames of those channels (`rtcan_core::service::sendable`), every one the gateway
//! receives back to the host — with a robot started by `SimLink::start_with_updates`.
use std::io::{Read, Write};

use rtcan_model::bridge_keys::{LinkDir, LinkTopic};
use rtcan_sim::candump::Entry;
use rtcan_sim::decode::{Catalog, Decoded, Decoder as BusDecoder};
use triskar2_link::{Decoder, LinkStats, MAX_PAYLOAD, OVERHEAD};

use crate::link::Link;
use crate::sim::SimLink;

/// The simulated robot with its gateway's serial link on `port`.
pub struct SimGateway<'c, P: Read + Write> {
    robot: SimLink,
    port: P,
    link_rx: Decoder,
    bus: BusDecoder<'c>,
    cat: &'c Catalog,
    link: Vec<LinkTopic>,
    /// Frames written to the host.
    pub sent: u64,
    /// Host-channel frames from the host put on the bus, and refused.
    pub relayed: u64,
    pub refused: u64,
}

impl<'c, P: Read + Write> SimGateway<'c, P> {
    /// The gateway of `robot` (its catalog `cat`) on `port` (non-blocking or with a
    /// read timeout: `step` reads what is there), forwarding the link topics `link`
    /// (the plan's `bridge.link`).
    pub fn new(robot: SimLink, port: P, cat: &'c Catalog, link: &[LinkTopic]) -> Self {
        SimGateway {
            link: link.to_vec(),
            robot,
            port,
            link_rx: Decoder::new(),
            bus: BusDecoder::new(cat),
            cat,
            sent: 0,
            relayed: 0,
            refused: 0,
        }
    }

    /// Link counters of the host → robot direction.
    pub fn stats(&self) -> LinkStats {
        self.link_rx.stats()
    }

    /// What module `m` would boot now (slot, image length, CRC-32), with update ports.
    pub fn booted(&self, m: usize) -> Option<(usize, u32, u32)> {
        self.robot.booted(m)
    }

    /// Robot pose (x, y m).
    pub fn pose_m(&self) -> (f64, f64) {
        self.robot.pose_m()
    }

    /// Runs the robot one step, forwards its messages to the host, and takes the host's
    /// commands; `mangle` may alter the bytes written (to test loss on the line).
    pub fn step(&mut self, mangle: &mut dyn FnMut(&mut Vec<u8>)) -> Result<(), String> {
        let mut buf = [0u8; 512];
        let n = match self.port.read(&mut buf) {
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => 0,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => 0,
            Err(e) => return Err(format!("gateway link: {e}")),
        };
        let mut cmds = Vec::new();
        let mut frames = Vec::new();
        for &b in buf.get(..n).unwrap_or(&[]) {
            if let Some((n, p)) = self.link_rx.push(b) {
                if n == triskar2_link::BUS_FRAME {
                    frames.push(triskar2_link::decode_bus_frame(p).and_then(|(raw, data)| {
                        rtcan_core::Frame::new(rtcan_core::CanId::from_raw(raw)?, data)
                    }));
                    continue;
                }
                let to_robot = self
                    .link
                    .iter()
                    .find(|l| l.number == n && l.dir == LinkDir::In);
                if let Some(l) = to_robot {
                    cmds.push((l.name.clone(), p.to_vec()));
                }
            }
        }
        for f in frames {
            match f {
                Some(f) if self.robot.relay_to_bus(f) => self.relayed += 1,
                _ => self.refused += 1,
            }
        }
        for (name, c) in cmds {
            // A command of the wrong size is dropped, as the firmware does.
            let _ = self.robot.publish(&name, &c);
        }
        let mut out = Vec::new();
        for s in self.robot.recv()?.unwrap_or_default() {
            let e = Entry {
                time_ns: s.time_ns,
                iface: String::new(),
                frame: s.frame,
                standard: false,
            };
            let Some(Decoded::Message {
                topic: t, payload, ..
            }) = self.bus.push(&e)
            else {
                continue;
            };
            let name = self.cat.topics.get(t).map_or("", |t| t.name.as_str());
            let Some(lt) = self
                .link
                .iter()
                .find(|l| l.name == name && l.dir == LinkDir::Out)
                .map(|l| l.number)
            else {
                continue;
            };
            let mut frame = [0u8; MAX_PAYLOAD + OVERHEAD];
            if let Some(k) = triskar2_link::encode(lt, &payload, &mut frame) {
                out.extend_from_slice(frame.get(..k).unwrap_or(&[]));
                self.sent += 1;
            }
        }
        for f in self.robot.relay_from_bus() {
            let mut frame = [0u8; MAX_PAYLOAD + OVERHEAD];
            if let Some(k) = triskar2_link::encode_bus_frame(f.id().raw(), f.data(), &mut frame) {
                out.extend_from_slice(frame.get(..k).unwrap_or(&[]));
                self.sent += 1;
            }
        }
        mangle(&mut out);
        self.port
            .write_all(&out)
            .map_err(|e| format!("gateway link: {e}"))
    }
}
