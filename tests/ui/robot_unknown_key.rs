// robots/broken/unknown-key.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/unknown-key.toml");

fn main() {}
