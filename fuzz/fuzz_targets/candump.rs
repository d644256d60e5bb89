//! `candump`: see `rtcan_fuzz::candump` (the harness body, shared with the stable replay test).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rtcan_fuzz::candump::run(data));
