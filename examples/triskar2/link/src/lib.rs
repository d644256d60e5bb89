//! The gateway's serial link to the host (ROS side): topic-tagged frames, COBS-stuffed,
//! checked by CRC-16, each ended by a zero byte.
//!
//! ```text
//! COBS( topic  payload[n]  crc_lo crc_hi )  0x00
//! ```
//! `topic` is a link topic number (robot.toml `link = "in"|"out"`, numbered 1.. in
//! file order by rtcan-model: the firmware's `rtcan::robot_toml::link`), `n` ≤ [`MAX_PAYLOAD`], and the CRC-16/CCITT-FALSE
//! (poly 0x1021, init 0xFFFF) covers `topic` and the payload. COBS leaves no zero byte
//! inside a frame, so the zero delimiter always marks a frame end: after any lost,
//! added or changed byte the decoder drops at most the frame it is in and is in step
//! again at the next delimiter. The CRC catches what a sum cannot: every error burst up
//! to 16 bits, so also a byte turned from 0x00 into 0xFF (a Fletcher-16 mod 255 check
//! cannot tell 0x00 from 0xFF). HAL-free and host-tested.
#![cfg_attr(not(test), no_std)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::indexing_slicing))]

/// Frame delimiter.
pub const DELIMITER: u8 = 0x00;
/// Largest payload (the biggest Triskar2 message, `LogLine`, is 32 bytes).
pub const MAX_PAYLOAD: usize = 32;
/// Bytes a frame adds to its payload: topic, 2 CRC, 1 COBS code byte (a frame of at most
/// 254 bytes needs one), the delimiter.
pub const OVERHEAD: usize = 5;
/// Unstuffed frame: topic, payload, CRC.
const RAW_MAX: usize = MAX_PAYLOAD + 3;

/// CRC-16/CCITT-FALSE of `bytes`, continuing from `crc` (start with 0xFFFF).
pub const fn crc16(mut crc: u16, bytes: &[u8]) -> u16 {
    let mut rest = bytes;
    while let [x, tail @ ..] = rest {
        crc ^= (*x as u16) << 8;
        let mut k = 0;
        while k < 8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ 0x1021
            } else {
                crc << 1
            };
            k += 1;
        }
        rest = tail;
    }
    crc
}

fn check(topic: u8, payload: &[u8]) -> [u8; 2] {
    crc16(crc16(0xFFFF, &[topic]), payload).to_le_bytes()
}

/// COBS-encodes `raw` into `out` (no delimiter); returns the length, `None` if `out` is
/// too short.
fn cobs_encode(raw: &[u8], out: &mut [u8]) -> Option<usize> {
    let mut code_at = 0;
    let mut w = 1;
    let mut code: u8 = 1;
    for &b in raw {
        if b == 0 {
            *out.get_mut(code_at)? = code;
            code_at = w;
            w += 1;
            code = 1;
        } else {
            *out.get_mut(w)? = b;
            w += 1;
            code += 1;
            if code == 0xFF {
                *out.get_mut(code_at)? = code;
                code_at = w;
                w += 1;
                code = 1;
            }
        }
    }
    *out.get_mut(code_at)? = code;
    Some(w)
}

/// Writes the frame of `payload` on `topic`, delimiter included, into `out`; returns its
/// length, or `None` when the payload is too long or `out` too short.
pub fn encode(topic: u8, payload: &[u8], out: &mut [u8]) -> Option<usize> {
    let n = payload.len();
    if n > MAX_PAYLOAD {
        return None;
    }
    let mut raw = [0u8; RAW_MAX];
    *raw.first_mut()? = topic;
    raw.get_mut(1..1 + n)?.copy_from_slice(payload);
    raw.get_mut(1 + n..3 + n)?
        .copy_from_slice(&check(topic, payload));
    let len = cobs_encode(raw.get(..3 + n)?, out)?;
    *out.get_mut(len)? = DELIMITER;
    Some(len + 1)
}

/// Link number of a bus frame of the host channels (parameters `0xFF00..`, firmware
/// update `0xFF80..`, docs/PROTOCOL.md §2.3), carried as it is on the bus: link topics
/// are numbered from 1, so 0 is free. Payload: the 29-bit identifier (u32 LE), then the
/// frame's 0..=8 data bytes (the DLC is the rest of the payload). The gateway forwards
/// such frames from the host to the bus only if they are NRT frames of the host
/// channels, and every host-channel frame it receives from the bus to the host.
pub const BUS_FRAME: u8 = 0;

/// Writes the link frame carrying the bus frame `raw_id`/`data` into `out`; its length,
/// or `None` for more than 8 data bytes or an `out` too short.
pub fn encode_bus_frame(raw_id: u32, data: &[u8], out: &mut [u8]) -> Option<usize> {
    if data.len() > 8 {
        return None;
    }
    let mut payload = [0u8; 12];
    payload.get_mut(..4)?.copy_from_slice(&raw_id.to_le_bytes());
    payload.get_mut(4..4 + data.len())?.copy_from_slice(data);
    encode(BUS_FRAME, payload.get(..4 + data.len())?, out)
}

/// The identifier and data of a `BUS_FRAME` payload; `None` if shorter than the
/// identifier, longer than 8 data bytes or not a 29-bit identifier.
pub fn decode_bus_frame(payload: &[u8]) -> Option<(u32, &[u8])> {
    let (id, data) = (payload.get(..4)?, payload.get(4..)?);
    let raw = u32::from_le_bytes([*id.first()?, *id.get(1)?, *id.get(2)?, *id.get(3)?]);
    (data.len() <= 8 && raw < (1 << 29)).then_some((raw, data))
}

/// Link error counters (saturating).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Frames accepted.
    pub frames: u32,
    /// Frames whose CRC failed.
    pub bad_check: u32,
    /// Frames longer than the largest payload allows (bytes dropped up to the delimiter).
    pub too_long: u32,
    /// Frames that were not valid COBS or too short to hold a topic and a CRC.
    pub malformed: u32,
}

/// Byte-at-a-time decoder (feed it from the UART RX interrupt or DMA ring).
#[derive(Clone, Debug)]
pub struct Decoder {
    /// Stuffed bytes of the frame so far.
    buf: [u8; RAW_MAX + 1],
    got: usize,
    /// Dropping bytes until the next delimiter (frame too long).
    overflow: bool,
    /// Unstuffed frame handed out by `push`.
    raw: [u8; RAW_MAX],
    stats: LinkStats,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// Waiting for a frame.
    pub const fn new() -> Self {
        Decoder {
            buf: [0; RAW_MAX + 1],
            got: 0,
            overflow: false,
            raw: [0; RAW_MAX],
            stats: LinkStats {
                frames: 0,
                bad_check: 0,
                too_long: 0,
                malformed: 0,
            },
        }
    }

    /// Counters.
    pub fn stats(&self) -> LinkStats {
        self.stats
    }

    /// Feeds one byte; a complete, checked frame comes back as `(topic, payload)`.
    pub fn push(&mut self, byte: u8) -> Option<(u8, &[u8])> {
        if byte != DELIMITER {
            match self.buf.get_mut(self.got) {
                Some(b) if !self.overflow => {
                    *b = byte;
                    self.got += 1;
                }
                _ => {
                    if !self.overflow {
                        bump(&mut self.stats.too_long);
                    }
                    self.overflow = true;
                }
            }
            return None;
        }
        let (got, overflow) = (self.got, self.overflow);
        self.got = 0;
        self.overflow = false;
        if overflow || got == 0 {
            // The tail of an overlong frame, or an empty frame (two delimiters in a row:
            // a sender may lead with one to flush a half-received frame).
            return None;
        }
        let Some(n) = cobs_decode(self.buf.get(..got)?, &mut self.raw) else {
            bump(&mut self.stats.malformed);
            return None;
        };
        if n < 3 {
            bump(&mut self.stats.malformed);
            return None;
        }
        let (topic, rest) = self.raw.get(..n)?.split_first()?;
        let (payload, crc) = rest.split_at(n - 3);
        if check(*topic, payload) != crc {
            bump(&mut self.stats.bad_check);
            return None;
        }
        bump(&mut self.stats.frames);
        Some((*topic, payload))
    }
}

/// COBS-decodes `src` (no delimiter) into `out`; `None` if `src` is not valid COBS.
fn cobs_decode(src: &[u8], out: &mut [u8]) -> Option<usize> {
    let (mut r, mut w) = (0, 0);
    while r < src.len() {
        let code = usize::from(*src.get(r)?);
        if code == 0 || r + code > src.len() {
            return None;
        }
        r += 1;
        for _ in 1..code {
            *out.get_mut(w)? = *src.get(r)?;
            r += 1;
            w += 1;
        }
        if code != 0xFF && r < src.len() {
            *out.get_mut(w)? = 0;
            w += 1;
        }
    }
    Some(w)
}

fn bump(c: &mut u32) {
    *c = c.saturating_add(1);
}

#[cfg(test)]
mod tests {
    /// Link numbers as Triskar2's robot.toml declares them (teleop in; odometry,
    /// proximity, battery, log out).
    mod topic {
        pub const TELEOP: u8 = 1;
        pub const ODOMETRY: u8 = 2;
        pub const PROXIMITY: u8 = 3;
        pub const BATTERY: u8 = 4;
    }
    use super::*;

    fn frames(d: &mut Decoder, bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
        bytes
            .iter()
            .filter_map(|&b| d.push(b).map(|(t, p)| (t, p.to_vec())))
            .collect()
    }

    fn enc(topic: u8, payload: &[u8]) -> Vec<u8> {
        let mut out = [0u8; MAX_PAYLOAD + OVERHEAD];
        let n = encode(topic, payload, &mut out).unwrap();
        out[..n].to_vec()
    }

    #[test]
    fn bus_frames_round_trip_with_exact_bytes() {
        // A parameter get to module 1 (identifier 0x1FFF8080).
        let mut out = [0u8; MAX_PAYLOAD + OVERHEAD];
        let n = encode_bus_frame(0x1FFF_8080, &[1, 0, 0, 0, 0, 0, 0, 0], &mut out).unwrap();
        let f = &out[..n];
        // COBS(topic, 12 bytes, CRC) = 16 bytes, and the delimiter.
        assert_eq!(n, 17);
        let mut d = Decoder::new();
        let got = frames(&mut d, f);
        assert_eq!(
            got,
            vec![(
                BUS_FRAME,
                vec![0x80, 0x80, 0xFF, 0x1F, 1, 0, 0, 0, 0, 0, 0, 0]
            )]
        );
        assert_eq!(
            decode_bus_frame(&got[0].1),
            Some((0x1FFF_8080, &[1u8, 0, 0, 0, 0, 0, 0, 0][..]))
        );
        // An empty frame, and what is refused.
        assert_eq!(
            decode_bus_frame(&[1, 2, 3, 0]),
            Some((0x0003_0201, &[][..]))
        );
        assert_eq!(decode_bus_frame(&[1, 2, 3]), None);
        assert_eq!(
            decode_bus_frame(&[0, 0, 0, 0x20]),
            None,
            "30-bit identifier"
        );
        assert_eq!(decode_bus_frame(&[0; 13]), None, "9 data bytes");
        assert_eq!(encode_bus_frame(1, &[0; 9], &mut out), None);
    }

    #[test]
    fn crc_is_ccitt_false() {
        // The catalogue check value of CRC-16/CCITT-FALSE.
        assert_eq!(crc16(0xFFFF, b"123456789"), 0x29B1);
    }

    #[test]
    fn encodes_known_bytes() {
        // Raw 48 01 00 03 + CRC; the zero is stuffed away.
        let crc = crc16(0xFFFF, &[0x48, 0x01, 0x00, 0x03]).to_le_bytes();
        // This input's CRC has no zero byte (one would be stuffed too).
        assert!(crc.iter().all(|&b| b != 0));
        let want = vec![0x03, 0x48, 0x01, 0x04, 0x03, crc[0], crc[1], 0x00];
        assert_eq!(enc(0x48, &[0x01, 0x00, 0x03]), want);
        // No zero anywhere but the delimiter, even for an all-zero payload.
        let z = enc(0, &[0; MAX_PAYLOAD]);
        assert_eq!(z.len(), MAX_PAYLOAD + OVERHEAD);
        assert_eq!(z.iter().filter(|&&b| b == 0).count(), 1);
        assert_eq!(*z.last().unwrap(), 0);
    }

    #[test]
    fn round_trip_every_length_and_value() {
        let mut d = Decoder::new();
        for n in 0..=MAX_PAYLOAD {
            for fill in [0u8, 1, 0xFF, 0x5A] {
                let p: Vec<u8> = (0..n)
                    .map(|i| fill.wrapping_add((i as u8).wrapping_mul(37)))
                    .collect();
                assert_eq!(frames(&mut d, &enc(7, &p)), vec![(7, p.clone())]);
            }
        }
        assert_eq!(d.stats().frames, 4 * (MAX_PAYLOAD as u32 + 1));
    }

    #[test]
    fn resyncs_at_the_next_delimiter_after_a_lost_byte() {
        let a = enc(topic::ODOMETRY, &[1; 24]);
        let b = enc(topic::BATTERY, &[2, 3, 4, 5, 6]);
        for lost in 0..a.len() - 1 {
            let mut wire = a.clone();
            wire.remove(lost);
            wire.extend_from_slice(&b);
            let mut d = Decoder::new();
            // The damaged frame is dropped (never delivered wrong), the next one arrives.
            assert_eq!(
                frames(&mut d, &wire),
                vec![(topic::BATTERY, vec![2, 3, 4, 5, 6])],
                "lost byte {lost}"
            );
            let s = d.stats();
            assert_eq!(s.frames, 1);
            assert_eq!(s.bad_check + s.malformed, 1, "lost byte {lost}: {s:?}");
        }
        // Garbage before the first frame costs nothing but one dropped piece.
        let mut wire = vec![0x13, 0xA5, 0x00];
        wire.extend_from_slice(&b);
        let mut d = Decoder::new();
        assert_eq!(frames(&mut d, &wire).len(), 1);
    }

    #[test]
    fn catches_a_zero_turned_into_ff() {
        // Fletcher-16 mod 255 cannot see this: 0x00 and 0xFF are both 0 mod 255.
        let good = enc(topic::TELEOP, &[0x10, 0x00, 0x20]);
        let mut d = Decoder::new();
        let mut bad_wire = Vec::new();
        // The sender's frame with its zero payload byte received as 0xFF (stuffed
        // again, as the wire would carry it), the CRC the sender computed.
        let crc = check(topic::TELEOP, &[0x10, 0x00, 0x20]);
        let raw = [topic::TELEOP, 0x10, 0xFF, 0x20, crc[0], crc[1]];
        let mut out = [0u8; 16];
        let n = cobs_encode(&raw, &mut out).unwrap();
        bad_wire.extend_from_slice(&out[..n]);
        bad_wire.push(0);
        bad_wire.extend_from_slice(&good);
        assert_eq!(
            frames(&mut d, &bad_wire),
            vec![(topic::TELEOP, vec![0x10, 0x00, 0x20])]
        );
        assert_eq!(d.stats().bad_check, 1);
    }

    #[test]
    fn every_single_bit_flip_is_caught() {
        let a = enc(topic::PROXIMITY, &[0x20, 0x03, 0, 0, 0xFF, 0x7F, 1, 2]);
        for i in 0..a.len() - 1 {
            for bit in 0..8 {
                let mut wire = a.clone();
                wire[i] ^= 1 << bit;
                let mut d = Decoder::new();
                let got = frames(&mut d, &wire);
                assert!(got.is_empty(), "byte {i} bit {bit}: {got:?}");
            }
        }
    }

    #[test]
    fn refuses_oversized_payloads_and_recovers() {
        let mut out = [0u8; 64];
        assert_eq!(encode(1, &[0; MAX_PAYLOAD + 1], &mut out), None);
        assert_eq!(encode(1, &[0; 4], &mut out[..8]), None);
        let mut wire = vec![0x55; 200];
        wire.push(0);
        wire.extend_from_slice(&enc(1, &[9, 9]));
        let mut d = Decoder::new();
        assert_eq!(frames(&mut d, &wire), vec![(1, vec![9, 9])]);
        assert_eq!(d.stats().too_long, 1);
        // Too short to hold a topic and a CRC; invalid COBS (code past the end).
        assert!(frames(&mut d, &[0x02, 0x05, 0x00, 0x09, 0x01, 0x00]).is_empty());
        assert_eq!(d.stats().malformed, 2);
    }
}
