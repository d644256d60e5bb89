//! The instructions of an image that the emulator must act on (WFI, `b .`, and the ones
//! that can unmask an interrupt), found once by scanning the image and looked up by address
//! from the single code hook.
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
    /// One entry per half-word from `base`: 0 none, else `Site as u8 + 1`.
    table: Vec<u8>,
}

const NONE: u8 = 0;

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
                if let Some(site) = classify(*hw, halves.get(i + 1).copied()) {
                    let addr = seg.addr + 2 * i as u32;
                    if let Some(slot) = table.get_mut(((addr - lo) / 2) as usize) {
                        *slot = code(site);
                    }
                }
            }
        }
        Sites { base: lo, table }
    }

    /// The site at instruction address `addr`.
    #[inline]
    pub fn at(&self, addr: u32) -> Option<Site> {
        let i = (addr.wrapping_sub(self.base) / 2) as usize;
        match self.table.get(i).copied().unwrap_or(NONE) {
            1 => Some(Site::Wfi),
            2 => Some(Site::Spin),
            3 => Some(Site::Unmask),
            _ => None,
        }
    }

    /// Number of sites (for the record: the hooks the old scheme registered).
    pub fn count(&self) -> usize {
        self.table.iter().filter(|&&c| c != NONE).count()
    }
}

#[cfg(test)]
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
    fn two_segments_and_an_msr_split_across_their_end() {
        // The MSR's second half-word is in no segment: not a site. A WFI in the second
        // segment is found at its own address.
        let s = Sites::scan(&[seg(0x0800_0000, &[0xF380]), seg(0x0800_0010, &[0xBF30])]);
        assert_eq!(s.at(0x0800_0000), None);
        assert_eq!(s.at(0x0800_0010), Some(Site::Wfi));
        assert_eq!(Sites::scan(&[]).at(0x0800_0000), None);
    }
}
