// robots/broken/unknown-node.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/unknown-node.toml");

fn main() {}
