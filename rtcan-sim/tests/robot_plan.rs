//! Scenarios from a robot.toml plan.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]
use rtcan_core::engine::Policy;
use rtcan_sim::policy::PolicyKind;
use rtcan_sim::run::{run_engine, SimConfig};

fn plan() -> rtcan_model::Plan {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/rtcan-paper.toml");
    rtcan_model::Robot::load(path)
        .map_err(|d| d.render())
        .unwrap()
}

#[test]
fn plan_scenario_runs_with_zero_hrt_misses() {
    let p = plan();
    let sc = rtcan_sim::robot::scenario(&p, &[]).unwrap();
    let cfg = SimConfig {
        seconds: 0.3,
        ..SimConfig::default()
    };
    let run = run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS);
    eprintln!("{}", rtcan_sim::report::text(&run));
    assert_eq!(run.overlaps, 0);
    assert!(!run.figures.hrt.is_empty());
    assert!(run.figures.hrt.iter().all(|h| h.misses == 0 && h.count > 0));
    assert_eq!(run.rx_bad, 0);
}

#[test]
fn user_scenario_file_drives_the_plan_like_the_hand_built_benchmark() {
    let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios"));
    let text = std::fs::read_to_string(dir.join("rtcan-paper.toml")).unwrap();
    let user = rtcan_sim::robot::parse_user(&text, dir).unwrap();
    let p = rtcan_model::Robot::load(&user.robot)
        .map_err(|d| d.render())
        .unwrap();
    let traffic = rtcan_sim::robot::expand(&user, &p).unwrap();
    assert_eq!(traffic.len(), 45);
    let sc = rtcan_sim::robot::scenario(&p, &traffic).unwrap();
    let cfg = SimConfig {
        seconds: 0.5,
        ..SimConfig::default()
    };
    let run = run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS);
    let events: u64 = run.figures.srt.iter().map(|s| s.count).sum();
    assert!(events > 500, "{events}");
    assert_eq!(run.overlaps, 0);
    assert!(run.figures.hrt.iter().all(|h| h.misses == 0));
    assert_eq!(run.rx_bad, 0);
}

#[test]
fn user_scenario_errors_are_reported() {
    let d = std::path::Path::new(".");
    assert!(rtcan_sim::robot::parse_user("[traffic]", d)
        .unwrap_err()
        .contains("missing `robot"));
    let e = rtcan_sim::robot::parse_user(
        "robot = \"x\"\n[traffic]\na = { every = [\"20ms\", \"10ms\"] }",
        d,
    )
    .unwrap_err();
    assert!(e.contains("0 < min <= max"), "{e}");
    let u =
        rtcan_sim::robot::parse_user("robot = \"x\"\n[traffic]\nnope = { period = \"1ms\" }", d)
            .unwrap();
    assert!(rtcan_sim::robot::expand(&u, &plan())
        .unwrap_err()
        .contains("matches no topic"));
}
