// robots/broken/inadmissible-hrt.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/inadmissible-hrt.toml");

fn main() {}
