// robots/broken/filter-banks-exhausted.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/filter-banks-exhausted.toml");

fn main() {}
