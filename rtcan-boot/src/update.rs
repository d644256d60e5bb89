//! The update protocol (docs/SERVICES.md §4.2), module side. The host sends NRT
//! messages to the module's update service; every request gets one reply, so the host
//! retries what was lost and a repeated request is harmless:
//!
//! - `Begin { len, crc, fingerprint }` → erases the slot that is *not* booted →
//!   `Ready { slot }`.
//! - `Data { offset, bytes }` (an even number of bytes, except the last chunk) →
//!   programmed if `offset` is the next expected one; `Ack { next }` either way (a
//!   duplicate or out-of-order chunk is not written again: flash programs only onto
//!   erased half-words).
//! - `End` → CRC-32 and fingerprint of the received image checked, header written
//!   (the commit) → `Done { slot, seq }`; or `Failed { why }`, nothing committed.
use rtcan_pubsub::flash::{Flash, FlashError};

use crate::{Crc32, Header, Layout};

/// Largest data chunk in one `Data` message (an NRT transfer of 256 bytes minus the
/// 5-byte message header, rounded down to half-words).
pub const MAX_CHUNK: usize = 250;

/// A request from the host.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Msg<'a> {
    Begin {
        len: u32,
        crc: u32,
        fingerprint: u32,
    },
    Data {
        offset: u32,
        bytes: &'a [u8],
    },
    End,
}

/// Why an update was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Why {
    /// The image does not fit a slot.
    TooLarge,
    /// `Data` or `End` without a `Begin`.
    NotStarted,
    /// Malformed message (odd-length chunk in the middle, chunk too long).
    BadMessage,
    /// The image's CRC-32 differs from the one announced.
    Crc,
    /// The image was built for another robot than announced.
    Fingerprint,
    /// Flash error (`FlashError`).
    Flash,
    /// `End` before every byte arrived.
    Incomplete,
}

/// A reply to the host.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reply {
    Ready { slot: u8 },
    Ack { next: u32 },
    Done { slot: u8, seq: u16 },
    Failed { why: Why },
}

impl Why {
    const ALL: [Why; 7] = [
        Why::TooLarge,
        Why::NotStarted,
        Why::BadMessage,
        Why::Crc,
        Why::Fingerprint,
        Why::Flash,
        Why::Incomplete,
    ];
    /// Wire code (1..=7).
    pub fn code(self) -> u8 {
        match self {
            Why::TooLarge => 1,
            Why::NotStarted => 2,
            Why::BadMessage => 3,
            Why::Crc => 4,
            Why::Fingerprint => 5,
            Why::Flash => 6,
            Why::Incomplete => 7,
        }
    }
    pub fn from_code(c: u8) -> Option<Why> {
        Why::ALL.into_iter().find(|w| w.code() == c)
    }
}

impl Reply {
    /// Wire form, one 8-byte frame: op, then little-endian fields, zero padded.
    /// Ready `01 slot`, Ack `02 next:u32`, Done `03 slot seq:u16`, Failed `04 why`.
    pub fn encode(&self) -> [u8; 8] {
        match *self {
            Reply::Ready { slot } => [1, slot, 0, 0, 0, 0, 0, 0],
            Reply::Ack { next } => {
                let [n0, n1, n2, n3] = next.to_le_bytes();
                [2, n0, n1, n2, n3, 0, 0, 0]
            }
            Reply::Done { slot, seq } => {
                let [s0, s1] = seq.to_le_bytes();
                [3, slot, s0, s1, 0, 0, 0, 0]
            }
            Reply::Failed { why } => [4, why.code(), 0, 0, 0, 0, 0, 0],
        }
    }

    /// `None` for anything but an 8-byte reply of a known op.
    pub fn decode(b: &[u8]) -> Option<Reply> {
        let b: &[u8; 8] = b.try_into().ok()?;
        let [op, a, c, d, e, ..] = *b;
        match op {
            1 => Some(Reply::Ready { slot: a }),
            2 => Some(Reply::Ack {
                next: u32::from_le_bytes([a, c, d, e]),
            }),
            3 => Some(Reply::Done {
                slot: a,
                seq: u16::from_le_bytes([c, d]),
            }),
            4 => Some(Reply::Failed {
                why: Why::from_code(a)?,
            }),
            _ => None,
        }
    }
}

fn put(out: &mut [u8], at: usize, bytes: &[u8]) -> Option<()> {
    out.get_mut(at..at + bytes.len())?.copy_from_slice(bytes);
    Some(())
}

impl Msg<'_> {
    /// Wire form: op byte, then little-endian fields (Data: offset u32 then the bytes).
    pub fn encode(&self, out: &mut [u8]) -> Option<usize> {
        match *self {
            Msg::Begin {
                len,
                crc,
                fingerprint,
            } => {
                put(out, 0, &[1])?;
                put(out, 1, &len.to_le_bytes())?;
                put(out, 5, &crc.to_le_bytes())?;
                put(out, 9, &fingerprint.to_le_bytes())?;
                Some(13)
            }
            Msg::Data { offset, bytes } => {
                put(out, 0, &[2])?;
                put(out, 1, &offset.to_le_bytes())?;
                put(out, 5, bytes)?;
                Some(5 + bytes.len())
            }
            Msg::End => {
                put(out, 0, &[3])?;
                Some(1)
            }
        }
    }
}

impl<'a> Msg<'a> {
    /// `None` for anything malformed.
    pub fn decode(b: &'a [u8]) -> Option<Msg<'a>> {
        let (&op, rest) = b.split_first()?;
        let u = |s: &[u8]| -> Option<u32> { Some(u32::from_le_bytes(s.try_into().ok()?)) };
        match op {
            1 if rest.len() == 12 => Some(Msg::Begin {
                len: u(rest.get(0..4)?)?,
                crc: u(rest.get(4..8)?)?,
                fingerprint: u(rest.get(8..12)?)?,
            }),
            2 if rest.len() >= 5 && rest.len() <= 4 + MAX_CHUNK => Some(Msg::Data {
                offset: u(rest.get(0..4)?)?,
                bytes: rest.get(4..)?,
            }),
            3 if rest.is_empty() => Some(Msg::End),
            _ => None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Session {
    slot: usize,
    seq: u16,
    len: u32,
    crc: u32,
    fingerprint: u32,
    next: u32,
    /// Whether the last chunk (odd length) was written.
    done: bool,
}

/// Counters of the update service (nothing lost silently).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UpdateCounters {
    pub duplicates: u32,
    pub out_of_order: u32,
    pub malformed: u32,
    pub failed: u32,
}

/// The module side of the protocol (runs in the bootloader, or in the application
/// through the same code: the slot written is never the running one).
pub struct Receiver<'l> {
    layout: &'l Layout,
    /// The slot currently booted (never written), if any.
    running: Option<usize>,
    session: Option<Session>,
    pub counters: UpdateCounters,
}

impl<'l> Receiver<'l> {
    pub fn new(layout: &'l Layout, running: Option<usize>) -> Self {
        Receiver {
            layout,
            running,
            session: None,
            counters: UpdateCounters::default(),
        }
    }

    fn fail(&mut self, why: Why) -> Reply {
        self.counters.failed = self.counters.failed.saturating_add(1);
        Reply::Failed { why }
    }

    /// Handles one request (raw bytes as received).
    pub fn handle(&mut self, f: &mut impl Flash, bytes: &[u8]) -> Reply {
        let Some(msg) = Msg::decode(bytes) else {
            self.counters.malformed = self.counters.malformed.saturating_add(1);
            return self.fail(Why::BadMessage);
        };
        match msg {
            Msg::Begin {
                len,
                crc,
                fingerprint,
            } => {
                if let Some(s) = self.session.filter(|s| {
                    s.len == len && s.crc == crc && s.fingerprint == fingerprint && s.next == 0
                }) {
                    // A repeated Begin (its Ready was lost): nothing to do again.
                    self.counters.duplicates = self.counters.duplicates.saturating_add(1);
                    return Reply::Ready { slot: s.slot as u8 };
                }
                if len > self.layout.capacity(f.page_bytes())
                    || len < self.layout.fingerprint_offset + 4
                {
                    return self.fail(Why::TooLarge);
                }
                let slot = match self.running {
                    Some(0) => 1,
                    _ => 0,
                };
                let other = self.layout.header(f, 1 - slot).map_or(0, |h| h.seq);
                if self.layout.erase_slot(f, slot).is_err() {
                    self.session = None;
                    return self.fail(Why::Flash);
                }
                self.session = Some(Session {
                    slot,
                    seq: other.wrapping_add(1),
                    len,
                    crc,
                    fingerprint,
                    next: 0,
                    done: false,
                });
                Reply::Ready { slot: slot as u8 }
            }
            Msg::Data { offset, bytes } => {
                let Some(mut s) = self.session else {
                    return self.fail(Why::NotStarted);
                };
                if offset != s.next || s.done {
                    if offset < s.next || s.done {
                        self.counters.duplicates = self.counters.duplicates.saturating_add(1);
                    } else {
                        self.counters.out_of_order = self.counters.out_of_order.saturating_add(1);
                    }
                    return Reply::Ack { next: s.next };
                }
                let n = u32::try_from(bytes.len()).unwrap_or(u32::MAX);
                let end = offset.saturating_add(n);
                if end > s.len || (bytes.len() % 2 == 1 && end != s.len) {
                    self.counters.malformed = self.counters.malformed.saturating_add(1);
                    return self.fail(Why::BadMessage);
                }
                let mut off = offset;
                for pair in bytes.chunks(2) {
                    let w = match *pair {
                        [a, b] => u16::from_le_bytes([a, b]),
                        [a] => u16::from_le_bytes([a, 0xFF]),
                        _ => 0xFFFF,
                    };
                    let Some(addr) = self.layout.image_addr(f, s.slot, off) else {
                        return self.fail(Why::Flash);
                    };
                    // 0xFFFF is what erased flash holds already: nothing to program.
                    if w != 0xFFFF && f.program(addr, w).is_err() {
                        self.session = None;
                        return self.fail(Why::Flash);
                    }
                    off += 2;
                }
                s.next = end;
                s.done = n % 2 == 1;
                self.session = Some(s);
                Reply::Ack { next: end }
            }
            Msg::End => {
                let Some(s) = self.session else {
                    return self.fail(Why::NotStarted);
                };
                if s.next != s.len {
                    return self.fail(Why::Incomplete);
                }
                self.session = None;
                if self.layout.image_crc(f, s.slot, s.len) != Some(s.crc) {
                    return self.fail(Why::Crc);
                }
                if self.layout.image_fingerprint(f, s.slot) != Some(s.fingerprint) {
                    return self.fail(Why::Fingerprint);
                }
                let h = Header {
                    seq: s.seq,
                    len: s.len,
                    crc: s.crc,
                    fingerprint: s.fingerprint,
                };
                match self.layout.commit(f, s.slot, h) {
                    Ok(()) => Reply::Done {
                        slot: s.slot as u8,
                        seq: s.seq,
                    },
                    Err(FlashError::PowerCut | FlashError::NotErased | FlashError::OutOfRange) => {
                        self.fail(Why::Flash)
                    }
                }
            }
        }
    }
}

/// The host side: the messages of a whole update of `image`, in order.
pub fn messages(
    image: &[u8],
    fingerprint: u32,
    chunk: usize,
) -> impl Iterator<Item = (Msg<'_>, u32)> {
    let chunk = chunk.clamp(2, MAX_CHUNK) & !1;
    let len = u32::try_from(image.len()).unwrap_or(u32::MAX);
    let begin = Msg::Begin {
        len,
        crc: Crc32::of(image),
        fingerprint,
    };
    core::iter::once((begin, 0))
        .chain(image.chunks(chunk).enumerate().map(move |(k, bytes)| {
            let offset = u32::try_from(k * chunk).unwrap_or(u32::MAX);
            (Msg::Data { offset, bytes }, offset)
        }))
        .chain(core::iter::once((Msg::End, len)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtcan_pubsub::flash::F103Flash;

    // 2 slots of 30 pages (1 header page + 29 KiB of image): the F103C8's 64 KiB minus
    // the 4 KiB bootloader region, which this region does not contain.
    const LAYOUT: Layout = Layout {
        slot_page: [0, 30],
        slot_pages: 30,
        fingerprint_offset: 0x1D0,
    };
    type F = F103Flash<60>;

    fn image(len: usize, fingerprint: u32, salt: u8) -> Vec<u8> {
        let mut v: Vec<u8> = (0..len)
            .map(|i| (i as u8).wrapping_mul(31) ^ salt)
            .collect();
        let o = LAYOUT.fingerprint_offset as usize;
        v[o..o + 4].copy_from_slice(&fingerprint.to_le_bytes());
        v
    }

    /// Runs an update; `Err` with the flash at the point of failure.
    fn update(f: &mut F, running: Option<usize>, img: &[u8], fp: u32) -> Result<Reply, Reply> {
        let mut rx = Receiver::new(&LAYOUT, running);
        let mut buf = [0u8; 300];
        let mut last = Reply::Ack { next: 0 };
        for (m, _) in messages(img, fp, 248) {
            let n = m.encode(&mut buf).unwrap();
            last = rx.handle(f, &buf[..n]);
            if matches!(last, Reply::Failed { .. }) {
                return Err(last);
            }
        }
        Ok(last)
    }

    #[test]
    fn full_update_of_28_kib_then_the_next_goes_to_the_other_slot() {
        let mut f = F::new();
        let a = image(28 * 1024, 0xF00D, 1);
        assert_eq!(
            update(&mut f, None, &a, 0xF00D),
            Ok(Reply::Done { slot: 0, seq: 1 })
        );
        assert_eq!(LAYOUT.boot_slot(&f, Some(0xF00D)), Some(0));
        assert_eq!(
            LAYOUT.boot_slot(&f, Some(0xBEEF)),
            None,
            "another robot's image"
        );
        let b = image(1001, 0xF00D, 2);
        assert_eq!(
            update(&mut f, Some(0), &b, 0xF00D),
            Ok(Reply::Done { slot: 1, seq: 2 })
        );
        assert_eq!(LAYOUT.boot_slot(&f, None), Some(1));
        // A third update overwrites slot 0, never the running slot 1.
        let c = image(600, 0xF00D, 3);
        assert_eq!(
            update(&mut f, Some(1), &c, 0xF00D),
            Ok(Reply::Done { slot: 0, seq: 3 })
        );
        assert_eq!(LAYOUT.boot_slot(&f, None), Some(0));
        assert_eq!(LAYOUT.image_crc(&f, 1, 1001), Some(Crc32::of(&b)));
    }

    #[test]
    fn bad_images_are_never_committed() {
        let mut f = F::new();
        let good = image(2000, 7, 0);
        update(&mut f, None, &good, 7).unwrap();
        // Announced fingerprint differs from the one built into the image.
        let other = image(2000, 8, 5);
        assert_eq!(
            update(&mut f, Some(0), &other, 7),
            Err(Reply::Failed {
                why: Why::Fingerprint
            })
        );
        // CRC mismatch: a corrupted chunk on the way.
        let mut rx = Receiver::new(&LAYOUT, Some(0));
        let img = image(600, 7, 9);
        let mut buf = [0u8; 300];
        let mut last = None;
        for (m, _) in messages(&img, 7, 248) {
            let n = m.encode(&mut buf).unwrap();
            if let Msg::Data { offset: 248, .. } = m {
                buf[10] ^= 0x40;
            }
            last = Some(rx.handle(&mut f, &buf[..n]));
        }
        assert_eq!(last, Some(Reply::Failed { why: Why::Crc }));
        // Too large, malformed, out of sequence.
        let mut rx = Receiver::new(&LAYOUT, Some(0));
        let begin = Msg::Begin {
            len: 29 * 1024 + 2,
            crc: 0,
            fingerprint: 7,
        };
        let n = begin.encode(&mut buf).unwrap();
        assert_eq!(
            rx.handle(&mut f, &buf[..n]),
            Reply::Failed { why: Why::TooLarge }
        );
        assert_eq!(
            rx.handle(&mut f, &[3]),
            Reply::Failed {
                why: Why::NotStarted
            }
        );
        assert_eq!(
            rx.handle(&mut f, &[9, 9]),
            Reply::Failed {
                why: Why::BadMessage
            }
        );
        assert_eq!(
            rx.handle(&mut f, &[]),
            Reply::Failed {
                why: Why::BadMessage
            }
        );
        assert_eq!(rx.counters.malformed, 2);
        // Through all of it the good image stays the one booted.
        assert_eq!(LAYOUT.boot_slot(&f, Some(7)), Some(0));
    }

    #[test]
    fn lost_and_repeated_messages_are_harmless() {
        let mut f = F::new();
        let img = image(3000, 5, 4);
        let mut rx = Receiver::new(&LAYOUT, None);
        let mut buf = [0u8; 300];
        let msgs: Vec<_> = messages(&img, 5, 248).collect();
        let data_at = |next: u32| {
            msgs.iter()
                .position(|(m, o)| matches!(m, Msg::Data { .. }) && *o == next)
                .unwrap_or(msgs.len() - 1)
        };
        let (mut k, mut step, mut lost) = (0, 0, 0);
        loop {
            step += 1;
            assert!(step < 200, "no progress");
            // Every fourth Data message is lost on the way (never reaches the module):
            // the module answers the next one with the offset it still expects.
            if step % 4 == 0 && matches!(msgs[k].0, Msg::Data { .. }) && k + 2 < msgs.len() {
                lost += 1;
                k += 1;
            }
            let n = msgs[k].0.encode(&mut buf).unwrap();
            let r = rx.handle(&mut f, &buf[..n]);
            // Every third reply is lost: the host repeats the request, same answer.
            if step % 3 == 0 && !matches!(r, Reply::Done { .. }) {
                assert_eq!(rx.handle(&mut f, &buf[..n]), r, "step {step}");
            }
            match r {
                Reply::Ready { slot } => {
                    assert_eq!(slot, 0);
                    k += 1;
                }
                Reply::Ack { next } => k = data_at(next),
                Reply::Done { slot, seq } => {
                    assert_eq!((slot, seq), (0, 1));
                    break;
                }
                Reply::Failed { why } => panic!("{why:?} at step {step}"),
            }
        }
        assert!(lost >= 2);
        assert_eq!(LAYOUT.boot_slot(&f, Some(5)), Some(0));
        assert_eq!(LAYOUT.image_crc(&f, 0, 3000), Some(Crc32::of(&img)));
        assert!(rx.counters.duplicates >= 3, "{:?}", rx.counters);
        assert!(rx.counters.out_of_order >= 2, "{:?}", rx.counters);
    }

    /// A power cut at every flash operation of an update (erase, each program, the
    /// commit): after the reset the old image still boots, unless the cut came after
    /// the commit's last half-word, in which case the new one does. Never neither.
    #[test]
    fn power_cut_at_every_step_leaves_a_bootable_module() {
        let old = image(4000, 0xAA, 1);
        let new = image(5000, 0xAA, 2);
        let mut base = F::new();
        update(&mut base, None, &old, 0xAA).unwrap();
        // Operations of an uncut update from here.
        let mut probe = base.clone();
        let ops0 = probe.ops;
        update(&mut probe, Some(0), &new, 0xAA).unwrap();
        let total = probe.ops - ops0;
        eprintln!("flash operations: {total}");
        assert!(total > 2500, "{total}");
        for cut in 0..total {
            let mut f = base.clone();
            f.cut_after = Some(cut);
            let r = update(&mut f, Some(0), &new, 0xAA);
            assert!(r.is_err(), "cut {cut} must interrupt");
            f.cut_after = None;
            // Reset: the bootloader decides.
            assert_eq!(
                LAYOUT.boot_slot(&f, Some(0xAA)),
                Some(0),
                "cut at op {cut} of {total}"
            );
            assert_eq!(LAYOUT.image_crc(&f, 0, 4000), Some(Crc32::of(&old)));
            // And the interrupted update can simply be run again.
            if cut % 500 == 0 {
                assert_eq!(
                    update(&mut f, Some(0), &new, 0xAA),
                    Ok(Reply::Done { slot: 1, seq: 2 })
                );
                assert_eq!(LAYOUT.boot_slot(&f, Some(0xAA)), Some(1));
            }
        }
        // A cut during an update with no valid slot at all (first flashing) leaves the
        // bootloader in update mode: boot_slot None, the protocol still answers.
        let mut f = F::new();
        f.cut_after = Some(100);
        assert!(update(&mut f, None, &old, 0xAA).is_err());
        f.cut_after = None;
        assert_eq!(LAYOUT.boot_slot(&f, None), None);
        assert_eq!(
            update(&mut f, None, &old, 0xAA),
            Ok(Reply::Done { slot: 0, seq: 1 })
        );
    }
}
