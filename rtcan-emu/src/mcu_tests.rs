//! The core's state across exception entry and return (ARMv7-M B1.5.6, B1.5.8), on a
//! hand-assembled image (encodings from `llvm-mc -triple=thumbv7m-none-eabi`).
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
use super::*;

/// A minimal ELF32 file: one PT_LOAD segment of `code` at `addr`, no sections.
fn elf(addr: u32, code: &[u8]) -> Vec<u8> {
    let mut f = vec![0u8; 84];
    f[..7].copy_from_slice(b"\x7fELF\x01\x01\x01");
    f[16..18].copy_from_slice(&2u16.to_le_bytes()); // ET_EXEC
    f[18..20].copy_from_slice(&40u16.to_le_bytes()); // EM_ARM
    f[28..32].copy_from_slice(&52u32.to_le_bytes()); // e_phoff
    f[40..42].copy_from_slice(&52u16.to_le_bytes()); // e_ehsize
    f[42..44].copy_from_slice(&32u16.to_le_bytes()); // e_phentsize
    f[44..46].copy_from_slice(&1u16.to_le_bytes()); // e_phnum
    f[46..48].copy_from_slice(&40u16.to_le_bytes()); // e_shentsize
    let ph = 52;
    f[ph..ph + 4].copy_from_slice(&1u32.to_le_bytes()); // PT_LOAD
    f[ph + 4..ph + 8].copy_from_slice(&84u32.to_le_bytes()); // p_offset
    f[ph + 8..ph + 12].copy_from_slice(&addr.to_le_bytes());
    f[ph + 12..ph + 16].copy_from_slice(&addr.to_le_bytes());
    f[ph + 16..ph + 20].copy_from_slice(&(code.len() as u32).to_le_bytes());
    f[ph + 20..ph + 24].copy_from_slice(&(code.len() as u32).to_le_bytes());
    f.extend_from_slice(code);
    f
}

fn put(img: &mut [u8], at: usize, bytes: &[u8]) {
    img[at..at + bytes.len()].copy_from_slice(bytes);
}

/// An interrupt taken between the two instructions of an `ITE` block that a 1 KiB page
/// boundary splits into two translation blocks (the run ends at the block boundary after
/// the store that pends it). The handler must start outside the IT block (EPSR.IT clear
/// on entry), and the return must restore it (the `movne` after it stays skipped). With
/// the IT state left set on entry, the handler's first instruction ran under `ne` and
/// was skipped (round 8: motor2 then ran into .rodata at 2.6 s).
#[test]
fn it_state_cleared_on_entry_and_restored_on_return() {
    let mut img = vec![0u8; 0x424];
    put(&mut img, 0x00, &0x2000_2000u32.to_le_bytes()); // initial SP
    put(&mut img, 0x04, &0x0800_03E1u32.to_le_bytes()); // reset
    for v in 2..16 {
        put(&mut img, 4 * v, &0x0800_0421u32.to_le_bytes()); // faults: b .
    }
    put(&mut img, 0x40, &0x0800_0411u32.to_le_bytes()); // IRQ0
    put(
        &mut img,
        0x3E0,
        &[
            0x4e, 0xf2, 0x00, 0x10, // movw r0, #0xE100
            0xce, 0xf2, 0x00, 0x00, // movt r0, #0xE000: NVIC_ISER0
            0x01, 0x21, // movs r1, #1
            0x01, 0x60, // str r1, [r0]: IRQ0 enabled
            0x4e, 0xf2, 0x00, 0x20, // movw r0, #0xE200
            0xce, 0xf2, 0x00, 0x00, // movt r0, #0xE000: NVIC_ISPR0
            0x00, 0x23, // movs r3, #0
            0x00, 0x24, // movs r4, #0
            0x00, 0x22, // movs r2, #0
            0x00, 0x2a, // 0x3FA cmp r2, #0: Z set
            0x0c, 0xbf, // 0x3FC ite eq
            0x01, 0x60, // 0x3FE streq r1, [r0]: IRQ0 pending
            0x01, 0x23, // 0x400 movne r3, #1: skipped (next page, next block)
            0xfe, 0xe7, // 0x402 b .
        ],
    );
    put(&mut img, 0x410, &[0x55, 0x24, 0x70, 0x47]); // movs r4, #0x55; bx lr
    put(&mut img, 0x420, &[0xfe, 0xe7]); // b .
    let mut m = Mcu::new("it", &elf(FLASH_BASE, &img), Timing::default()).unwrap();
    m.run_until(50_000_000).unwrap();
    assert_eq!(m.st.taken.get(&16), Some(&1), "IRQ0 taken once");
    assert_eq!(
        m.reg(REG_R0 + 4),
        0x55,
        "the handler's first instruction ran"
    );
    assert_eq!(
        m.reg(REG_R0 + 3),
        0,
        "movne skipped after the return (IT restored)"
    );
    assert_eq!(m.pc() & !1, 0x0800_0402, "asleep at `b .`");
    assert_eq!(
        m.st.taken.keys().copied().collect::<Vec<_>>(),
        [16],
        "no fault"
    );
}
