// robots/broken/unknown-type.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/unknown-type.toml");

fn main() {}
