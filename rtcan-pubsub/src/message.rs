//! Typed messages and their fixed-size little-endian wire form.
//!
//! `rtcan-codegen` generates one struct per message type of robot.toml and implements
//! [`Message`] for it; the primitive impls here serve tests and simple topics.

/// The encoded bytes of one message: always `[u8; M::SIZE]`. An associated type
/// (rather than `[u8; Self::SIZE]`, which stable Rust cannot name generically) lets a
/// pool reserve the wire buffer of each block at compile time.
pub trait WireBuf: Copy + AsRef<[u8]> + AsMut<[u8]> + Send + 'static {
    /// All-zero buffer, for const initialisation of pools.
    const ZERO: Self;
}

impl<const L: usize> WireBuf for [u8; L] {
    const ZERO: Self = [0; L];
}

/// A message type: plain data with a fixed-size little-endian encoding.
pub trait Message: Copy + Send + 'static {
    /// Encoded size in bytes (the payload size of the topic on the wire).
    const SIZE: usize;
    /// `[u8; Self::SIZE]`.
    type Wire: WireBuf;
    /// Writes the `SIZE`-byte encoding into `out` (`out.len() >= SIZE`; shorter
    /// buffers are left partly unwritten, never a panic).
    fn encode(&self, out: &mut [u8]);
    /// Decodes `bytes`; `None` if the length is not `SIZE` or a field is invalid.
    fn decode(bytes: &[u8]) -> Option<Self>;
}

macro_rules! le_message {
    ($($t:ty),*) => {$(
        impl Message for $t {
            const SIZE: usize = core::mem::size_of::<$t>();
            type Wire = [u8; core::mem::size_of::<$t>()];
            fn encode(&self, out: &mut [u8]) {
                for (o, b) in out.iter_mut().zip(self.to_le_bytes()) {
                    *o = b;
                }
            }
            fn decode(bytes: &[u8]) -> Option<Self> {
                Some(<$t>::from_le_bytes(bytes.try_into().ok()?))
            }
        }
    )*};
}
le_message!(u8, u16, u32, u64, i8, i16, i32, i64, f32, f64);

impl Message for bool {
    const SIZE: usize = 1;
    type Wire = [u8; 1];
    fn encode(&self, out: &mut [u8]) {
        if let Some(o) = out.first_mut() {
            *o = u8::from(*self);
        }
    }
    fn decode(bytes: &[u8]) -> Option<Self> {
        match bytes {
            [0] => Some(false),
            [1] => Some(true),
            _ => None,
        }
    }
}

impl<const L: usize> Message for [u8; L] {
    const SIZE: usize = L;
    type Wire = [u8; L];
    fn encode(&self, out: &mut [u8]) {
        for (o, b) in out.iter_mut().zip(self) {
            *o = *b;
        }
    }
    fn decode(bytes: &[u8]) -> Option<Self> {
        bytes.try_into().ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitives_round_trip_little_endian() {
        let mut out = [0u8; 4];
        0x1234_5678u32.encode(&mut out);
        assert_eq!(out, [0x78, 0x56, 0x34, 0x12]);
        assert_eq!(u32::decode(&out), Some(0x1234_5678));
        assert_eq!(u32::decode(&out[..3]), None);
        let mut f = [0u8; 4];
        (-1.5f32).encode(&mut f);
        assert_eq!(f32::decode(&f), Some(-1.5));
    }

    #[test]
    fn bool_rejects_other_bytes() {
        assert_eq!(bool::decode(&[1]), Some(true));
        assert_eq!(bool::decode(&[2]), None);
        assert_eq!(bool::decode(&[]), None);
    }
}
