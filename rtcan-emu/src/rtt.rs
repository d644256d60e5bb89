//! defmt output of an emulated MCU: the image's RTT up-buffer 0 (SEGGER RTT control block
//! `_SEGGER_RTT` in emulated RAM, written by defmt-rtt) is drained like a debug probe
//! would, and the bytes are decoded with the image's own defmt table (`defmt-decoder`).
use crate::mcu::Mcu;
use defmt_decoder::{DecodeError, Table};

// Control block layout (SEGGER RTT): id[16], max up, max down, then per up buffer
// name ptr, buffer ptr, size, write offset, read offset, flags.
const UP0: u32 = 24;

/// Reads the new bytes of up-buffer 0 and marks them read (the firmware sees the space).
pub fn drain(mcu: &mut Mcu) -> Vec<u8> {
    let Some(cb) = mcu.rtt else {
        return Vec::new();
    };
    let word = |m: &Mcu, a: u32| {
        let b = m.read_mem(a, 4);
        u32::from_le_bytes([
            b.first().copied().unwrap_or(0),
            b.get(1).copied().unwrap_or(0),
            b.get(2).copied().unwrap_or(0),
            b.get(3).copied().unwrap_or(0),
        ])
    };
    let buf = word(mcu, cb + UP0 + 4);
    let size = word(mcu, cb + UP0 + 8);
    let wr = word(mcu, cb + UP0 + 12);
    let rd = word(mcu, cb + UP0 + 16);
    // Not set up yet (defmt-rtt initialises the block at its first log), or corrupt.
    if size == 0 || size > 64 * 1024 || wr >= size || rd >= size || wr == rd {
        return Vec::new();
    }
    let mut out = Vec::new();
    if wr > rd {
        out.extend(mcu.read_mem(buf + rd, (wr - rd) as usize));
    } else {
        out.extend(mcu.read_mem(buf + rd, (size - rd) as usize));
        out.extend(mcu.read_mem(buf, wr as usize));
    }
    mcu.write_mem(cb + UP0 + 16, &wr.to_le_bytes());
    out
}

/// Decodes defmt bytes with the table of `elf`: one line per log frame, "LEVEL message".
pub fn decode(elf: &[u8], bytes: &[u8]) -> Result<Vec<String>, String> {
    let table = Table::parse(elf)
        .map_err(|e| format!("defmt table: {e}"))?
        .ok_or("the image has no defmt table")?;
    let mut dec = table.new_stream_decoder();
    dec.received(bytes);
    let mut lines = Vec::new();
    // Each decode consumes input; the bound only guards against a decoder that would not.
    for _ in 0..=bytes.len() {
        match dec.decode() {
            Ok(frame) => {
                let level = frame
                    .level()
                    .map_or("PRINT".to_string(), |l| format!("{l:?}").to_uppercase());
                lines.push(format!("{level} {}", frame.display_message()));
            }
            Err(DecodeError::UnexpectedEof) => break,
            Err(DecodeError::Malformed) => lines.push("<malformed defmt frame>".to_string()),
        }
    }
    Ok(lines)
}
