//! Persisted parameters in flash (docs/SERVICES.md §2.3): a log of (index, value)
//! records appended to the active page and compacted into the next page of the region
//! when full, so erases rotate over every page (wear levelling). Every record carries a
//! CRC-16; a page with a bad record is corrupt and the module falls back to defaults.
//!
//! Page layout (half-words): MAGIC, seq, !seq, ACTIVE (0x0000 once the page is complete),
//! then records of 4 half-words: index, value low, value high, CRC-16/CCITT of the six
//! bytes. The valid page with the newest seq (wrapping) is the active one. A compaction
//! writes the new page completely, ACTIVE last: a power cut at any step leaves either
//! the old page or the new one active, never neither. A record cut mid-write (the last
//! one, partly erased) is ignored: that set is lost, not the others.
use crate::flash::{Flash, FlashError};

const MAGIC: u16 = 0x5250; // "RP"
const ACTIVE: u16 = 0x0000;
const HEADER_BYTES: u32 = 8;
const RECORD_BYTES: u32 = 8;

/// CRC-16/CCITT-FALSE.
pub fn crc16(bytes: &[u8]) -> u16 {
    let mut crc: u16 = 0xFFFF;
    for &b in bytes {
        crc ^= u16::from(b) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ 0x1021
            } else {
                crc << 1
            };
        }
    }
    crc
}

fn record_crc(index: u16, bits: u32) -> u16 {
    let [i0, i1] = index.to_le_bytes();
    let [b0, b1, b2, b3] = bits.to_le_bytes();
    crc16(&[i0, i1, b0, b1, b2, b3])
}

/// What `open` found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Found {
    /// No valid page: defaults (first start, or every page erased).
    Empty,
    /// The active page and its records were good.
    Ok,
    /// The active page had a bad record: defaults; the next write starts a fresh page.
    Corrupt,
}

/// A parameter store over `flash` for `N` parameters.
pub struct ParamStore<F: Flash, const N: usize> {
    flash: F,
    /// Active page and its sequence number.
    active: Option<(u32, u16)>,
    /// Offset of the next free record in the active page.
    next: u32,
    /// Latest stored value per parameter (what a compaction copies).
    latest: [Option<u32>; N],
}

impl<F: Flash, const N: usize> ParamStore<F, N> {
    /// Opens the store: finds the active page and reads its records.
    pub fn open(flash: F) -> (Self, Found) {
        let mut s = ParamStore {
            flash,
            active: None,
            next: HEADER_BYTES,
            latest: [None; N],
        };
        let found = s.scan();
        (s, found)
    }

    /// The flash (tests inspect wear and inject power cuts).
    pub fn flash(&self) -> &F {
        &self.flash
    }

    /// The flash, mutable.
    pub fn flash_mut(&mut self) -> &mut F {
        &mut self.flash
    }

    /// Gives the flash back (a "reset": `open` it again).
    pub fn into_flash(self) -> F {
        self.flash
    }

    /// Stored values, `(index, bits)`, for `Params::load`.
    pub fn values(&self) -> impl Iterator<Item = (u16, u32)> + '_ {
        self.latest
            .iter()
            .enumerate()
            .filter_map(|(i, v)| Some((u16::try_from(i).ok()?, (*v)?)))
    }

    fn rd(&self, addr: u32) -> u16 {
        // An unreadable address reads as erased: treated as the end of the data.
        self.flash.read(addr).unwrap_or(0xFFFF)
    }

    fn page_seq(&self, page: u32) -> Option<u16> {
        let base = page * self.flash.page_bytes();
        let (m, seq, inv, act) = (
            self.rd(base),
            self.rd(base + 2),
            self.rd(base + 4),
            self.rd(base + 6),
        );
        (m == MAGIC && inv == !seq && act == ACTIVE).then_some(seq)
    }

    fn scan(&mut self) -> Found {
        let mut best: Option<(u32, u16)> = None;
        for p in 0..self.flash.pages() {
            if let Some(seq) = self.page_seq(p) {
                // Newest by wrapping comparison of 16-bit sequence numbers.
                let newer = best.is_none_or(|(_, b)| (seq.wrapping_sub(b) as i16) > 0);
                if newer {
                    best = Some((p, seq));
                }
            }
        }
        let Some((page, seq)) = best else {
            return Found::Empty;
        };
        self.active = Some((page, seq));
        let base = page * self.flash.page_bytes();
        let end = self.flash.page_bytes();
        let mut off = HEADER_BYTES;
        let mut latest = [None; N];
        while off + RECORD_BYTES <= end {
            let a = base + off;
            let w = [self.rd(a), self.rd(a + 2), self.rd(a + 4), self.rd(a + 6)];
            if w == [0xFFFF; 4] {
                // The first free slot; a slot cut before its first half-word looks
                // the same and is reused (nothing was programmed there).
                break;
            }
            let [index, lo, hi, crc] = w;
            let bits = u32::from(lo) | (u32::from(hi) << 16);
            if crc != record_crc(index, bits) {
                // Half-words are programmed in order, so a write cut short leaves an
                // erased tail (the CRC at least): skip that record, it was never
                // acknowledged; the slot stays used (never program over it).
                let torn = w.last() == Some(&0xFFFF)
                    && w.iter().skip_while(|&&h| h != 0xFFFF).all(|&h| h == 0xFFFF);
                if torn {
                    off += RECORD_BYTES;
                    continue;
                }
                self.latest = [None; N];
                // A fresh page on the next write.
                self.next = end;
                return Found::Corrupt;
            }
            if let Some(l) = latest.get_mut(usize::from(index)) {
                *l = Some(bits);
            }
            off += RECORD_BYTES;
        }
        self.next = off;
        self.latest = latest;
        Found::Ok
    }

    fn put(&mut self, addr: u32, index: u16, bits: u32) -> Result<(), FlashError> {
        let [l0, l1, h0, h1] = bits.to_le_bytes();
        self.flash.program(addr, index)?;
        self.flash.program(addr + 2, u16::from_le_bytes([l0, l1]))?;
        self.flash.program(addr + 4, u16::from_le_bytes([h0, h1]))?;
        self.flash.program(addr + 6, record_crc(index, bits))
    }

    /// Persists parameter `index` = `bits` (append, or compact into the next page).
    pub fn write(&mut self, index: u16, bits: u32) -> Result<(), FlashError> {
        if usize::from(index) >= N {
            return Err(FlashError::OutOfRange);
        }
        let page_bytes = self.flash.page_bytes();
        if let Some((page, _)) = self.active {
            if self.next + RECORD_BYTES <= page_bytes {
                let at = page * page_bytes + self.next;
                // Whatever happens, this slot is used: never program over a torn record.
                self.next += RECORD_BYTES;
                self.put(at, index, bits)?;
                if let Some(l) = self.latest.get_mut(usize::from(index)) {
                    *l = Some(bits);
                }
                return Ok(());
            }
        }
        self.compact(index, bits)
    }

    /// Writes the latest values plus the new one into the next page, then marks it
    /// active (the old page stays valid until then).
    fn compact(&mut self, index: u16, bits: u32) -> Result<(), FlashError> {
        let pages = self.flash.pages();
        // Two pages at least: the page being written is never the active one.
        if pages < 2 {
            return Err(FlashError::OutOfRange);
        }
        let (page, seq) = match self.active {
            Some((p, s)) => ((p + 1) % pages, s.wrapping_add(1)),
            None => (0, 1),
        };
        let page_bytes = self.flash.page_bytes();
        let base = page * page_bytes;
        self.flash.erase(page)?;
        self.flash.program(base, MAGIC)?;
        self.flash.program(base + 2, seq)?;
        self.flash.program(base + 4, !seq)?;
        let mut latest = self.latest;
        if let Some(l) = latest.get_mut(usize::from(index)) {
            *l = Some(bits);
        }
        let mut off = HEADER_BYTES;
        for (i, v) in latest.iter().enumerate() {
            let (Some(v), Ok(i)) = (v, u16::try_from(i)) else {
                continue;
            };
            if off + RECORD_BYTES > page_bytes {
                return Err(FlashError::OutOfRange);
            }
            self.put(base + off, i, *v)?;
            off += RECORD_BYTES;
        }
        self.flash.program(base + 6, ACTIVE)?;
        self.active = Some((page, seq));
        self.next = off;
        self.latest = latest;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flash::F103Flash;

    type Store = ParamStore<F103Flash<3>, 4>;

    fn reopen(s: Store) -> (Store, Found) {
        let mut f = s.into_flash();
        f.cut_after = None;
        Store::open(f)
    }

    #[test]
    fn one_page_region_is_refused() {
        let (mut s, _) = ParamStore::<F103Flash<1>, 2>::open(F103Flash::new());
        assert_eq!(s.write(0, 1), Err(FlashError::OutOfRange));
        assert_eq!(s.flash().ops, 0);
    }

    #[test]
    fn crc_reference() {
        // CRC-16/CCITT-FALSE check value.
        assert_eq!(crc16(b"123456789"), 0x29B1);
    }

    #[test]
    fn empty_then_values_survive_a_reset() {
        let (mut s, found) = Store::open(F103Flash::new());
        assert_eq!(found, Found::Empty);
        assert_eq!(s.values().count(), 0);
        s.write(1, 0xDEAD_BEEF).unwrap();
        s.write(1, 7).unwrap();
        s.write(3, 9).unwrap();
        assert_eq!(s.write(4, 0), Err(FlashError::OutOfRange));
        let (s, found) = reopen(s);
        assert_eq!(found, Found::Ok);
        assert_eq!(s.values().collect::<Vec<_>>(), [(1, 7), (3, 9)]);
        // Exact layout of page 0: header, then the first record.
        let f = s.flash();
        let w: Vec<u16> = (0..8).map(|k| f.read(k * 2).unwrap()).collect();
        assert_eq!(
            w,
            [
                MAGIC,
                1,
                !1,
                0,
                1,
                0xBEEF,
                0xDEAD,
                record_crc(1, 0xDEAD_BEEF)
            ]
        );
    }

    #[test]
    fn wear_levels_over_every_page() {
        let (mut s, _) = Store::open(F103Flash::new());
        // 127 records per page: 3000 writes compact about 23 times.
        for k in 0..3000u32 {
            s.write((k % 4) as u16, k).unwrap();
        }
        let e = s.flash().erases;
        let (lo, hi) = (e.iter().min().unwrap(), e.iter().max().unwrap());
        assert!(hi - lo <= 1, "erases spread evenly: {e:?}");
        assert!(*lo >= 7, "{e:?}");
        let (s, found) = reopen(s);
        assert_eq!(found, Found::Ok);
        assert_eq!(
            s.values().collect::<Vec<_>>(),
            [(0, 2996), (1, 2997), (2, 2998), (3, 2999)]
        );
    }

    #[test]
    fn corrupt_record_falls_back_to_defaults_and_recovers() {
        let (mut s, _) = Store::open(F103Flash::new());
        s.write(0, 1).unwrap();
        s.write(2, 5).unwrap();
        s.write(0, 3).unwrap();
        let mut f = s.into_flash();
        // Flip a bit in the middle record's value.
        f.corrupt(HEADER_BYTES + RECORD_BYTES + 2, 0x0010);
        let (mut s, found) = Store::open(f);
        assert_eq!(found, Found::Corrupt);
        assert_eq!(s.values().count(), 0, "defaults");
        // The next write starts a fresh page, readable again.
        s.write(1, 42).unwrap();
        let (s, found) = reopen(s);
        assert_eq!(found, Found::Ok);
        assert_eq!(s.values().collect::<Vec<_>>(), [(1, 42)]);
        // A corrupt header invalidates the page: the older page (page 0, seq 1) is the
        // newest valid one, and it is corrupt: defaults.
        let mut f = s.into_flash();
        f.corrupt(1024 + 2, 1);
        let (s, found) = Store::open(f);
        assert_eq!(found, Found::Corrupt);
        assert_eq!(s.values().count(), 0);
    }

    /// Power cut at every flash operation of a run of writes that includes compactions:
    /// after the reset the store opens, holds either the value before or after the
    /// write in flight for that parameter, and every earlier write.
    #[test]
    fn power_cut_at_every_step_keeps_a_consistent_store() {
        let script: Vec<(u16, u32)> = (0..300u32).map(|k| ((k % 3) as u16, k + 100)).collect();
        // Operations of the whole script without a cut.
        let (mut s, _) = Store::open(F103Flash::new());
        for &(i, v) in &script {
            s.write(i, v).unwrap();
        }
        let total = s.flash().ops;
        eprintln!("flash operations: {total}");
        assert!(total > 1200, "covers compactions: {total}");
        for cut in 0..total {
            let mut f = F103Flash::<3>::new();
            f.cut_after = Some(cut);
            let (mut s, _) = Store::open(f);
            let mut done = [None::<u32>; 4];
            let mut inflight = None;
            for &(i, v) in &script {
                match s.write(i, v) {
                    Ok(()) => done[usize::from(i)] = Some(v),
                    Err(e) => {
                        assert_eq!(e, FlashError::PowerCut);
                        inflight = Some((i, v));
                        break;
                    }
                }
            }
            let (s, found) = reopen(s);
            assert_ne!(found, Found::Corrupt, "cut {cut}");
            let got: Vec<(u16, u32)> = s.values().collect();
            for i in 0..4u16 {
                let have = got.iter().find(|g| g.0 == i).map(|g| g.1);
                let before = done[usize::from(i)];
                match inflight {
                    Some((j, v)) if j == i => {
                        assert!(have == before || have == Some(v), "cut {cut} param {i}")
                    }
                    _ => assert_eq!(have, before, "cut {cut} param {i}"),
                }
            }
        }
    }
}
