// robots/broken/period-not-representable.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/period-not-representable.toml");

fn main() {}
