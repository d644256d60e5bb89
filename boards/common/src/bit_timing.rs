//! CAN bit timing: the computation lives in `rtcan_core::bit_timing` (no_std, shared
//! with `rtcan check`, which refuses a bit rate the board's CAN clock cannot reach);
//! this module re-exports it and adds `can_btr!`, its compile-time form.
pub use rtcan_core::bit_timing::*;

/// `can_btr!(clock_hz, bitrate)`: the `CAN_BTR` register value, computed at compile time.
/// `const BTR: u32 = can_btr!(36_000_000, 1_000_000);` is `0x001E_0001`;
/// `can_btr!(36_000_000, 700_000)` does not compile.
#[macro_export]
macro_rules! can_btr {
    ($clock_hz:expr, $bitrate:expr) => {
        const { $crate::bit_timing::btr_or_fail($clock_hz, $bitrate) }
    };
}

#[cfg(test)]
mod tests {
    #[test]
    fn can_btr_is_the_shared_computation() {
        assert_eq!(can_btr!(36_000_000, 1_000_000), 0x001E_0001);
        assert_eq!(can_btr!(36_000_000, 500_000), 0x0000_0008 | (5 << 16));
    }
}
