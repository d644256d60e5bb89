// robots/broken/bus-overload.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/bus-overload.toml");

fn main() {}
