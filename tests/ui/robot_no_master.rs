// robots/broken/no-master.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/no-master.toml");

fn main() {}
