// robots/broken/several-errors.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/several-errors.toml");

fn main() {}
