//! The emulated robot with the simulator's plants: the six release images drive
//! Triskar2 toward a wall and the obstacle node stops it short, as the simulator's
//! `rtcan-sim/tests/triskar2.rs` asserts; the gateway's host link (USART1 + DMA1) in
//! both directions.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
use rtcan_emu::mcu::{Mcu, Timing};
use rtcan_emu::robot::{EmuRobot, HostScript, MODULES};
use std::path::PathBuf;

fn image(name: &str) -> Vec<u8> {
    let dir = std::env::var_os("RTCAN_EMU_IMAGES")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../examples/triskar2/target/thumbv7m-none-eabi/release")
        });
    let p = dir.join(name);
    std::fs::read(&p).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (build the images first: cd examples/triskar2 && cargo build --release)",
            p.display()
        )
    })
}

fn plan() -> rtcan_model::Plan {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robot.toml");
    rtcan_model::Robot::load(&path).unwrap_or_else(|d| panic!("{}", d.render()))
}

fn robot(script: HostScript) -> EmuRobot {
    let mcus = MODULES
        .iter()
        .map(|n| Mcu::new(n, &image(n), Timing::default()).unwrap())
        .collect();
    EmuRobot::new(&plan(), mcus, 1.5, 1, script).unwrap()
}

const MS: u64 = 1_000_000;

#[test]
fn emulated_robot_drives_to_the_wall_and_stops_short() {
    let mut r = robot(HostScript::default());
    r.run_until(10_000 * MS).unwrap();
    for s in r.physics.path.clone().into_vec().iter().step_by(10) {
        eprintln!(
            "{:5.2} x {:.3} y {:.3} vx {:.3} gap {:.3} cmd {:.2} vel {:.2} wheels {:?}",
            s.t_ns as f64 / 1e9,
            s.pose.x,
            s.pose.y,
            s.vx,
            s.gap_m,
            s.cmd_vx,
            s.velocity_vx,
            s.wheels
        );
    }
    eprintln!(
        "overrides {} host {:?}",
        r.overrides,
        (
            r.host_rx.proximity,
            r.host_rx.battery,
            r.host_rx.log,
            &r.host_rx.last_log,
            r.host_rx.odometry.len(),
            r.host_rx.bad
        )
    );
    for m in &r.bus.mcus {
        assert_eq!(m.st.unknown, vec![], "{}", m.name);
        assert_eq!(m.st.fault, None, "{}", m.name);
    }
    assert!(r.physics.max_x_m > 0.6, "max x {}", r.physics.max_x_m);
}
