// A topic pool above 32 blocks is refused at compile time, naming the topic.
rtcan::robot!("tests/ui/robots/pool-too-large.toml");

fn main() {}
