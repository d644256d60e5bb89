// `encoder1` carries `Encoder`; publishing a `Twist` on it does not compile.
mod robot {
    rtcan::robot!("robot.toml");
}

fn main() {
    let cmd = robot::Twist { vx: 1.0, vy: 0.0, wz: 0.0 };
    let _ = robot::motor1::nodes::motor_ctrl1::encoder1_pub().send(cmd, 0);
}
