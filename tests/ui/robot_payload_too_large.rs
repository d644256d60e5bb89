// robots/broken/payload-too-large.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/payload-too-large.toml");

fn main() {}
