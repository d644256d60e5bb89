//! Unsuffixed literals, so the generated code reads like hand-written code.
use proc_macro2::Literal;

/// Decimal unsuffixed integer.
pub fn int(n: impl Into<u128>) -> Literal {
    Literal::u128_unsuffixed(n.into())
}

/// `usize` as an unsuffixed integer.
pub fn usize(n: usize) -> Literal {
    Literal::u128_unsuffixed(n as u128)
}

/// Hex unsuffixed integer (IDs and masks), e.g. `0x0000_a000`.
pub fn hex(n: u64) -> Literal {
    let s = if n > 0xFFFF {
        format!("0x{:04x}_{:04x}", n >> 16, n & 0xFFFF)
    } else {
        format!("0x{n:04x}")
    };
    s.parse().unwrap_or_else(|_| Literal::u64_unsuffixed(n))
}
