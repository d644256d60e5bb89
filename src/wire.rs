//! Fixed-size little-endian field codec used by the generated message types.
//!
//! Generated `encode`/`decode` are one `put`/`take` per field, so the byte layout lives
//! here once (and is tested here) instead of being spelled out per type. Nothing panics:
//! a short output buffer is left partly unwritten, a short input decodes to `None`.

/// Writes fields in order into a byte buffer.
pub struct Writer<'a> {
    out: &'a mut [u8],
    pos: usize,
}

impl<'a> Writer<'a> {
    /// A writer at the start of `out`.
    pub fn new(out: &'a mut [u8]) -> Self {
        Writer { out, pos: 0 }
    }
    /// Appends `bytes` (dropped if they do not fit).
    pub fn put(&mut self, bytes: &[u8]) {
        let end = self.pos + bytes.len();
        if let Some(dst) = self.out.get_mut(self.pos..end) {
            dst.copy_from_slice(bytes);
        }
        self.pos = end;
    }
}

/// Reads fields in order from a byte buffer.
pub struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    /// A reader at the start of `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        Reader { bytes, pos: 0 }
    }
    /// The next `L` bytes, or `None` past the end.
    pub fn take<const L: usize>(&mut self) -> Option<[u8; L]> {
        let end = self.pos + L;
        let b = self.bytes.get(self.pos..end)?.try_into().ok()?;
        self.pos = end;
        Some(b)
    }
}

/// A field type of robot.toml: a primitive or a fixed-length array of one.
pub trait Field: Copy {
    /// All-zero value (arrays of any length have no `Default`).
    const ZERO: Self;
    /// Appends the little-endian encoding.
    fn put(&self, w: &mut Writer<'_>);
    /// Reads the value; `None` past the end or for an invalid `bool` byte.
    fn take(r: &mut Reader<'_>) -> Option<Self>;
}

macro_rules! le_field {
    ($($t:ty),*) => {$(
        impl Field for $t {
            const ZERO: Self = 0 as $t;
            fn put(&self, w: &mut Writer<'_>) {
                w.put(&self.to_le_bytes());
            }
            fn take(r: &mut Reader<'_>) -> Option<Self> {
                Some(<$t>::from_le_bytes(r.take()?))
            }
        }
    )*};
}
le_field!(u8, u16, u32, u64, i8, i16, i32, i64, f32, f64);

impl Field for bool {
    const ZERO: Self = false;
    fn put(&self, w: &mut Writer<'_>) {
        w.put(&[u8::from(*self)]);
    }
    fn take(r: &mut Reader<'_>) -> Option<Self> {
        match r.take::<1>()? {
            [0] => Some(false),
            [1] => Some(true),
            _ => None,
        }
    }
}

impl<T: Field, const N: usize> Field for [T; N] {
    const ZERO: Self = [T::ZERO; N];
    fn put(&self, w: &mut Writer<'_>) {
        for x in self {
            x.put(w);
        }
    }
    fn take(r: &mut Reader<'_>) -> Option<Self> {
        let mut a = Self::ZERO;
        for x in a.iter_mut() {
            *x = T::take(r)?;
        }
        Some(a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn little_endian_fields_and_arrays() {
        let mut buf = [0u8; 9];
        let mut w = Writer::new(&mut buf);
        0x1234u16.put(&mut w);
        [-1i16, 2].put(&mut w);
        true.put(&mut w);
        1.0f32.to_bits().put(&mut w);
        assert_eq!(buf, [0x34, 0x12, 0xFF, 0xFF, 0x02, 0x00, 0x01, 0x00, 0x00]);
        let mut r = Reader::new(&buf);
        assert_eq!(u16::take(&mut r), Some(0x1234));
        assert_eq!(<[i16; 2]>::take(&mut r), Some([-1, 2]));
        assert_eq!(bool::take(&mut r), Some(true));
        assert_eq!(u32::take(&mut r), None, "only 2 bytes left");
    }

    #[test]
    fn invalid_bool_and_short_buffers() {
        assert_eq!(bool::take(&mut Reader::new(&[2])), None);
        let mut short = [0u8; 1];
        let mut w = Writer::new(&mut short);
        0xABCDu16.put(&mut w);
        assert_eq!(short, [0], "does not fit: left unwritten, no panic");
    }
}
