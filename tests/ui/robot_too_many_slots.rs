// robots/broken/too-many-slots.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/too-many-slots.toml");

fn main() {}
