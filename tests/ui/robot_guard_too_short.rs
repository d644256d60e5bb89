// robots/broken/guard-too-short.toml must not build: the build runs the same timing check
// as `rtcan check` (slot timer latency + clock error against the guard).
rtcan::robot!("robots/broken/guard-too-short.toml");

fn main() {}
