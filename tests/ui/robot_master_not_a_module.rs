// robots/broken/master-not-a-module.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/master-not-a-module.toml");

fn main() {}
