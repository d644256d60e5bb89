// robots/broken/duplicate-name.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/duplicate-name.toml");

fn main() {}
