//! Acceptance filters: a list of extended-ID `(id, mask)` pairs, one 32-bit mask filter
//! bank each, checked against the chip's bank count when the constant is built.

/// Filter banks of the STM32F103 (non-connectivity line) bxCAN. stm32f1xx-hal declares
/// 28 for every part; the F103 has 14.
pub const STM32F103_FILTER_BANKS: usize = 14;

/// A checked list of `(id, mask)` pairs (29-bit extended identifiers; mask bit 1 = must
/// match). Build it with `filter_set!` so the checks run at compile time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FilterSet {
    list: &'static [(u32, u32)],
}

impl FilterSet {
    /// Checks `list` against `banks` filter banks. In a const context (`filter_set!`) a
    /// failed check is a compile-time error.
    #[allow(clippy::panic)] // evaluated at compile time through `filter_set!`
    pub const fn new(list: &'static [(u32, u32)], banks: usize) -> Self {
        if list.len() > banks {
            panic!("more acceptance filters than the CAN controller has filter banks");
        }
        let mut rest = list;
        while let [(id, mask), tail @ ..] = rest {
            if *id > 0x1FFF_FFFF || *mask > 0x1FFF_FFFF {
                panic!("acceptance filter id or mask wider than 29 bits");
            }
            rest = tail;
        }
        FilterSet { list }
    }
    /// The `(id, mask)` pairs, bank 0 first.
    pub const fn pairs(&self) -> &'static [(u32, u32)] {
        self.list
    }
    /// Number of banks used.
    pub const fn len(&self) -> usize {
        self.list.len()
    }
    /// True if no frame passes (no bank enabled).
    pub const fn is_empty(&self) -> bool {
        self.list.is_empty()
    }
}

/// `filter_set!(LIST)` for the STM32F103's 14 banks, or `filter_set!(LIST, banks)`.
#[macro_export]
macro_rules! filter_set {
    ($list:expr) => {
        $crate::filter_set!($list, $crate::filters::STM32F103_FILTER_BANKS)
    };
    ($list:expr, $banks:expr) => {
        const { $crate::filters::FilterSet::new($list, $banks) }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fourteen_banks_fit_and_keep_order() {
        const L: &[(u32, u32)] = &[(0x0000_0000, 0x1F80_0000), (0x0000_A000, 0x007F_FF80)];
        let s = filter_set!(L);
        assert_eq!(s.pairs(), L);
        assert_eq!(s.len(), 2);
        const FULL: [(u32, u32); 14] = [(1, 0x1FFF_FFFF); 14];
        assert_eq!(filter_set!(&FULL).len(), 14);
    }

    #[test]
    #[should_panic(expected = "more acceptance filters")]
    fn fifteen_filters_are_refused() {
        static TOO_MANY: [(u32, u32); 15] = [(1, 1); 15];
        let _ = FilterSet::new(&TOO_MANY, STM32F103_FILTER_BANKS);
    }

    #[test]
    #[should_panic(expected = "wider than 29 bits")]
    fn wide_ids_are_refused() {
        let _ = FilterSet::new(&[(0x2000_0000, 0)], 14);
    }
}
