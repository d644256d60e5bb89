//! The robot of the on-target tests and benchmarks, robots/qemu-test.toml (a master and
//! two slaves; the file shows its calendar), generated at compile time: message types,
//! per-module `TABLES`, `FILTERS`, engine sizes, topic indices and R2P topics. An
//! inadmissible change to the file fails this crate's build.
rtcan::robot!("../../robots/qemu-test.toml");
