// robots/broken/missing-key.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/missing-key.toml");

fn main() {}
