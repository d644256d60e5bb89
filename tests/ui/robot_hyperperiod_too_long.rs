// robots/broken/hyperperiod-too-long.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/hyperperiod-too-long.toml");

fn main() {}
