// robots/broken/bad-name.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/bad-name.toml");

fn main() {}
