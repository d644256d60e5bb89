// robots/broken/unknown-field-type.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/unknown-field-type.toml");

fn main() {}
