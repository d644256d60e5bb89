//! CAN acceptance filters of a generated module, as 29-bit extended identifiers (the
//! driver shifts them into the bxCAN register layout).

/// One bxCAN filter bank at 32-bit scale.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterBank {
    /// Passes identifiers with `raw & mask == id & mask`.
    Mask {
        /// Identifier bits to compare.
        id: u32,
        /// Bits that must match (1 = compare).
        mask: u32,
    },
    /// Passes exactly these two identifiers (list mode).
    List {
        /// The identifiers.
        ids: [u32; 2],
    },
}

impl FilterBank {
    /// Whether this bank passes the 29-bit identifier `raw`.
    pub const fn passes(&self, raw: u32) -> bool {
        match *self {
            FilterBank::Mask { id, mask } => raw & mask == id & mask,
            FilterBank::List { ids: [a, b] } => raw == a || raw == b,
        }
    }
}

/// Whether any `(id, mask)` pair passes `raw` (the flat form of a module's `FILTERS`).
pub fn filters_pass(filters: &[(u32, u32)], raw: u32) -> bool {
    filters.iter().any(|&(id, mask)| raw & mask == id & mask)
}
