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

/// Hex unsuffixed integer (IDs and masks) in groups of 4 digits (4, 8 or 16 digits), e.g. `0x0000_0001_8000_03ff`.
pub fn hex(n: u64) -> Literal {
    let digits = if n > 0xFFFF_FFFF {
        16
    } else if n > 0xFFFF {
        8
    } else {
        4
    };
    let hex = format!("{n:0digits$x}");
    let groups: Vec<&str> = (0..digits / 4)
        .filter_map(|g| hex.get(g * 4..g * 4 + 4))
        .collect();
    let s = format!("0x{}", groups.join("_"));
    s.parse().unwrap_or_else(|_| Literal::u64_unsuffixed(n))
}

#[cfg(test)]
mod tests {
    #[test]
    fn hex_groups_of_four() {
        assert_eq!(super::hex(0x140).to_string(), "0x0140");
        assert_eq!(super::hex(0x1fff_8000).to_string(), "0x1fff_8000");
        assert_eq!(
            super::hex(0x1_8000_03ff).to_string(),
            "0x0000_0001_8000_03ff"
        );
    }
}
