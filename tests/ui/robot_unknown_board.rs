// robots/broken/unknown-board.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/unknown-board.toml");

fn main() {}
