// `encoder2` belongs to motor2: motor1's image has neither its topic nor a handle for it.
mod robot {
    rtcan::robot!("robot.toml");
}

fn main() {
    let _ = robot::motor1::nodes::motor_ctrl1::encoder2_pub();
    let _ = robot::motor1::topics::ENCODER2.publisher();
    // A node of another module is not in motor1's image either.
    let _ = robot::motor1::nodes::odometry::encoder1_sub();
}
