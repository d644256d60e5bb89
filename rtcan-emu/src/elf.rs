//! The loadable segments and symbols of a 32-bit little-endian ELF (the firmware
//! images), enough to put an image into emulated flash and find its RTT block.

/// A PT_LOAD segment: bytes at their physical (load) address.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Segment {
    pub addr: u32,
    pub bytes: Vec<u8>,
}

/// Why an ELF file cannot be loaded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BadElf(pub &'static str);

fn u16_at(b: &[u8], o: usize) -> Result<u16, BadElf> {
    b.get(o..o + 2)
        .and_then(|s| s.try_into().ok())
        .map(u16::from_le_bytes)
        .ok_or(BadElf("truncated"))
}

fn u32_at(b: &[u8], o: usize) -> Result<u32, BadElf> {
    b.get(o..o + 4)
        .and_then(|s| s.try_into().ok())
        .map(u32::from_le_bytes)
        .ok_or(BadElf("truncated"))
}

/// PT_LOAD segments (file bytes at p_paddr; .data is loaded at its flash address, as a
/// programmer would, and copied to RAM by the image's own start-up code).
pub fn load_segments(b: &[u8]) -> Result<Vec<Segment>, BadElf> {
    if b.get(0..4) != Some(b"\x7fELF") || b.get(4) != Some(&1) || b.get(5) != Some(&1) {
        return Err(BadElf("not a 32-bit little-endian ELF file"));
    }
    let phoff = u32_at(b, 28)? as usize;
    let phentsize = usize::from(u16_at(b, 42)?);
    let phnum = usize::from(u16_at(b, 44)?);
    let mut out = Vec::new();
    for i in 0..phnum {
        let p = phoff + i * phentsize;
        if u32_at(b, p)? != 1 {
            continue;
        }
        let offset = u32_at(b, p + 4)? as usize;
        let paddr = u32_at(b, p + 12)?;
        let filesz = u32_at(b, p + 16)? as usize;
        if filesz == 0 {
            continue;
        }
        let bytes = b
            .get(offset..offset + filesz)
            .ok_or(BadElf("segment outside the file"))?;
        out.push(Segment {
            addr: paddr,
            bytes: bytes.to_vec(),
        });
    }
    Ok(out)
}

/// Address of symbol `name` in .symtab.
pub fn symbol(b: &[u8], name: &str) -> Result<Option<u32>, BadElf> {
    let shoff = u32_at(b, 32)? as usize;
    let shentsize = usize::from(u16_at(b, 46)?);
    let shnum = usize::from(u16_at(b, 48)?);
    for i in 0..shnum {
        let sh = shoff + i * shentsize;
        if u32_at(b, sh + 4)? != 2 {
            continue; // SHT_SYMTAB
        }
        let off = u32_at(b, sh + 16)? as usize;
        let size = u32_at(b, sh + 20)? as usize;
        let link = u32_at(b, sh + 24)? as usize;
        let strtab = u32_at(b, shoff + link * shentsize + 16)? as usize;
        for s in (off..off + size).step_by(16) {
            let n = strtab + u32_at(b, s)? as usize;
            let end = b.get(n..).and_then(|r| r.iter().position(|&c| c == 0));
            if let Some(e) = end {
                if b.get(n..n + e) == Some(name.as_bytes()) {
                    return Ok(Some(u32_at(b, s + 4)?));
                }
            }
        }
    }
    Ok(None)
}

/// The bytes of section `name` (e.g. ".debug_info"), if the file has it.
pub fn section<'a>(b: &'a [u8], name: &str) -> Result<Option<&'a [u8]>, BadElf> {
    let shoff = u32_at(b, 32)? as usize;
    let shentsize = usize::from(u16_at(b, 46)?);
    let shnum = usize::from(u16_at(b, 48)?);
    let shstrndx = usize::from(u16_at(b, 50)?);
    let names = u32_at(b, shoff + shstrndx * shentsize + 16)? as usize;
    for i in 0..shnum {
        let sh = shoff + i * shentsize;
        let n = names + u32_at(b, sh)? as usize;
        let end = b.get(n..).and_then(|r| r.iter().position(|&c| c == 0));
        if end.and_then(|e| b.get(n..n + e)) != Some(name.as_bytes()) {
            continue;
        }
        if u32_at(b, sh + 4)? == 8 {
            return Ok(Some(&[])); // SHT_NOBITS: no bytes in the file
        }
        let off = u32_at(b, sh + 16)? as usize;
        let size = u32_at(b, sh + 20)? as usize;
        return b
            .get(off..off + size)
            .map(Some)
            .ok_or(BadElf("section outside the file"));
    }
    Ok(None)
}
