// robots/broken/bitrate-unreachable.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/bitrate-unreachable.toml");

fn main() {}
