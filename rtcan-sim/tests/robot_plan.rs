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
    let run = run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS).unwrap();
    eprintln!("{}", rtcan_sim::report::text(&run));
    assert_eq!(run.overlaps, 0);
    assert!(!run.figures.hrt.is_empty());
    assert!(run.figures.hrt.iter().all(|h| h.misses == 0 && h.count > 0));
    assert_eq!(run.rx_bad, 0);
    assert!(run.rx_ok > 0);
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
    let run = run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS).unwrap();
    let events: u64 = run.figures.srt.iter().map(|s| s.count).sum();
    assert!(events > 500, "{events}");
    assert_eq!(run.overlaps, 0);
    assert!(run.figures.hrt.iter().all(|h| h.misses == 0));
    assert_eq!(run.rx_bad, 0);
    assert!(run.rx_ok > 0);
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

#[test]
fn traffic_on_an_hrt_topic_is_an_error_not_ignored() {
    let d = std::path::Path::new(".");
    let p = plan();
    for pat in ["h_a1", "h_*", "*"] {
        let u = rtcan_sim::robot::parse_user(
            &format!("robot = \"x\"\n[traffic]\n\"{pat}\" = {{ period = \"1ms\" }}"),
            d,
        )
        .unwrap();
        let e = rtcan_sim::robot::expand(&u, &p).unwrap_err();
        assert!(e.contains("matches HRT topic `h_a1`"), "{pat}: {e}");
    }
    let direct = [rtcan_sim::robot::Traffic {
        topic: "h_b2".into(),
        kind: rtcan_sim::traffic::GenKind::Periodic { period: 1_000_000 },
    }];
    let e = rtcan_sim::robot::scenario(&p, &direct).unwrap_err();
    assert!(e.contains("traffic for HRT topic `h_b2`"), "{e}");
}

/// `check` admits robots/hrt200.toml (the sink receives 200 topics); the simulator
/// held 128 and refused it. Engines are now sized by the robot.
#[test]
fn every_robot_check_admits_simulates_hrt200() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/hrt200.toml");
    let p = rtcan_model::Robot::load(path)
        .map_err(|d| d.render())
        .unwrap();
    let sc = rtcan_sim::robot::scenario(&p, &[]).unwrap();
    let sink = sc.tables.iter().map(|t| t.rx.len()).max().unwrap();
    assert_eq!(sink, 200);
    let cfg = SimConfig {
        seconds: 0.3,
        ..SimConfig::default()
    };
    let run = run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS).unwrap();
    assert_eq!(run.figures.hrt.len(), 200);
    assert_eq!(run.rx_bad, 0);
    assert!(run.rx_ok >= 200, "{}", run.rx_ok);
    assert!(run.figures.hrt.iter().all(|h| h.count > 0));
}

/// The largest engine tier (built on a thread with a stack sized by the robot): one
/// module receiving 2 250 one-byte topics from nine publishers.
#[test]
fn a_robot_beyond_the_medium_tier_simulates() {
    let mut src = String::from(
        "[bus]\nbitrate = \"1Mbit/s\"\ncycle = \"10ms\"\nslots = 10\nmaster = \"p0\"\n\
         [types.B]\nv = \"u8\"\n[modules.sink]\nboard = \"stm32f103re\"\nfilters = \"accept-all\"\n\
         [nodes.drain]\nmodule = \"sink\"\n",
    );
    for m in 0..9 {
        src.push_str(&format!(
            "[modules.p{m}]\nboard = \"stm32f103re\"\n[nodes.n{m}]\nmodule = \"p{m}\"\n"
        ));
    }
    for i in 0..2250 {
        // The last few carry traffic the sink must receive intact.
        let rate = if i >= 2245 { "rate = \"50Hz\"\n" } else { "" };
        src.push_str(&format!(
            "[topics.t{i}]\ntype = \"B\"\npublisher = \"n{}\"\nclass = \"nrt\"\n{rate}subscribers = [\"drain\"]\n",
            i / 250
        ));
    }
    let p = rtcan_model::Robot::parse("big.toml", &src)
        .map_err(|d| d.render())
        .unwrap();
    let sc = rtcan_sim::robot::scenario(&p, &[]).unwrap();
    let sink = &sc.tables[0];
    assert_eq!(sink.rx.len(), 2250);
    assert_eq!(rtcan_sim::traffic::tier(sink), Some(2));
    assert!(rtcan_sim::traffic::stack_bytes(&sc.tables).is_some());
    let run = run_engine(
        &sc,
        &SimConfig {
            seconds: 0.1,
            ..SimConfig::default()
        },
        PolicyKind::Ours,
        Policy::OURS,
    )
    .unwrap();
    assert_eq!(run.rx_bad, 0);
    assert!(run.rx_ok >= 10, "{}", run.rx_ok);
    assert_eq!(run.overlaps, 0);
}

/// "If `check` admits a robot, the simulator runs it": every robot file of the
/// repository the model admits (robots/, robots/broken/, tests/) builds a scenario and
/// runs 0.2 s with no bad delivery and no slot overlap.
#[test]
fn every_admitted_robot_file_of_the_repository_simulates() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = vec![root.join("robot.toml")];
    for dir in ["robots", "robots/broken", "tests/robots", "tests/ui/robots"] {
        let Ok(rd) = std::fs::read_dir(root.join(dir)) else {
            continue;
        };
        for e in rd.flatten() {
            if e.path().extension().is_some_and(|x| x == "toml") {
                files.push(e.path());
            }
        }
    }
    files.sort();
    let mut admitted = 0;
    for f in &files {
        let Ok(p) = rtcan_model::Robot::load(f) else {
            continue;
        };
        admitted += 1;
        let sc =
            rtcan_sim::robot::scenario(&p, &[]).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let cfg = SimConfig {
            seconds: 0.2,
            record_wire: false,
            ..SimConfig::default()
        };
        let run = run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS)
            .unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert_eq!(run.rx_bad, 0, "{}", f.display());
        assert_eq!(run.overlaps, 0, "{}", f.display());
    }
    assert!(admitted >= 5, "{admitted} of {}", files.len());
}
