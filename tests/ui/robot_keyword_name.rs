// robots/broken/keyword-name.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/keyword-name.toml");

fn main() {}
