//! Time. Everything the core is given or returns is a `Nanos`: nanoseconds on the
//! clock of the caller (the node-local clock). Bus time (laxity, deadlines, slot
//! boundaries) is derived from it by the slot clock (`clock.rs`), never kept in a
//! node-local tick (the 2014 code's laxity in per-board ticks was a bug).

/// Nanoseconds. `u64` wraps after 584 years.
pub type Nanos = u64;

/// Signed nanoseconds, for differences (laxity may be negative: deadline passed).
pub type SNanos = i64;
