//! Which instruction of a translation block made a peripheral access.
//!
//! The emulator counts instructions per block (`mcu::on_block`): inside a block Unicorn
//! keeps no PC, so a register access alone does not say how many of the block's
//! instructions ran before it. Timed at the block's start, a transmit request written at
//! the end of a mailbox fill would be stamped ≈ 7 instructions (≈ 145 ns) early, and a
//! polling loop that rewrites a register would see it at the wrong time. So each access
//! is matched to an instruction of the block by decoding the block's loads and stores
//! (ARMv7-M A5.2–A5.3 encodings): the first one from where the last match left off whose
//! direction, size and immediate offset (the register's offset in its 1 KiB peripheral
//! block, as register-block code writes it) fit, else the first of the right direction.
//! Stack (SP-based) and literal (PC-based) accesses are never peripheral accesses and are
//! skipped. The access is then timed at that instruction: exact whenever the match is.

/// A load or store instruction as the locator sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemOp {
    pub write: bool,
    /// Bytes per access.
    pub size: u8,
    /// Immediate offset from the base register of the first access, when the encoding
    /// has one (register-offset forms: None).
    pub offset: Option<u32>,
    /// Accesses the instruction makes (LDRD/STRD 2, LDM/STM one per register).
    pub accesses: u8,
}

/// Length in bytes of the instruction starting with `hw1`, and what it accesses in memory
/// if it can touch a peripheral. `hw2` is the next half-word (for 32-bit encodings).
pub fn decode(hw1: u16, hw2: u16) -> (u32, Option<MemOp>) {
    if crate::sites::is_wide(hw1) {
        (4, decode32(hw1, hw2))
    } else {
        (2, decode16(hw1))
    }
}

fn op(write: bool, size: u8, offset: Option<u32>, accesses: u8) -> Option<MemOp> {
    Some(MemOp {
        write,
        size,
        offset,
        accesses,
    })
}

/// 16-bit encodings (A5.2.4 load/store single, A5.2 LDM/STM).
fn decode16(hw: u16) -> Option<MemOp> {
    let imm5 = u32::from((hw >> 6) & 0x1F);
    match hw >> 12 {
        // STR/STRH/STRB/LDRSB/LDR/LDRH/LDRB/LDRSH (register).
        0b0101 => {
            let opb = (hw >> 9) & 7;
            let size = match opb {
                0 | 4 => 4,
                1 | 5 | 7 => 2,
                _ => 1,
            };
            op(opb < 3, size, None, 1)
        }
        // STR/LDR (immediate, ×4) and STRB/LDRB (immediate).
        0b0110 => op(hw & 0x0800 == 0, 4, Some(imm5 * 4), 1),
        0b0111 => op(hw & 0x0800 == 0, 1, Some(imm5), 1),
        // STRH/LDRH (immediate, ×2).
        0b1000 => op(hw & 0x0800 == 0, 2, Some(imm5 * 2), 1),
        // STM/LDM (T1): base register, one word per listed register.
        0b1100 => {
            let n = (hw & 0xFF).count_ones() as u8;
            op(hw & 0x0800 == 0, 4, Some(0), n.max(1))
        }
        // 0b0100_1: LDR (literal); 0b1001: SP-relative; PUSH/POP: never a peripheral.
        _ => None,
    }
}

/// 32-bit encodings (A5.3.7–A5.3.10 load/store single, A5.3.5 LDRD/STRD and LDM/STM).
fn decode32(hw1: u16, hw2: u16) -> Option<MemOp> {
    let rn = hw1 & 0xF;
    if rn == 13 || rn == 15 {
        return None;
    }
    if hw1 & 0xFE00 == 0xF800 {
        let load = hw1 & 0x0010 != 0;
        let size = match (hw1 >> 5) & 3 {
            0 => 1,
            1 => 2,
            2 => 4,
            _ => return None,
        };
        // PLD/PLI (a load to PC): a hint, no access.
        if load && hw2 >> 12 == 0xF && size < 4 {
            return None;
        }
        let offset = if hw1 & 0x0080 != 0 {
            Some(u32::from(hw2 & 0xFFF))
        } else if hw2 & 0x0800 != 0 {
            // imm8 with P (pre-index), U (add): post-indexed accesses use the base as is.
            let imm8 = u32::from(hw2 & 0xFF);
            match (hw2 & 0x0400 != 0, hw2 & 0x0200 != 0) {
                (true, true) => Some(imm8),
                (true, false) => Some(imm8.wrapping_neg()),
                (false, _) => Some(0),
            }
        } else {
            None
        };
        return op(!load, size, offset, 1);
    }
    // LDRD/STRD (immediate): P or W set; with both clear the space holds LDREX/STREX/TBB.
    if hw1 & 0xFE40 == 0xE840 && hw1 & 0x0120 != 0 {
        let imm = u32::from(hw2 & 0xFF) * 4;
        let offset = match (hw1 & 0x0100 != 0, hw1 & 0x0080 != 0) {
            (true, true) => imm,
            (true, false) => imm.wrapping_neg(),
            (false, _) => 0,
        };
        return op(hw1 & 0x0010 == 0, 4, Some(offset), 2);
    }
    // STM/LDM (IA) and STMDB/LDMDB (T2).
    let n = (hw2 & 0xDFFF).count_ones() as u8;
    match hw1 & 0xFFD0 {
        0xE880 | 0xE890 => op(hw1 & 0x0010 == 0, 4, Some(0), n.max(1)),
        0xE900 | 0xE910 => op(hw1 & 0x0010 == 0, 4, None, n.max(1)),
        _ => None,
    }
}

/// Where in the current block the last access was matched (`State` holds one).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cursor {
    /// Instruction index of the last matched access: the access's time offset.
    pub pos: u32,
    /// Byte offset in the block and instruction index where the next search starts.
    next_off: u32,
    next_idx: u32,
    /// Further accesses of the instruction at `pos` (LDRD/STRD, LDM/STM).
    left: u8,
}

impl Cursor {
    /// Matches an access (`write`, `size` bytes at `addr`) to an instruction of the block
    /// whose half-words `hw(byte offset)` returns, `len` bytes long; moves `pos` there.
    /// With no load or store of the access's direction left, `pos` stays.
    pub fn locate(
        &mut self,
        write: bool,
        size: u32,
        addr: u32,
        len: u32,
        hw: impl Fn(u32) -> Option<u16>,
    ) {
        if self.left > 0 {
            self.left -= 1;
            return;
        }
        let (mut off, mut idx) = (self.next_off, self.next_idx);
        let mut first_dir: Option<(u32, u32, u32, MemOp)> = None;
        while off < len {
            let Some(h1) = hw(off) else { return };
            let (n, m) = decode(h1, hw(off + 2).unwrap_or(0));
            if let Some(m) = m.filter(|m| m.write == write) {
                let exact = u32::from(m.size) == size.min(4)
                    && m.offset.is_some_and(|o| o & 0x3FF == addr & 0x3FF);
                if exact {
                    first_dir = Some((idx, off, n, m));
                    break;
                }
                first_dir.get_or_insert((idx, off, n, m));
            }
            off += n;
            idx += 1;
        }
        if let Some((i, o, n, m)) = first_dir {
            self.pos = i;
            self.next_off = o + n;
            self.next_idx = i + 1;
            self.left = m.accesses.saturating_sub(1);
        }
    }
}

#[cfg(test)]
#[allow(clippy::expect_used, clippy::indexing_slicing)]
mod tests {
    use super::*;

    #[test]
    fn decodes_the_load_store_classes() {
        // str r1, [r2] ; ldrb r0, [r1, #3] ; strh r0, [r1, #6] ; ldr r0, [r1, r2]
        assert_eq!(decode(0x6011, 0), (2, op(true, 4, Some(0), 1)));
        assert_eq!(decode(0x78C8, 0), (2, op(false, 1, Some(3), 1)));
        assert_eq!(decode(0x80C8, 0), (2, op(true, 2, Some(6), 1)));
        assert_eq!(decode(0x5888, 0), (2, op(false, 4, None, 1)));
        // str r0, [sp, #8]; ldr r0, [pc, #16]; push {r4, lr}: never peripherals.
        assert_eq!(decode(0x9002, 0).1, None);
        assert_eq!(decode(0x4804, 0).1, None);
        assert_eq!(decode(0xB510, 0).1, None);
        // stm r1!, {r2, r3}
        assert_eq!(decode(0xC10C, 0), (2, op(true, 4, Some(0), 2)));
        // str.w r4, [r3, #516] (F8C3 4204); ldr.w r4, [r3, #540] (F8D3 421C)
        assert_eq!(decode(0xF8C3, 0x4204), (4, op(true, 4, Some(516), 1)));
        assert_eq!(decode(0xF8D3, 0x421C), (4, op(false, 4, Some(540), 1)));
        // ldr.w r5, [sp, #250]: stack.
        assert_eq!(decode(0xF8DD, 0x50FA).1, None);
        // strb.w r0, [r1, #-4] (imm8, P U=0) and ldrh r0, [r1], #2 (post-index).
        assert_eq!(
            decode(0xF801, 0x0C04).1,
            op(true, 1, Some(4u32.wrapping_neg()), 1)
        );
        assert_eq!(decode(0xF831, 0x0B02).1, op(false, 2, Some(0), 1));
        // strd r2, r3, [r1, #0x188] (E9C1 2362) and ldrex r0, [r1] (E851 0F00).
        assert_eq!(decode(0xE9C1, 0x2362).1, op(true, 4, Some(0x188), 2));
        assert_eq!(decode(0xE851, 0x0F00).1, None);
        // ldm.w r0, {r1, r2, r3} (E890 000E); a data-processing 32-bit op (orr.w).
        assert_eq!(decode(0xE890, 0x000E).1, op(false, 4, Some(0), 3));
        assert_eq!(decode(0xF041, 0x0140), (4, None));
    }

    /// The gateway's mailbox fill (boards bxCAN driver): RAM loads, then stores into
    /// the mailbox's TDLR/TDHR and TIR with TXRQ last.
    #[test]
    fn each_access_lands_on_its_instruction() {
        let code: [u16; 10] = [
            0x6848, // ldr r0, [r1, #4]       (RAM)
            0x688A, // ldr r2, [r1, #8]       (RAM)
            0xF8C3, 0x0188, // str.w r0, [r3, #0x188] TDLR
            0xF8C3, 0x218C, // str.w r2, [r3, #0x18C] TDHR
            0x2001, // movs r0, #1
            0xF8C3, 0x0180, // str.w r0, [r3, #0x180] TIR
            0x4770, // bx lr
        ];
        let hw = |off: u32| code.get((off / 2) as usize).copied();
        let len = 2 * code.len() as u32;
        let mut c = Cursor::default();
        c.locate(true, 4, 0x4000_6588, len, hw);
        assert_eq!(c.pos, 2, "TDLR store is the block's third instruction");
        c.locate(true, 4, 0x4000_658C, len, hw);
        assert_eq!(c.pos, 3);
        c.locate(true, 4, 0x4000_6580, len, hw);
        assert_eq!(
            c.pos, 5,
            "TXRQ at the sixth instruction, not the block's start"
        );
        // A further store with nothing left to match: stays.
        c.locate(true, 4, 0x4000_6580, len, hw);
        assert_eq!(c.pos, 5);
        // A read-modify-write: the load, then the store after it.
        let rmw: [u16; 4] = [0x6950, 0xF040, 0x0001, 0x6150]; // ldr r0,[r2,#20]; orr; str
        let hw = |off: u32| rmw.get((off / 2) as usize).copied();
        let mut c = Cursor::default();
        c.locate(false, 4, 0x4000_6414, 8, hw);
        assert_eq!(c.pos, 0);
        c.locate(true, 4, 0x4000_6414, 8, hw);
        assert_eq!(c.pos, 2);
    }

    #[test]
    fn strd_covers_two_accesses_and_offsets_pick_among_stores() {
        // str r4, [r5, #0] (RAM); strd r2, r3, [r1, #0x188]; the two mailbox words.
        let code: [u16; 3] = [0x602C, 0xE9C1, 0x2362];
        let hw = |off: u32| code.get((off / 2) as usize).copied();
        let mut c = Cursor::default();
        c.locate(true, 4, 0x4000_6588, 6, hw);
        assert_eq!(c.pos, 1, "the offset skips the RAM store");
        c.locate(true, 4, 0x4000_658C, 6, hw);
        assert_eq!(c.pos, 1, "second word of the same STRD");
        // Outside the block's half-words: no panic, no move.
        let mut c = Cursor::default();
        c.locate(false, 4, 0x4000_0000, 64, |_| None);
        assert_eq!(c.pos, 0);
    }
}
