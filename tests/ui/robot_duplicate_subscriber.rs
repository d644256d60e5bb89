// robots/broken/duplicate-subscriber.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/duplicate-subscriber.toml");

fn main() {}
