//! Nodes run where robot.toml says (issue 14, R2P §5.2): the triskar2 scenario on the
//! robot the `rtcan` facade and the Triskar2 node crate were built from (`RTCAN_ROBOT`
//! at build time, else the workspace robot.toml), with no change to the node code.
//!
//! `cargo test` checks the workspace robot: `kinematics` on motor1.
//! `scripts/moved-node-check.sh` builds this test again with
//! `RTCAN_ROBOT=target/tmp/triskar2-moved.toml` (written by scripts/moved-node-check.sh from robot.toml) (kinematics on motor2, odometry on motor3)
//! and `MOVED_NODE_KINEMATICS=motor2`: the same node code, composed into the new modules'
//! apps by the generated apps, drives the robot to the wall and stops it short, every
//! HRT topic on time, and `wheel_setpoints` now leaves motor2.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan_sim::run::SimConfig;
use rtcan_sim::triskar::{self, TriskarConfig};

/// The robot.toml the code under test was generated from.
fn robot_path() -> std::path::PathBuf {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    match option_env!("RTCAN_ROBOT") {
        Some(p) if std::path::Path::new(p).is_absolute() => p.into(),
        Some(p) => root.join(p),
        None => root.join("robot.toml"),
    }
}

#[test]
fn the_kinematics_node_runs_where_robot_toml_places_it_and_the_robot_stops_short() {
    let expected = std::env::var("MOVED_NODE_KINEMATICS").unwrap_or_else(|_| "motor1".into());
    let path = robot_path();
    let plan = rtcan_model::Robot::load(&path).unwrap_or_else(|d| panic!("{}", d.render()));
    // The model, the generated placement and the generated apps agree.
    let k = plan.nodes.iter().find(|n| n.name == "kinematics").unwrap();
    assert_eq!(plan.modules[k.module].name, expected, "{}", path.display());
    assert_eq!(rtcan::robot_toml::nodes::kinematics::MODULE, expected);
    assert_eq!(
        usize::from(rtcan::robot_toml::nodes::kinematics::MODULE_INDEX),
        k.module
    );

    let cfg = TriskarConfig {
        sim: SimConfig {
            seconds: 10.0,
            seed: 1,
            ..SimConfig::default()
        },
        ..TriskarConfig::default()
    };
    let r = triskar::run(&plan, &cfg).unwrap();
    for (mi, m) in r.modules.iter().enumerate() {
        eprintln!("{:10} {:?}", m.name, m.nodes);
        // Every node's task runs on the module robot.toml places it on, and only there.
        let mut placed: Vec<&str> = plan
            .nodes
            .iter()
            .filter(|n| n.module == mi)
            .map(|n| n.name.as_str())
            .collect();
        let mut ran = m.nodes.to_vec();
        placed.sort_unstable();
        ran.sort_unstable();
        assert_eq!(ran, placed, "{}", m.name);
        let runs = m.nodes.contains(&"kinematics");
        assert_eq!(runs, m.name == expected, "{}: {:?}", m.name, m.nodes);
        // The module that runs kinematics sends `wheel_setpoints` (measured at
        // transmission), and no other module does.
        let sends = m
            .sample_age
            .iter()
            .any(|a| a.topic == "wheel_setpoints" && a.stat.count > 0);
        assert_eq!(sends, runs, "{} sends wheel_setpoints", m.name);
        assert!(m.synced, "{} synced", m.name);
        assert_eq!(m.safe_trips, 0, "{} tripped", m.name);
    }
    // The same behaviour wherever kinematics runs: to the wall and stopped short of it,
    // every HRT topic on time, no slot overlap.
    assert!(r.max_x_m > 0.6, "max x {}", r.max_x_m);
    assert!(r.overrides > 10, "overrides {}", r.overrides);
    assert!(
        r.min_gap_m > 0.1 && r.min_gap_m < 0.5,
        "min gap {}",
        r.min_gap_m
    );
    assert!(r.stopped_short());
    for h in &r.run.figures.hrt {
        assert_eq!(h.misses, 0, "{}", h.name);
        assert!(h.count > 0, "{}", h.name);
    }
    assert_eq!(r.run.overlaps, 0);
    eprintln!(
        "kinematics on {expected}: max x {:.3} m, min gap {:.3} m, final gap {:.3} m, {} overrides, HRT misses 0",
        r.max_x_m, r.min_gap_m, r.final_gap_m, r.overrides
    );
}
