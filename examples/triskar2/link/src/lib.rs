//! The gateway's serial link to the host (ROS side): topic-tagged frames.
//!
//! ```text
//! 0xA5 0x5A  topic  len  payload[len]  f16_lo f16_hi
//! ```
//! `topic` is a [`topic`] number, `len` ≤ [`MAX_PAYLOAD`], and the
//! Fletcher-16 check covers `topic`, `len` and the payload. Two sync bytes plus the
//! check let the decoder resynchronise after a lost byte without escaping (a UART link
//! loses whole bytes, it does not flip runs of them). HAL-free and host-tested.
#![cfg_attr(not(test), no_std)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::indexing_slicing))]

/// Link topic numbers (fixed by this protocol, independent of the bus message IDs
/// the planner assigns, so the host side does not change when robot.toml does).
pub mod topic {
    /// Host → robot: `Twist` velocity command (forwarded as robot.toml `teleop`).
    pub const TELEOP: u8 = 1;
    /// Robot → host: `Odometry`.
    pub const ODOMETRY: u8 = 2;
    /// Robot → host: `Proximity`.
    pub const PROXIMITY: u8 = 3;
    /// Robot → host: `Battery`.
    pub const BATTERY: u8 = 4;
    /// Robot → host: `LogLine`.
    pub const LOG: u8 = 5;
}

/// First sync byte.
pub const SYNC0: u8 = 0xA5;
/// Second sync byte.
pub const SYNC1: u8 = 0x5A;
/// Largest payload (the biggest Triskar2 message, `LogLine`, is 32 bytes).
pub const MAX_PAYLOAD: usize = 32;
/// Header (2 sync + topic + len) and trailer (check) bytes.
pub const OVERHEAD: usize = 6;

/// Fletcher-16 over `bytes` (sums mod 255), continuing from `(a, b)`.
const fn fletcher(mut a: u16, mut b: u16, bytes: &[u8]) -> (u16, u16) {
    let mut rest = bytes;
    while let [x, tail @ ..] = rest {
        a = (a + *x as u16) % 255;
        b = (b + a) % 255;
        rest = tail;
    }
    (a, b)
}

fn check(topic: u8, payload: &[u8]) -> [u8; 2] {
    let (a, b) = fletcher(0, 0, &[topic, payload.len() as u8]);
    let (a, b) = fletcher(a, b, payload);
    [a as u8, b as u8]
}

/// Writes the frame of `payload` on `topic` into `out`; returns its length, or `None`
/// when the payload is too long or `out` too short.
pub fn encode(topic: u8, payload: &[u8], out: &mut [u8]) -> Option<usize> {
    let n = payload.len();
    if n > MAX_PAYLOAD {
        return None;
    }
    let frame = out.get_mut(..n + OVERHEAD)?;
    let (head, rest) = frame.split_at_mut(4);
    head.copy_from_slice(&[SYNC0, SYNC1, topic, n as u8]);
    let (body, tail) = rest.split_at_mut(n);
    body.copy_from_slice(payload);
    tail.copy_from_slice(&check(topic, payload));
    Some(n + OVERHEAD)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Sync0,
    Sync1,
    Topic,
    Len,
    Payload,
    Check0,
    Check1,
}

/// Link error counters (saturating).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Frames accepted.
    pub frames: u32,
    /// Frames whose check failed.
    pub bad_check: u32,
    /// Frames announcing more than `MAX_PAYLOAD` bytes.
    pub too_long: u32,
    /// Bytes skipped while looking for a frame start.
    pub skipped: u32,
}

/// Byte-at-a-time decoder (feed it from the UART RX interrupt).
#[derive(Clone, Debug)]
pub struct Decoder {
    state: State,
    topic: u8,
    len: usize,
    got: usize,
    check0: u8,
    buf: [u8; MAX_PAYLOAD],
    stats: LinkStats,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// Waiting for a frame start.
    pub const fn new() -> Self {
        Decoder {
            state: State::Sync0,
            topic: 0,
            len: 0,
            got: 0,
            check0: 0,
            buf: [0; MAX_PAYLOAD],
            stats: LinkStats {
                frames: 0,
                bad_check: 0,
                too_long: 0,
                skipped: 0,
            },
        }
    }

    /// Counters.
    pub fn stats(&self) -> LinkStats {
        self.stats
    }

    /// Feeds one byte; a complete, checked frame comes back as `(topic, payload)`.
    pub fn push(&mut self, byte: u8) -> Option<(u8, &[u8])> {
        match self.state {
            State::Sync0 => {
                if byte == SYNC0 {
                    self.state = State::Sync1;
                } else {
                    bump(&mut self.stats.skipped);
                }
            }
            State::Sync1 => {
                self.state = match byte {
                    SYNC1 => State::Topic,
                    SYNC0 => State::Sync1,
                    _ => {
                        bump(&mut self.stats.skipped);
                        State::Sync0
                    }
                };
            }
            State::Topic => {
                self.topic = byte;
                self.state = State::Len;
            }
            State::Len => {
                self.len = usize::from(byte);
                self.got = 0;
                self.state = if self.len > MAX_PAYLOAD {
                    bump(&mut self.stats.too_long);
                    State::Sync0
                } else if self.len == 0 {
                    State::Check0
                } else {
                    State::Payload
                };
            }
            State::Payload => {
                if let Some(b) = self.buf.get_mut(self.got) {
                    *b = byte;
                }
                self.got += 1;
                if self.got >= self.len {
                    self.state = State::Check0;
                }
            }
            State::Check0 => {
                self.check0 = byte;
                self.state = State::Check1;
            }
            State::Check1 => {
                self.state = State::Sync0;
                let payload = self.buf.get(..self.len)?;
                if check(self.topic, payload) == [self.check0, byte] {
                    bump(&mut self.stats.frames);
                    return Some((self.topic, payload));
                }
                bump(&mut self.stats.bad_check);
            }
        }
        None
    }
}

fn bump(c: &mut u32) {
    *c = c.saturating_add(1);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(d: &mut Decoder, bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
        bytes
            .iter()
            .filter_map(|&b| d.push(b).map(|(t, p)| (t, p.to_vec())))
            .collect()
    }

    #[test]
    fn encodes_known_bytes() {
        let mut out = [0u8; 16];
        let n = encode(0x48, &[1, 2, 3], &mut out).unwrap();
        // Fletcher-16 over 48 03 01 02 03: running sums a = 48 4B 4C 4E 51, so a = 0x51
        // and b = (0x48 + 0x4B + 0x4C + 0x4E + 0x51) mod 255 = 0x7F.
        assert_eq!(&out[..n], &[0xA5, 0x5A, 0x48, 3, 1, 2, 3, 0x51, 0x7F]);
    }

    #[test]
    fn round_trip_and_resync_after_garbage() {
        let mut wire = vec![0x00, 0xA5, 0x13, 0xA5];
        let mut out = [0u8; 40];
        let n = encode(0x40, &[9; 24], &mut out).unwrap();
        wire.extend_from_slice(&out[..n]);
        let n = encode(0x43, &[], &mut out).unwrap();
        wire.extend_from_slice(&out[..n]);
        let mut d = Decoder::new();
        let got = frames(&mut d, &wire);
        assert_eq!(got, vec![(0x40, vec![9; 24]), (0x43, vec![])]);
        assert_eq!(d.stats().frames, 2);
        assert_eq!(d.stats().skipped, 2);
    }

    #[test]
    fn corrupted_byte_is_rejected_and_next_frame_accepted() {
        let mut out = [0u8; 16];
        let n = encode(0x48, &[1, 2, 3, 4], &mut out).unwrap();
        let mut wire = out[..n].to_vec();
        wire[5] ^= 0x10;
        wire.extend_from_slice(&out[..n]);
        let mut d = Decoder::new();
        assert_eq!(frames(&mut d, &wire), vec![(0x48, vec![1, 2, 3, 4])]);
        assert_eq!(d.stats().bad_check, 1);
    }

    #[test]
    fn refuses_oversized_payloads() {
        let mut out = [0u8; 64];
        assert_eq!(encode(1, &[0; 33], &mut out), None);
        assert_eq!(encode(1, &[0; 4], &mut out[..9]), None);
        let mut d = Decoder::new();
        assert!(frames(&mut d, &[0xA5, 0x5A, 1, 33, 0, 0]).is_empty());
        assert_eq!(d.stats().too_long, 1);
    }
}
