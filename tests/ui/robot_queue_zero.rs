// robots/broken/queue-zero.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/queue-zero.toml");

fn main() {}
