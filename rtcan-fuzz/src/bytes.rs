//! Reads fuzz input as a stream of small numbers; past the end every read is 0, so any
//! input (the empty one included) is a complete, valid program of the harness.

/// Cursor over the fuzz input.
pub struct Bytes<'a> {
    rest: &'a [u8],
}

impl<'a> Bytes<'a> {
    /// A cursor at the start of `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Bytes { rest: data }
    }
    /// True when the input is used up.
    pub fn is_empty(&self) -> bool {
        self.rest.is_empty()
    }
    /// Next byte (0 past the end).
    pub fn u8(&mut self) -> u8 {
        match self.rest.split_first() {
            Some((b, rest)) => {
                self.rest = rest;
                *b
            }
            None => 0,
        }
    }
    /// Next little-endian u16.
    pub fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.u8(), self.u8()])
    }
    /// Next little-endian u32.
    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }
    /// Next little-endian u64.
    pub fn u64(&mut self) -> u64 {
        u64::from(self.u32()) | u64::from(self.u32()) << 32
    }
    /// `n` bytes (zero-padded past the end), `n <= 8`.
    pub fn array8(&mut self, n: usize) -> [u8; 8] {
        let mut out = [0u8; 8];
        for b in out.iter_mut().take(n) {
            *b = self.u8();
        }
        out
    }
}
