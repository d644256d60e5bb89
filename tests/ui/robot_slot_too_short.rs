// robots/broken/slot-too-short.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/slot-too-short.toml");

fn main() {}
