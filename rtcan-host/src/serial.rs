//! The gateway's serial link as a [`Link`] (`--serial PORT`): frames of `triskar2_link`
//! (COBS + CRC-16) both ways. The link carries whole topic messages, not CAN frames;
//! each received message is handed out as the frames the bus carried it in (same message
//! ID and fragmentation, `rtcan_core::fragment`), stamped with wall time since the link
//! opened, so every command decodes it the same way. Which topics cross the link, with
//! which numbers and in which direction, is robot.toml's `link` (the plan's
//! `bridge.link`): the host sends the `link = "in"` topics. The host channels' bus frames
//! (parameters, firmware update: `triskar2_link::BUS_FRAME`) cross the link as the bus
//! carries them: [`SerialLink::send_frame`] sends one through the gateway, `recv` hands
//! out the ones the gateway forwards.
use std::fs::File;
use std::io::{Read, Write};
use std::os::fd::AsRawFd;
use std::time::Instant;

use rtcan_core::fragment::{fragment_count, fragment_data, fragment_field};
use rtcan_core::{CanId, Frame, MsgId, Nanos};
use rtcan_model::bridge_keys::{LinkDir, LinkTopic};
use rtcan_sim::decode::Catalog;
use triskar2_link::{Decoder, LinkStats, MAX_PAYLOAD, OVERHEAD};

use crate::link::{Link, Stamped};

/// Puts the terminal `fd` in raw mode with reads that return after 100 ms of silence.
pub fn make_raw(fd: i32) -> Result<(), String> {
    // SAFETY: `t` is a plain C struct filled by tcgetattr before use; fd is open.
    unsafe {
        let mut t: libc::termios = std::mem::zeroed();
        if libc::tcgetattr(fd, &mut t) != 0 {
            return Err(format!(
                "not a terminal: {}",
                std::io::Error::last_os_error()
            ));
        }
        libc::cfmakeraw(&mut t);
        t.c_cc[libc::VMIN] = 0;
        t.c_cc[libc::VTIME] = 1;
        // 115200 Bd as the gateway's USART (ignored by a pty).
        libc::cfsetspeed(&mut t, libc::B115200);
        if libc::tcsetattr(fd, libc::TCSANOW, &t) != 0 {
            return Err(format!("tcsetattr: {}", std::io::Error::last_os_error()));
        }
    }
    Ok(())
}

/// A pseudo-terminal pair standing in for a serial cable (tests, and a simulated gateway
/// a host tool can open as `--serial PATH`): the master side non-blocking, the slave
/// side already raw (a pty starts cooked and would echo the gateway's frames back), and
/// the slave's path. Keep the slave `File` open while the path is in use, so the master
/// never reads EIO between two opens of the path.
pub fn open_pty() -> Result<(File, File, String), String> {
    use std::os::fd::FromRawFd;
    let (mut m, mut s) = (0, 0);
    let mut name = [0 as libc::c_char; 128];
    // SAFETY: out-pointers to locals; the name buffer holds any /dev/pts/N.
    let rc = unsafe {
        libc::openpty(
            &mut m,
            &mut s,
            name.as_mut_ptr(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    if rc != 0 {
        return Err(format!("openpty: {}", std::io::Error::last_os_error()));
    }
    // SAFETY: both fds were just opened by openpty and are owned by these Files only.
    let (master, slave) = unsafe { (File::from_raw_fd(m), File::from_raw_fd(s)) };
    // SAFETY: the master fd is open (owned by `master`).
    unsafe {
        let fl = libc::fcntl(master.as_raw_fd(), libc::F_GETFL);
        libc::fcntl(master.as_raw_fd(), libc::F_SETFL, fl | libc::O_NONBLOCK);
    }
    // SAFETY: openpty NUL-terminates the name within the buffer.
    let path = unsafe { std::ffi::CStr::from_ptr(name.as_ptr()) }
        .to_str()
        .map_err(|e| format!("pty name: {e}"))?
        .to_string();
    make_raw(slave.as_raw_fd())?;
    Ok((master, slave, path))
}

/// A serial link to the gateway.
pub struct SerialLink<P: Read + Write> {
    port: P,
    dec: Decoder,
    /// Robot → host link topic → (message ID, payload size) on the bus.
    topics: Vec<(u8, MsgId, usize)>,
    /// Host → robot link topics.
    to_robot: Vec<LinkTopic>,
    tid: u8,
    started: Instant,
    now_ns: Nanos,
}

impl SerialLink<File> {
    /// Opens the serial port (or pty) at `path` in raw mode.
    pub fn open(path: &str, cat: &Catalog, link: &[LinkTopic]) -> Result<Self, String> {
        let port = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map_err(|e| format!("--serial {path}: {e}"))?;
        make_raw(port.as_raw_fd()).map_err(|e| format!("--serial {path}: {e}"))?;
        Ok(Self::new(port, cat, link))
    }
}

impl<P: Read + Write> SerialLink<P> {
    /// A link over `port` (already configured) for the robot `cat` describes, carrying
    /// the link topics `link` (the plan's `bridge.link`).
    pub fn new(port: P, cat: &Catalog, link: &[LinkTopic]) -> Self {
        let topics = link
            .iter()
            .filter(|l| l.dir == LinkDir::Out)
            .filter_map(|l| {
                let t = cat.topics.iter().find(|t| t.name == l.name)?;
                Some((l.number, MsgId(t.msg_id), usize::from(t.size)))
            })
            .collect();
        let to_robot = link
            .iter()
            .filter(|l| l.dir == LinkDir::In)
            .cloned()
            .collect();
        SerialLink {
            port,
            dec: Decoder::new(),
            topics,
            to_robot,
            tid: 0,
            started: Instant::now(),
            now_ns: 0,
        }
    }

    /// Link counters (frames, CRC failures, malformed, too long).
    pub fn stats(&self) -> LinkStats {
        self.dec.stats()
    }

    /// The bus frames of one message.
    fn frames(&mut self, msg: MsgId, payload: &[u8], out: &mut Vec<Stamped>) {
        let count = fragment_count(payload.len());
        self.tid = self.tid.wrapping_add(1);
        for counter in (0..count).rev() {
            let mut data = [0u8; 8];
            let dlc = fragment_data(payload, counter, &mut data);
            let field = fragment_field(count, self.tid, counter);
            let frame = CanId::new(0, msg, field)
                .and_then(|id| Frame::new(id, data.get(..usize::from(dlc)).unwrap_or(&[])));
            if let Some(frame) = frame {
                out.push(Stamped {
                    time_ns: self.now_ns,
                    frame,
                });
            }
        }
    }
}

impl<P: Read + Write> SerialLink<P> {
    /// Sends `frame` through the gateway onto the bus: only NRT frames of the host
    /// channels (`rtcan_core::service::sendable`; the gateway refuses anything else).
    pub fn send_frame(&mut self, frame: &Frame) -> Result<(), String> {
        if !rtcan_core::service::sendable(frame) {
            return Err(format!(
                "identifier {:#010x}: the gateway forwards only NRT frames of the host channels \
                 (message IDs {:#06x}..=0xFFFF)",
                frame.id().raw(),
                rtcan_core::service::SERVICE_MSG_ID_START
            ));
        }
        let mut buf = [0u8; MAX_PAYLOAD + OVERHEAD];
        let n = triskar2_link::encode_bus_frame(frame.id().raw(), frame.data(), &mut buf)
            .ok_or("a bus frame does not fit a link frame")?;
        self.port
            .write_all(buf.get(..n).unwrap_or(&[]))
            .map_err(|e| format!("serial link: {e}"))
    }

    /// Flushes what `send_frame` wrote.
    pub fn flush(&mut self) -> Result<(), String> {
        self.port.flush().map_err(|e| format!("serial link: {e}"))
    }
}

impl<P: Read + Write> Link for SerialLink<P> {
    fn recv(&mut self) -> Result<Option<Vec<Stamped>>, String> {
        let mut buf = [0u8; 1024];
        let n = match self.port.read(&mut buf) {
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => 0,
            // A pty whose other side closed reads EIO: the link is gone.
            Err(e) => return Err(format!("serial link: {e}")),
        };
        self.now_ns = self.started.elapsed().as_nanos() as Nanos;
        let mut out = Vec::new();
        let mut msgs = Vec::new();
        for &b in buf.get(..n).unwrap_or(&[]) {
            if let Some((t, p)) = self.dec.push(b) {
                msgs.push((t, p.to_vec()));
            }
        }
        for (t, p) in msgs {
            if t == triskar2_link::BUS_FRAME {
                // A bus frame the gateway forwarded as it is.
                let frame = triskar2_link::decode_bus_frame(&p)
                    .and_then(|(raw, data)| Frame::new(CanId::from_raw(raw)?, data));
                if let Some(frame) = frame {
                    out.push(Stamped {
                        time_ns: self.now_ns,
                        frame,
                    });
                }
                continue;
            }
            // Unknown link topics and wrong sizes are dropped (counted by the caller's
            // decoder as nothing: they never reach the bus view).
            if let Some(&(_, msg, size)) = self.topics.iter().find(|(n, _, _)| *n == t) {
                if p.len() == size {
                    self.frames(msg, &p, &mut out);
                }
            }
        }
        Ok(Some(out))
    }

    fn publish(&mut self, name: &str, payload: &[u8]) -> Result<(), String> {
        let t = self
            .to_robot
            .iter()
            .find(|l| l.name == name)
            .map(|l| l.number)
            .ok_or_else(|| {
                let names: Vec<&str> = self.to_robot.iter().map(|l| l.name.as_str()).collect();
                format!(
                    "the gateway link takes only {} from the host, not `{name}` (robot.toml `link = \"in\"`)",
                    if names.is_empty() { "nothing".to_string() } else { names.join(", ") }
                )
            })?;
        let mut frame = [0u8; MAX_PAYLOAD + OVERHEAD];
        let n = triskar2_link::encode(t, payload, &mut frame)
            .ok_or_else(|| format!("`{name}`: {} bytes do not fit a link frame", payload.len()))?;
        self.port
            .write_all(frame.get(..n).unwrap_or(&[]))
            .and_then(|()| self.port.flush())
            .map_err(|e| format!("serial link: {e}"))
    }

    fn now_ns(&self) -> Nanos {
        self.started.elapsed().as_nanos() as Nanos
    }
}
