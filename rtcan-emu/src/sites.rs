//! The instructions of an image that the emulator must act on (WFI, `b .`, and the ones
//! that can unmask an interrupt), and where each 32-bit Thumb-2 encoding starts, found
//! once by scanning the image and looked up by address from the single block hook: a
//! translation block's instruction count and its first and last sites (`Sites::block`).
//!
//! Why one hook with a table rather than one Unicorn hook per site: Unicorn 2 calls a lone
//! UC_HOOK_CODE hook inline from the translated code, but with two or more it calls a
//! generic helper for every instruction that walks the whole hook list and checks each
//! hook's bounds. With the 65–89 site hooks of a Triskar2 image that walk, not the
//! instruction count, was the emulator's cost (measured on Unicorn 2.0.1: 2.6 ns per
//! instruction with one hook, 10 ns with two, 227 ns with 101).
use crate::elf::Segment;

/// What the emulator does at an instruction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Site {
    /// `WFI` (0xBF30): sleep until the next event.
    Wfi,
    /// `b .` (0xE7FE): RTIC's idle without an idle task; sleeps like WFI.
    Spin,
    /// `CPSIE i` (0xB662) or `MSR PRIMASK/BASEPRI, Rn` (0xF38n 0x8810/0x8811; ARMv7-M
    /// A7.7.83, B5.2.3): RTIC's lock release and critical-section exit.
    Unmask,
}

/// Site of each half-word of the scanned range.
#[derive(Clone, Debug, Default)]
pub struct Sites {
    /// First address of `table`.
    base: u32,
    /// One entry per half-word from `base`: bits 0..2 the site (0 none, else
    /// `code(site)`), bit 2 (`WIDE`) set when the half-word, read as the first one of an
    /// instruction, starts a 32-bit encoding.
    table: Vec<u8>,
    /// `Sites::block`'s answers by the block's first half-word, packed (`pack`): 0 not
    /// yet asked. Unicorn translates a block once and runs it many times, so the walk is
    /// done once per block, not at every execution.
    blocks: Vec<u32>,
    /// The image's half-words from `base` (0 where no segment), for `access::Cursor`.
    hws: Vec<u16>,
}

const NONE: u8 = 0;
const SITE: u8 = 3;
const WIDE: u8 = 4;

/// A translation block as `Sites::block` reads it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Block {
    /// Instructions in the block.
    pub n: u32,
    /// The site of its first instruction.
    pub first: Option<Site>,
    /// The site of its last instruction.
    pub last: Option<Site>,
}

/// Whether half-word `hw` starts a 32-bit Thumb-2 encoding: its top five bits are
/// 0b11101, 0b11110 or 0b11111 (ARMv7-M A5.1).
pub fn is_wide(hw: u16) -> bool {
    hw >> 11 >= 0b11101
}

fn code(s: Site) -> u8 {
    match s {
        Site::Wfi => 1,
        Site::Spin => 2,
        Site::Unmask => 3,
    }
}

/// The site an instruction starting with half-words `hw`, `next` is, if any.
fn classify(hw: [u8; 2], next: Option<[u8; 2]>) -> Option<Site> {
    match (hw, next) {
        ([0x30, 0xBF], _) => Some(Site::Wfi),
        ([0xFE, 0xE7], _) => Some(Site::Spin),
        ([0x62, 0xB6], _) => Some(Site::Unmask),
        ([n, 0xF3], Some([0x10 | 0x11, 0x88])) if n & 0xF0 == 0x80 => Some(Site::Unmask),
        _ => None,
    }
}

/// A block's answer in 32 bits: size in bytes (bits 16..32), instruction count (4..16),
/// last site (2..4), first site (0..2). None if it does not fit (a block that large is
/// walked each time); never 0, since a block has an instruction.
fn pack(b: Block, size: u32) -> Option<u32> {
    let code = |s: Option<Site>| s.map_or(0, |s| u32::from(code(s)));
    (size < 1 << 16 && b.n < 1 << 12 && b.n > 0)
        .then(|| size << 16 | b.n << 4 | code(b.last) << 2 | code(b.first))
}

fn unpack(p: u32) -> Block {
    Block {
        n: (p >> 4) & 0xFFF,
        first: site((p & 3) as u8),
        last: site(((p >> 2) & 3) as u8),
    }
}

fn site(c: u8) -> Option<Site> {
    match c & SITE {
        1 => Some(Site::Wfi),
        2 => Some(Site::Spin),
        3 => Some(Site::Unmask),
        _ => None,
    }
}

impl Sites {
    /// Scans every half-word of `segments` (code and data alike: a site found in data
    /// never executes, so it costs nothing). The table spans the lowest to the highest
    /// segment address; images are contiguous in flash, so it is about the image's size.
    pub fn scan(segments: &[Segment]) -> Sites {
        let lo = segments.iter().map(|s| s.addr & !1).min().unwrap_or(0);
        let hi = segments
            .iter()
            .map(|s| s.addr.saturating_add(s.bytes.len() as u32))
            .max()
            .unwrap_or(0);
        let len = (hi.saturating_sub(lo) as usize).div_ceil(2);
        let mut table = vec![NONE; len];
        let mut hws = vec![0u16; len];
        for seg in segments {
            let halves: Vec<[u8; 2]> = seg
                .bytes
                .chunks_exact(2)
                .map(|c| {
                    [
                        c.first().copied().unwrap_or(0),
                        c.get(1).copied().unwrap_or(0),
                    ]
                })
                .collect();
            for (i, hw) in halves.iter().enumerate() {
                let addr = seg.addr + 2 * i as u32;
                let Some(slot) = table.get_mut(((addr - lo) / 2) as usize) else {
                    continue;
                };
                if let Some(site) = classify(*hw, halves.get(i + 1).copied()) {
                    *slot = code(site);
                }
                if let Some(h) = hws.get_mut(((addr - lo) / 2) as usize) {
                    *h = u16::from_le_bytes(*hw);
                }
                if is_wide(u16::from_le_bytes(*hw)) {
                    *slot |= WIDE;
                }
            }
        }
        let blocks = vec![0; table.len()];
        Sites {
            base: lo,
            table,
            blocks,
            hws,
        }
    }

    /// The site at instruction address `addr`.
    #[inline]
    pub fn at(&self, addr: u32) -> Option<Site> {
        let i = (addr.wrapping_sub(self.base) / 2) as usize;
        site(self.table.get(i).copied().unwrap_or(NONE))
    }

    /// The translation block of `size` bytes at `addr` (Unicorn's block hook): its
    /// instruction count, decoded from its first instruction on (a block starts on an
    /// instruction and holds only instructions, so the walk never lands in a literal
    /// pool), and the sites of its first and last instructions. None when the block is
    /// not wholly in the scanned image.
    #[inline]
    pub fn block(&mut self, addr: u32, size: u32) -> Option<Block> {
        let start = (addr.wrapping_sub(self.base) / 2) as usize;
        let cached = self.blocks.get(start).copied().unwrap_or(0);
        if cached != 0 && cached >> 16 == size {
            return Some(unpack(cached));
        }
        let b = self.walk(start, size)?;
        if let (Some(slot), Some(packed)) = (self.blocks.get_mut(start), pack(b, size)) {
            *slot = packed;
        }
        Some(b)
    }

    fn walk(&self, start: usize, size: u32) -> Option<Block> {
        let end = start.checked_add((size as usize).div_ceil(2))?;
        let span = self.table.get(start..end)?;
        let (mut i, mut n, mut last) = (0, 0, NONE);
        while let Some(&c) = span.get(i) {
            n += 1;
            last = c;
            i += if c & WIDE != 0 { 2 } else { 1 };
        }
        Some(Block {
            n,
            first: site(span.first().copied().unwrap_or(NONE)),
            last: site(last),
        })
    }

    /// The image's half-word at `addr`, if in the scanned range.
    #[inline]
    pub fn halfword(&self, addr: u32) -> Option<u16> {
        self.hws
            .get((addr.wrapping_sub(self.base) / 2) as usize)
            .copied()
    }

    /// Number of sites (for the record: the hooks the old scheme registered).
    pub fn count(&self) -> usize {
        self.table.iter().filter(|&&c| c & SITE != NONE).count()
    }
}

#[cfg(test)]
#[allow(clippy::expect_used, clippy::indexing_slicing)]
mod tests {
    use super::*;

    fn seg(addr: u32, hws: &[u16]) -> Segment {
        Segment {
            addr,
            bytes: hws.iter().flat_map(|h| h.to_le_bytes()).collect(),
        }
    }

    #[test]
    fn finds_each_kind_at_its_address_and_nothing_else() {
        // nop; wfi; b .; cpsie i; msr basepri, r0 (0xF380 0x8811); msr primask, r1
        // (0xF381 0x8810); msr control, r0 (0xF380 0x8814: not an unmask); nop
        let s = Sites::scan(&[seg(
            0x0800_0100,
            &[
                0xBF00, 0xBF30, 0xE7FE, 0xB662, 0xF380, 0x8811, 0xF381, 0x8810, 0xF380, 0x8814,
                0xBF00,
            ],
        )]);
        assert_eq!(s.at(0x0800_0100), None);
        assert_eq!(s.at(0x0800_0102), Some(Site::Wfi));
        assert_eq!(s.at(0x0800_0104), Some(Site::Spin));
        assert_eq!(s.at(0x0800_0106), Some(Site::Unmask));
        assert_eq!(s.at(0x0800_0108), Some(Site::Unmask));
        assert_eq!(s.at(0x0800_010A), None);
        assert_eq!(s.at(0x0800_010C), Some(Site::Unmask));
        assert_eq!(s.at(0x0800_0110), None, "MSR CONTROL does not unmask");
        assert_eq!(s.count(), 5);
        // Outside the image (below, above, far away): no site, no panic.
        assert_eq!(s.at(0x0800_00FE), None);
        assert_eq!(s.at(0x0800_0116), None);
        assert_eq!(s.at(0xFFFF_FFFE), None);
        assert_eq!(s.at(0), None);
    }

    #[test]
    fn counts_the_instructions_of_a_block_wide_and_narrow() {
        // movs r0, #1; ldr.w r1, [r2, #4] (0xF8D2 0x1004); adds r0, r0, r1;
        // msr basepri, r0 (0xF380 0x8811): 4 instructions in 12 bytes, the last an unmask.
        let mut s = Sites::scan(&[seg(
            0x0800_0200,
            &[
                0x2001, 0xF8D2, 0x1004, 0x1840, 0xF380, 0x8811, 0xBF30, 0xE7FE,
            ],
        )]);
        let b0 = s.block(0x0800_0200, 12).expect("in the image");
        assert_eq!((b0.n, b0.first, b0.last), (4, None, Some(Site::Unmask)));
        // From the ldr.w: 3 instructions; the 0x1004 half-word is not an instruction start.
        assert_eq!(s.block(0x0800_0202, 10).map(|b| b.n), Some(3));
        // A one-instruction block of each site.
        let wfi = s.block(0x0800_020C, 2).expect("wfi");
        assert_eq!(
            (wfi.n, wfi.first, wfi.last),
            (1, Some(Site::Wfi), Some(Site::Wfi))
        );
        assert_eq!(
            s.block(0x0800_020E, 2).and_then(|b| b.first),
            Some(Site::Spin)
        );
        // From 0x8811 (read as a 16-bit instruction: the walk trusts the block's start),
        // then the WFI, which ends the block.
        let b = s.block(0x0800_020A, 4).expect("in the image");
        assert_eq!((b.n, b.last), (2, Some(Site::Wfi)));
        // Partly or wholly outside the image: no answer, no panic.
        assert_eq!(s.block(0x0800_020E, 4), None);
        assert_eq!(s.block(0x0800_01FE, 4), None);
        assert_eq!(s.block(0xFFFF_FFFE, 0xFFFF_FFFF), None);
        // Asked again (from the cache), the same answers; the same start with another
        // size is walked anew.
        assert_eq!(s.block(0x0800_0200, 12), Some(b0));
        assert_eq!(
            s.block(0x0800_0200, 6).map(|b| (b.n, b.last)),
            Some((2, None))
        );
        assert_eq!(s.block(0x0800_0200, 12), Some(b0));
    }

    #[test]
    fn wide_prefixes_are_the_three_of_the_architecture() {
        assert!(!is_wide(0xE7FE), "0b11100: unconditional branch, 16-bit");
        assert!(is_wide(0xE800) && is_wide(0xF000) && is_wide(0xF800));
        assert!(!is_wide(0xBF30) && !is_wide(0x2001));
    }

    #[test]
    fn two_segments_and_an_msr_split_across_their_end() {
        // The MSR's second half-word is in no segment: not a site. A WFI in the second
        // segment is found at its own address.
        let s = Sites::scan(&[seg(0x0800_0000, &[0xF380]), seg(0x0800_0010, &[0xBF30])]);
        assert_eq!(s.at(0x0800_0000), None);
        assert_eq!(s.at(0x0800_0010), Some(Site::Wfi));
        assert_eq!(Sites::scan(&[]).at(0x0800_0000), None);
    }
}
