// robots/broken/bad-value.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/bad-value.toml");

fn main() {}
