//! `engine_rx`: see `rtcan_fuzz::engine_rx` (the harness body, shared with the stable replay test).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rtcan_fuzz::engine_rx::run(data));
