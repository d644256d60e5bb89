// robots/broken/wrong-type.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/wrong-type.toml");

fn main() {}
