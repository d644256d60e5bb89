//! A CAN adapter as a [`Link`] (`--can IFACE`): the host is a listen-only monitor plus an
//! NRT sender. The frame path is the [`FramePort`] trait so everything above the socket
//! (stamping, the NRT rule, fragmentation) is tested without SocketCAN, through
//! [`LogPort`] (a candump log in, the frames sent kept); `socket::SocketPort` (feature
//! `socketcan`, Linux) is the thin backend on a real interface.
//!
//! Why NRT only: an HRT topic needs a slot of the robot's calendar, which a host outside
//! the schedule does not have; an SRT frame's laxity is a promise about its deadline,
//! and a frame handed to a kernel queue and a USB adapter has a queueing delay the host
//! cannot bound. NRT frames (laxity 63) lose every arbitration and promise nothing.
use std::time::Duration;

use rtcan_core::fragment::{fragment_count, fragment_data, fragment_field};
use rtcan_core::id::LAXITY_NRT;
use rtcan_core::{CanId, Class, Frame, MsgId, Nanos};
use rtcan_sim::decode::Catalog;

use crate::link::{Link, Stamped};
use crate::replay::ReplayLink;

/// How long one `recv` waits for frames at most, so callers stay responsive.
pub const WAIT: Duration = Duration::from_millis(50);

/// Raw frames in and out of a CAN adapter.
pub trait FramePort {
    /// Frames received within `wait`, stamped by the port; `None` once the port has ended
    /// (the end of a log).
    fn read(&mut self, wait: Duration) -> Result<Option<Vec<Stamped>>, String>;
    /// Queues one frame for the bus.
    fn write(&mut self, frame: &Frame) -> Result<(), String>;
    /// The port's clock, ns (time since it opened, or the log's time).
    fn now_ns(&self) -> Nanos;
}

/// A bus reached through a [`FramePort`].
pub struct CanLink<P: FramePort> {
    port: P,
    cat: Catalog,
    /// Transfer ID of the host's last fragmented message (rtcan_core::fragment).
    tid: u8,
}

impl<P: FramePort> CanLink<P> {
    /// A link over `port` for the robot `cat` describes.
    pub fn new(port: P, cat: Catalog) -> Self {
        CanLink { port, cat, tid: 0 }
    }

    /// The port (to read what a test port kept).
    pub fn port(&self) -> &P {
        &self.port
    }

    /// The frames that carry `payload` as an NRT message `msg`, in order, their counter
    /// counting down to 0 on the last as every RTCAN sender's (rtcan_core::fragment).
    pub fn nrt_frames(&mut self, msg: MsgId, payload: &[u8]) -> Vec<Frame> {
        let count = fragment_count(payload.len());
        self.tid = self.tid.wrapping_add(1);
        (0..count)
            .rev()
            .filter_map(|counter| {
                let mut data = [0u8; 8];
                let dlc = fragment_data(payload, counter, &mut data);
                let field = fragment_field(count, self.tid, counter);
                CanId::new(LAXITY_NRT, msg, field)
                    .and_then(|id| Frame::new(id, data.get(..usize::from(dlc))?))
            })
            .collect()
    }
}

impl<P: FramePort> Link for CanLink<P> {
    fn recv(&mut self) -> Result<Option<Vec<Stamped>>, String> {
        self.port.read(WAIT)
    }

    fn publish(&mut self, topic: &str, payload: &[u8]) -> Result<(), String> {
        let t = self
            .cat
            .topics
            .iter()
            .find(|t| t.name == topic)
            .ok_or_else(|| format!("no topic `{topic}` on this bus"))?;
        if t.class != Class::Nrt {
            return Err(format!(
                "`{topic}` is {:?}: a host on a CAN adapter sends NRT topics only (an HRT \
                 topic needs a calendar slot, an SRT one a deadline the adapter's queue \
                 cannot promise)",
                t.class
            ));
        }
        if payload.len() != usize::from(t.size) {
            return Err(format!(
                "`{topic}` takes {} bytes, not {}",
                t.size,
                payload.len()
            ));
        }
        for f in self.nrt_frames(MsgId(t.msg_id), payload) {
            self.port.write(&f)?;
        }
        Ok(())
    }

    fn now_ns(&self) -> Nanos {
        self.port.now_ns()
    }
}

/// A candump log as a CAN adapter: frames read from the log (paced as
/// [`ReplayLink`]), frames written kept in [`LogPort::sent`].
pub struct LogPort {
    log: ReplayLink,
    /// Every frame written, in order.
    pub sent: Vec<Frame>,
}

impl LogPort {
    /// A port replaying `log`.
    pub fn new(log: ReplayLink) -> Self {
        LogPort {
            log,
            sent: Vec::new(),
        }
    }
}

impl FramePort for LogPort {
    fn read(&mut self, _wait: Duration) -> Result<Option<Vec<Stamped>>, String> {
        self.log.recv()
    }

    fn write(&mut self, frame: &Frame) -> Result<(), String> {
        self.sent.push(*frame);
        Ok(())
    }

    fn now_ns(&self) -> Nanos {
        self.log.now_ns()
    }
}

/// The SocketCAN backend: a raw CAN socket on a Linux interface.
#[cfg(all(target_os = "linux", feature = "socketcan"))]
pub mod socket {
    use std::time::{Duration, Instant};

    use rtcan_core::{CanId, Frame, Nanos};
    use socketcan::{CanFrame, CanSocket, EmbeddedFrame, ExtendedId, Id, Socket, SocketOptions};

    use super::FramePort;
    use crate::link::Stamped;

    /// A raw socket on one interface. Own frames are received too, so a sender sees
    /// what it put on the bus as every other node does.
    pub struct SocketPort {
        sock: CanSocket,
        started: Instant,
        /// Frames RTCAN never sends (standard IDs, remote, error frames), skipped.
        pub skipped: u64,
    }

    impl SocketPort {
        /// Opens `iface` (`can0`); the error names the interface and how to bring it up.
        pub fn open(iface: &str, bitrate: u32) -> Result<Self, String> {
            let sock = CanSocket::open(iface).map_err(|e| {
                format!(
                    "--can {iface}: no usable CAN interface `{iface}` ({e}); list them with \
                     `ip -details link show type can`, bring one up with \
                     `ip link set {iface} up type can bitrate {bitrate}`"
                )
            })?;
            sock.set_recv_own_msgs(true)
                .map_err(|e| format!("--can {iface}: {e}"))?;
            Ok(SocketPort {
                sock,
                started: Instant::now(),
                skipped: 0,
            })
        }

        fn stamp(&self) -> Nanos {
            self.started.elapsed().as_nanos() as Nanos
        }
    }

    impl FramePort for SocketPort {
        fn read(&mut self, wait: Duration) -> Result<Option<Vec<Stamped>>, String> {
            self.sock
                .set_read_timeout(wait)
                .map_err(|e| format!("CAN socket: {e}"))?;
            let mut out = Vec::new();
            loop {
                let f = match self.sock.read_frame() {
                    Ok(f) => f,
                    Err(e)
                        if matches!(
                            e.kind(),
                            std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                        ) =>
                    {
                        break
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                    Err(e) => return Err(format!("CAN socket: {e}")),
                };
                let frame = match (&f, f.id()) {
                    (CanFrame::Data(_), Id::Extended(id)) => {
                        CanId::from_raw(id.as_raw()).and_then(|id| Frame::new(id, f.data()))
                    }
                    _ => None,
                };
                match frame {
                    Some(frame) => out.push(Stamped {
                        time_ns: self.stamp(),
                        frame,
                    }),
                    None => self.skipped += 1,
                }
                // After the first frame, take only what is already queued.
                if out.len() == 1 {
                    self.sock
                        .set_read_timeout(Duration::from_micros(1))
                        .map_err(|e| format!("CAN socket: {e}"))?;
                }
                if out.len() >= 256 {
                    break;
                }
            }
            Ok(Some(out))
        }

        fn write(&mut self, frame: &Frame) -> Result<(), String> {
            let id = ExtendedId::new(frame.id().raw()).ok_or("CAN ID out of range")?;
            let f = CanFrame::new(id, frame.data()).ok_or("CAN frame longer than 8 bytes")?;
            self.sock
                .write_frame(&f)
                .map_err(|e| format!("CAN socket: {e}"))
        }

        fn now_ns(&self) -> Nanos {
            self.stamp()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    fn cat() -> Catalog {
        let plan = rtcan_model::Robot::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml"))
            .unwrap();
        rtcan_sim::decode::plan_catalog(&plan)
    }

    fn link(log: &str) -> CanLink<LogPort> {
        let r = ReplayLink::from_reader(Box::new(Cursor::new(log.to_string())), 0.0);
        CanLink::new(LogPort::new(r), cat())
    }

    #[test]
    fn frames_of_the_log_come_through_in_order_with_their_times() {
        let mut l = link(
            "(1700000000.000100) can0 1F014000#0102\n\
             (1700000000.000300) can0 1F014100#R\n\
             (1700000000.000400) can0 0C014200#AABBCCDD\n",
        );
        let got = l.recv().unwrap().unwrap();
        let ids: Vec<(u64, u32)> = got
            .iter()
            .map(|s| (s.time_ns, s.frame.id().raw()))
            .collect();
        // The remote frame is not an RTCAN frame: skipped.
        assert_eq!(
            ids,
            [
                (1_700_000_000_000_100_000, 0x1F01_4000),
                (1_700_000_000_000_400_000, 0x0C01_4200)
            ]
        );
        assert_eq!(got[1].frame.data(), [0xAA, 0xBB, 0xCC, 0xDD]);
        assert_eq!(l.now_ns(), 1_700_000_000_000_400_000);
        assert_eq!(l.recv().unwrap(), None);
    }

    #[test]
    fn nrt_topics_are_sent_as_laxity_63_fragments_others_refused() {
        let c = cat();
        // `log` (LogLine, 32 bytes): four frames.
        let log = c.topics.iter().find(|t| t.name == "log").unwrap();
        let (msg, size) = (log.msg_id, usize::from(log.size));
        let mut l = link("");
        let payload: Vec<u8> = (1..=size as u8).collect();
        l.publish("log", &payload).unwrap();
        let sent = &l.port().sent;
        let count = fragment_count(size);
        assert_eq!((size, count, sent.len()), (32, 4, 4));
        for (k, f) in sent.iter().enumerate() {
            let id = f.id();
            assert_eq!(id.laxity(), 63);
            assert_eq!(id.msg_id(), MsgId(msg));
            // Counting down to 0, transfer ID 1.
            let counter = count - 1 - k as u8;
            assert_eq!(id.fragment(), fragment_field(count, 1, counter));
        }
        // The robot's own decoder takes the frames as one `log` message.
        let mut dec = rtcan_sim::decode::Decoder::new(&c);
        let decoded: Vec<_> = sent
            .iter()
            .enumerate()
            .filter_map(|(k, f)| {
                dec.push(&rtcan_sim::candump::Entry {
                    time_ns: k as u64,
                    iface: "can0".into(),
                    frame: *f,
                    standard: false,
                })
            })
            .collect();
        match decoded.as_slice() {
            [rtcan_sim::decode::Decoded::Message {
                topic, payload: p, ..
            }] => {
                assert_eq!(c.topics[*topic].name, "log");
                assert_eq!(p, &payload);
            }
            other => panic!("{other:?}"),
        }

        let e = l.publish("teleop", &[0; 12]).unwrap_err();
        assert!(
            e.starts_with("`teleop` is Srt: a host on a CAN adapter sends NRT topics only"),
            "{e}"
        );
        let e = l.publish("odometry", &[0; 12]).unwrap_err();
        assert!(e.starts_with("`odometry` is Hrt"), "{e}");
        let e = l.publish("battery", &[0; 1]).unwrap_err();
        assert_eq!(e, "`battery` takes 5 bytes, not 1");
        let e = l.publish("nosuch", &[]).unwrap_err();
        assert_eq!(e, "no topic `nosuch` on this bus");
        assert_eq!(l.port().sent.len(), 4, "refusals send nothing");
    }
}
