//! `robot_toml`: see `rtcan_fuzz::robot_toml` (the harness body, shared with the stable replay test).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| rtcan_fuzz::robot_toml::run(data));
