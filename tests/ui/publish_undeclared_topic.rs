// `kinematics` does not publish `encoder1` (its publisher is `motor_ctrl1`): no handle.
mod robot {
    rtcan::robot!("robot.toml");
}

fn main() {
    let _ = robot::motor1::nodes::kinematics::encoder1_pub();
    // Nor does it subscribe to `wheel_setpoints`, which it publishes.
    let _ = robot::motor1::nodes::kinematics::wheel_setpoints_sub();
}
