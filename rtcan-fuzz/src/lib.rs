//! Fuzz harnesses of rtcan, shared by the cargo-fuzz targets in `fuzz/` (nightly,
//! libFuzzer) and the stable test `tests/fuzz_corpora.rs`, which replays every committed
//! corpus file and crash artifact through the same functions (README "Fuzzing").
//!
//! Each harness takes arbitrary bytes and panics (an `assert!`) only when it finds a
//! bug: a panic or hang inside the code under test, a diagnostic span outside the input,
//! or (`engine_rx`) a delivery or counter of the engine that the independent protocol
//! model of `oracle.rs` does not predict.
// Harness code, not product code: a failed `assert!`/`panic!` is how a harness reports a
// finding to libFuzzer and to the replay test.
#![allow(clippy::expect_used, clippy::panic)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::indexing_slicing))]

pub mod bytes;
pub mod candump;
pub mod engine_rx;
pub mod oracle;
pub mod robot_toml;

/// A harness: one fuzz input in, a panic on a finding.
pub type Harness = fn(&[u8]);

/// The fuzz targets by name (directory names under `fuzz/corpus/` and `fuzz/artifacts/`).
pub const TARGETS: [(&str, Harness); 3] = [
    ("robot_toml", robot_toml::run),
    ("engine_rx", engine_rx::run),
    ("candump", candump::run),
];
