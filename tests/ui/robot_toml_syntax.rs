// robots/broken/toml-syntax.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/toml-syntax.toml");

fn main() {}
