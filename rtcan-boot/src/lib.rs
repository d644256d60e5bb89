//! Firmware update over RTCAN (docs/SERVICES.md §4), the part that decides what runs:
//! two application slots (A/B) in flash, each with a header page written *last*, after
//! the image was received and verified (CRC-32 and the robot fingerprint). The
//! bootloader boots the valid slot with the newest sequence number; an update only ever
//! erases and writes the other slot, so a power cut at any step leaves the old image
//! bootable (and with no valid slot at all, the bootloader stays in update mode: the
//! module is never bricked). The bootloader's own flash region is outside both slots and
//! nothing here can address it.
#![cfg_attr(not(test), no_std)]
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::indexing_slicing,
        clippy::panic
    )
)]

pub mod can;
pub mod sender;
pub mod update;

use rtcan_pubsub::flash::{Flash, FlashError};

/// Header magic ("RB").
pub const MAGIC: u16 = 0x5242;

/// Where the slots are, in pages of the region the `Flash` covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// First page of slot A and of slot B.
    pub slot_page: [u32; 2],
    /// Pages per slot: one header page, then the image.
    pub slot_pages: u32,
    /// Image offset of the robot fingerprint the image was built for (the generated
    /// `FINGERPRINT`, placed by the linker script at a fixed offset after the vector
    /// table): the header must carry the same one.
    pub fingerprint_offset: u32,
}

/// A slot's header (first 8 half-words of its header page).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    pub seq: u16,
    pub len: u32,
    pub crc: u32,
    pub fingerprint: u32,
}

/// CRC-32 (IEEE 802.3, reflected, as zlib's `crc32`), incremental.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crc32(u32);

impl Default for Crc32 {
    fn default() -> Self {
        Crc32(0xFFFF_FFFF)
    }
}

impl Crc32 {
    pub fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u32::from(b);
            for _ in 0..8 {
                self.0 = if self.0 & 1 != 0 {
                    (self.0 >> 1) ^ 0xEDB8_8320
                } else {
                    self.0 >> 1
                };
            }
        }
    }
    pub fn finish(self) -> u32 {
        !self.0
    }
    pub fn of(bytes: &[u8]) -> u32 {
        let mut c = Crc32::default();
        c.update(bytes);
        c.finish()
    }
}

impl Layout {
    /// Image bytes a slot holds.
    pub fn capacity(&self, page_bytes: u32) -> u32 {
        self.slot_pages.saturating_sub(1) * page_bytes
    }

    /// Region offset of byte `off` of slot `s`'s image.
    pub fn image_addr(&self, f: &impl Flash, s: usize, off: u32) -> Option<u32> {
        let first = *self.slot_page.get(s)?;
        Some((first + 1) * f.page_bytes() + off)
    }

    fn header_addr(&self, f: &impl Flash, s: usize) -> Option<u32> {
        Some(*self.slot_page.get(s)? * f.page_bytes())
    }

    /// The header of slot `s`, if well-formed (magic, seq and its complement).
    pub fn header(&self, f: &impl Flash, s: usize) -> Option<Header> {
        let a = self.header_addr(f, s)?;
        let mut w = [0u16; 8];
        for (k, x) in (0u32..).zip(w.iter_mut()) {
            *x = f.read(a + 2 * k).ok()?;
        }
        let [m, seq, inv, l0, l1, c0, c1, f0] = w;
        let f1 = f.read(a + 16).ok()?;
        let word = |lo: u16, hi: u16| u32::from(lo) | (u32::from(hi) << 16);
        (m == MAGIC && inv == !seq).then_some(Header {
            seq,
            len: word(l0, l1),
            crc: word(c0, c1),
            fingerprint: word(f0, f1),
        })
    }

    /// CRC-32 of the first `len` image bytes of slot `s`.
    pub fn image_crc(&self, f: &impl Flash, s: usize, len: u32) -> Option<u32> {
        let mut c = Crc32::default();
        let mut off = 0;
        while off < len {
            let h = f.read(self.image_addr(f, s, off)?).ok()?;
            let [b0, b1] = h.to_le_bytes();
            if off + 1 < len {
                c.update(&[b0, b1]);
            } else {
                c.update(&[b0]);
            }
            off += 2;
        }
        Some(c.finish())
    }

    /// The fingerprint word embedded in slot `s`'s image.
    pub fn image_fingerprint(&self, f: &impl Flash, s: usize) -> Option<u32> {
        let a = self.image_addr(f, s, self.fingerprint_offset)?;
        Some(u32::from(f.read(a).ok()?) | (u32::from(f.read(a + 2).ok()?) << 16))
    }

    /// Whether slot `s` holds a complete image: header well-formed, CRC-32 of the image
    /// as the header says, the image built for the header's robot fingerprint, and (when
    /// the bus's fingerprint is known, `expected`) for this robot.
    pub fn valid(&self, f: &impl Flash, s: usize, expected: Option<u32>) -> Option<Header> {
        let h = self.header(f, s)?;
        (expected.is_none_or(|e| e == h.fingerprint)
            && h.len <= self.capacity(f.page_bytes())
            && h.len >= self.fingerprint_offset + 4
            && self.image_crc(f, s, h.len) == Some(h.crc)
            && self.image_fingerprint(f, s) == Some(h.fingerprint))
        .then_some(h)
    }

    /// The slot to boot: the valid one with the newest sequence number (wrapping);
    /// `None`: stay in the bootloader, in update mode.
    pub fn boot_slot(&self, f: &impl Flash, expected: Option<u32>) -> Option<usize> {
        let a = self.valid(f, 0, expected);
        let b = self.valid(f, 1, expected);
        match (a, b) {
            (Some(a), Some(b)) => Some(if (b.seq.wrapping_sub(a.seq) as i16) > 0 {
                1
            } else {
                0
            }),
            (Some(_), None) => Some(0),
            (None, Some(_)) => Some(1),
            (None, None) => None,
        }
    }

    /// Erases slot `s` (header page first: from the first erase on, it is invalid).
    pub fn erase_slot(&self, f: &mut impl Flash, s: usize) -> Result<(), FlashError> {
        let first = *self.slot_page.get(s).ok_or(FlashError::OutOfRange)?;
        for p in first..first + self.slot_pages {
            f.erase(p)?;
        }
        Ok(())
    }

    /// Writes slot `s`'s header: the commit point of an update (the magic last).
    pub fn commit(&self, f: &mut impl Flash, s: usize, h: Header) -> Result<(), FlashError> {
        let a = self.header_addr(f, s).ok_or(FlashError::OutOfRange)?;
        let [l0, l1] = [h.len as u16, (h.len >> 16) as u16];
        let [c0, c1] = [h.crc as u16, (h.crc >> 16) as u16];
        let [f0, f1] = [h.fingerprint as u16, (h.fingerprint >> 16) as u16];
        for (k, w) in (1u32..).zip([h.seq, !h.seq, l0, l1, c0, c1, f0, f1]) {
            f.program(a + 2 * k, w)?;
        }
        f.program(a, MAGIC)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtcan_pubsub::flash::F103Flash;

    #[test]
    fn crc32_reference() {
        assert_eq!(Crc32::of(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn empty_flash_boots_nothing() {
        let l = Layout {
            slot_page: [0, 3],
            slot_pages: 3,
            fingerprint_offset: 0x10,
        };
        let f = F103Flash::<6>::new();
        assert_eq!(l.boot_slot(&f, None), None);
        assert_eq!(l.capacity(1024), 2048);
    }
}
