// robots/broken/name-collision.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/name-collision.toml");

fn main() {}
