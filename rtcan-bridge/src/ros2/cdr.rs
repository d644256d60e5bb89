//! CDR as rmw_zenoh puts it on the wire (Fast-CDR, plain XCDR1 little-endian): a 4-byte
//! encapsulation header `00 01 00 00` (CDR_LE, options 0), then the fields in order,
//! each primitive aligned to its own size counted from the end of the header; strings
//! are a u32 length including the terminating NUL, the bytes and the NUL; sequences a
//! u32 count and the elements; fixed arrays the elements only.

/// The encapsulation header of little-endian plain CDR.
pub const HEADER_LE: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// A CDR writer.
#[derive(Clone, Debug)]
pub struct Writer {
    buf: Vec<u8>,
}

impl Default for Writer {
    fn default() -> Self {
        Self::new()
    }
}

impl Writer {
    /// A message with its encapsulation header.
    pub fn new() -> Self {
        Writer {
            buf: HEADER_LE.to_vec(),
        }
    }
    fn align(&mut self, n: usize) {
        while !(self.buf.len() - HEADER_LE.len()).is_multiple_of(n) {
            self.buf.push(0);
        }
    }
    /// `uint8` / `byte`.
    pub fn u8(&mut self, v: u8) -> &mut Self {
        self.buf.push(v);
        self
    }
    /// `bool` (one byte, 0 or 1).
    pub fn bool(&mut self, v: bool) -> &mut Self {
        self.u8(u8::from(v))
    }
    /// `int32`.
    pub fn i32(&mut self, v: i32) -> &mut Self {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }
    /// `uint32`.
    pub fn u32(&mut self, v: u32) -> &mut Self {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }
    /// `float32`.
    pub fn f32(&mut self, v: f32) -> &mut Self {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }
    /// `float64`.
    pub fn f64(&mut self, v: f64) -> &mut Self {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }
    /// `string` (u32 length with the NUL, bytes, NUL).
    pub fn string(&mut self, s: &str) -> &mut Self {
        self.u32(u32::try_from(s.len() + 1).unwrap_or(u32::MAX));
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
        self
    }
    /// The u32 element count of a sequence.
    pub fn seq_len(&mut self, n: usize) -> &mut Self {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX))
    }
    /// The serialized message.
    pub fn finish(&self) -> Vec<u8> {
        self.buf.clone()
    }
}

/// A CDR reader over one serialized message (header included).
#[derive(Clone, Debug)]
pub struct Reader<'a> {
    buf: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    /// Checks the header: only little-endian plain CDR is read.
    pub fn new(buf: &'a [u8]) -> Result<Self, String> {
        match buf.get(..4) {
            Some(h) if h == HEADER_LE => Ok(Reader { buf, at: 4 }),
            Some(h) => Err(format!(
                "CDR encapsulation {}: only 00 01 00 00 (little-endian plain CDR) is read",
                h.iter()
                    .map(|b| format!("{b:02x}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            )),
            None => Err(format!("{} bytes: shorter than the CDR header", buf.len())),
        }
    }
    fn take<const N: usize>(&mut self, align: usize) -> Result<[u8; N], String> {
        while !(self.at - HEADER_LE.len()).is_multiple_of(align) {
            self.at += 1;
        }
        let b = self
            .buf
            .get(self.at..self.at + N)
            .ok_or_else(|| format!("message ends at byte {}", self.buf.len()))?;
        self.at += N;
        let mut out = [0u8; N];
        out.copy_from_slice(b);
        Ok(out)
    }
    /// `float64`.
    pub fn f64(&mut self) -> Result<f64, String> {
        self.take::<8>(8).map(f64::from_le_bytes)
    }
    /// Bytes left after what was read (a longer message is not the type).
    pub fn rest(&self) -> usize {
        self.buf.len().saturating_sub(self.at)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alignment_counts_from_the_end_of_the_header() {
        let mut w = Writer::new();
        w.u8(7).f64(1.0).u8(1).u32(2).string("ab").f32(0.5);
        assert_eq!(
            w.finish(),
            [
                0, 1, 0, 0, // header
                7, 0, 0, 0, 0, 0, 0, 0, // u8, padded to 8
                0, 0, 0, 0, 0, 0, 0xF0, 0x3F, // 1.0
                1, 0, 0, 0, // u8, padded to 4
                2, 0, 0, 0, // u32
                3, 0, 0, 0, b'a', b'b', 0, // "ab" with its NUL
                0, // pad to 4
                0, 0, 0, 0x3F, // 0.5f32
            ]
        );
    }

    #[test]
    fn the_reader_refuses_other_encapsulations_and_short_messages() {
        assert!(Reader::new(&[0, 0, 0, 0, 1])
            .unwrap_err()
            .contains("00 00 00 00"));
        assert!(Reader::new(&[0, 1]).is_err());
        let mut r = Reader::new(&[0, 1, 0, 0, 1, 2, 3]).unwrap();
        assert!(r.f64().unwrap_err().contains("ends at byte 7"));
    }
}
