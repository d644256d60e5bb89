// robots/broken/class-mismatch.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/class-mismatch.toml");

fn main() {}
