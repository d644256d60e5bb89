//! HRT admission and phase assignment (exact search) plus the paper's rule as a named
//! baseline. Runs at build time in rtcan-model; no_std with caller-provided scratch.
//! OWNER: scheduling helper. Signatures fixed.

/// One HRT message to place.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HrtRequest {
    /// Period in slots.
    pub period_slots: u32,
    /// Frames per message; they go in consecutive slots.
    pub fragments: u8,
}
