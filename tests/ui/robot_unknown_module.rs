// robots/broken/unknown-module.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/unknown-module.toml");

fn main() {}
