// robots/broken/hrt-over-capacity.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/hrt-over-capacity.toml");

fn main() {}
