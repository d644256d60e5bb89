// robots/broken/srt-deadline-too-short.toml must not build; the error shows the robot.toml excerpt.
rtcan::robot!("robots/broken/srt-deadline-too-short.toml");

fn main() {}
