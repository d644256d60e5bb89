//! Supervision on the simulated Triskar2 (issue 15, docs/SERVICES.md §1): robot.toml
//! declares `on_missing` for every module, so every module beats every cycle and a dead
//! module is shown missing 3 cycle starts after the heartbeat it failed to send (3 to 4
//! cycles after its death); the rules put exactly the modules they name in their safe
//! state; no module is ever shown missing in a clean run nor at BER 1e-4.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan::pubsub::{OnMissing, SafeReason};
use rtcan::robot_toml as robot;
use rtcan_sim::run::SimConfig;
use rtcan_sim::triskar::{self, TriskarConfig, TriskarRun};

const CYCLE_NS: u64 = 10_000_000;
const WARM_UP_NS: u64 = 1_000_000_000;

fn plan() -> rtcan_model::Plan {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robot.toml");
    rtcan_model::Robot::load(&path).unwrap_or_else(|d| panic!("{}", d.render()))
}

fn run(cfg: TriskarConfig) -> TriskarRun {
    triskar::run(&plan(), &cfg).unwrap()
}

#[test]
fn the_robot_is_supervised_with_a_heartbeat_every_cycle() {
    // From robot.toml: every module has a rule, 6 heartbeats fit 10 % of a 10 ms cycle.
    const { assert!(robot::supervision::SUPERVISED) };
    assert_eq!(robot::supervision::HEARTBEAT_CYCLES, 1);
    assert_eq!(robot::supervision::MISSING_AFTER_CYCLES, 3);
    let rules = robot::supervision::RULES;
    assert_eq!(rules.len(), 6);
    let rule = |m: u8| rules.iter().find(|r| r.module == m).unwrap();
    assert_eq!(rule(robot::gateway::INDEX).on_missing, OnMissing::SafeAll);
    assert_eq!(rule(robot::psu::INDEX).on_missing, OnMissing::Warn);
    let prox = rule(robot::proximity::INDEX);
    assert_eq!(prox.on_missing, OnMissing::SafeDependents);
    let motors = (1u64 << robot::motor1::INDEX)
        | (1u64 << robot::motor2::INDEX)
        | (1u64 << robot::motor3::INDEX);
    assert_eq!(prox.dependents, motors);
}

/// Kills `victim` at `die_s`; checks the sync master's table (through its wire form) and
/// every module's safe state against the victim's rule. Returns cycles to detection.
fn kill(victim: usize, seed: u64, die_s: f64) -> f64 {
    let die = (die_s * 1e9) as u64;
    let r = run(TriskarConfig {
        sim: SimConfig {
            seconds: 2.5,
            seed,
            ..SimConfig::default()
        },
        // Into the open: the robot drives while the victim dies.
        wall_x_m: 50.0,
        module_dies_at: Some((victim, die_s)),
        ..TriskarConfig::default()
    });
    let name = r.modules[victim].name;
    for s in r
        .supervision
        .iter()
        .filter(|s| s.t_ns > WARM_UP_NS && s.t_ns <= die)
    {
        assert_eq!(
            s.table.missing(),
            0,
            "{name}: at {} ns: {:?}",
            s.t_ns,
            s.table
        );
    }
    let first = r
        .supervision
        .iter()
        .find(|s| s.t_ns > die && s.table.missing() != 0)
        .unwrap_or_else(|| panic!("{name} never shown missing"));
    assert_eq!(
        first.table.missing(),
        1 << victim,
        "{name}: only the victim"
    );
    let row = first.table.rows[victim];
    assert!(!row.alive && row.heard, "{row:?}");
    assert_eq!(row.age, robot::supervision::MISSING_AFTER_CYCLES + 1);
    let cycles = (first.t_ns - die) as f64 / CYCLE_NS as f64;
    // 3 cycle starts after the heartbeat it failed to send: within 4 cycles of the death
    // (samples every 1/20 cycle).
    assert!(first.t_ns <= die + 4 * CYCLE_NS, "{name}: {cycles} cycles");
    for s in r.supervision.iter().filter(|s| s.t_ns >= first.t_ns) {
        assert_eq!(s.table.missing(), 1 << victim, "{name} stays missing");
    }
    // The safe state per robot.toml's rule for the victim, on every survivor.
    let rule = robot::supervision::RULES
        .iter()
        .find(|x| usize::from(x.module) == victim)
        .unwrap();
    for m in r.modules.iter().enumerate().filter(|(i, _)| *i != victim) {
        let (i, m) = m;
        // The sync master (the gateway) never stops itself on a rule.
        let expected = i != usize::from(robot::MASTER)
            && match rule.on_missing {
                OnMissing::SafeAll => true,
                OnMissing::SafeDependents => rule.dependents & (1 << i) != 0,
                OnMissing::Warn => false,
            };
        assert_eq!(
            m.safe_now, expected,
            "{name} dead: {} {:?}",
            m.name, m.safe_reason
        );
        if expected {
            let missing = Some(SafeReason::ModuleMissing {
                module: victim as u8,
            });
            assert_eq!(m.safe_reason, missing, "{name} dead: {}", m.name);
            // Entered within 4 cycles of the death (and not before it).
            let at = m.safe_times.0.unwrap();
            assert!(at > die && at <= die + 4 * CYCLE_NS, "{}: {at}", m.name);
            if let Some((speed, safe)) = m.motor {
                assert!(safe, "{} motor safe", m.name);
                assert!(speed.abs() < 1.0, "{} wheel {speed}", m.name);
            }
        } else {
            assert_eq!(
                m.safe_trips, 0,
                "{name} dead: {} {:?}",
                m.name, m.safe_reason
            );
        }
    }
    eprintln!(
        "{name} (on_missing {:?}): died at {die} ns, shown missing at {} ns ({cycles:.2} cycles)",
        rule.on_missing, first.t_ns
    );
    cycles
}

#[test]
fn every_killed_slave_is_shown_missing_within_4_cycles_and_its_rule_applied() {
    let mut worst: f64 = 0.0;
    // Deaths at several points of the cycle: before and after the victim's heartbeat.
    for (victim, seed, die_s) in [
        (robot::motor2::INDEX, 5, 2.0),
        (robot::psu::INDEX, 4, 2.0025),
        (robot::proximity::INDEX, 6, 2.005),
        (robot::motor3::INDEX, 7, 2.0075),
        (robot::motor1::INDEX, 8, 2.0099),
        (robot::motor2::INDEX, 9, 2.0051),
        (robot::psu::INDEX, 10, 2.0001),
    ] {
        worst = worst.max(kill(usize::from(victim), seed, die_s));
    }
    eprintln!("worst detection: {worst:.2} cycles");
    assert!(worst <= 4.0);
}

fn no_false_missing(ber: f64, seed: u64) {
    let r = run(TriskarConfig {
        sim: SimConfig {
            seconds: 10.0,
            seed,
            bit_error_rate: ber,
            ..SimConfig::default()
        },
        supervise: true,
        ..TriskarConfig::default()
    });
    let samples: Vec<_> = r
        .supervision
        .iter()
        .filter(|s| s.t_ns > WARM_UP_NS)
        .collect();
    // Sampled every 1/20 cycle: a transient "missing" cannot slip between samples.
    assert!(samples.len() > 17_000, "{}", samples.len());
    let oldest = samples
        .iter()
        .flat_map(|s| s.table.rows.iter().map(|r| r.age))
        .max()
        .unwrap();
    for s in &samples {
        assert_eq!(
            s.table.missing(),
            0,
            "ber {ber} at {} ns: {:?}",
            s.t_ns,
            s.table
        );
    }
    for m in &r.modules {
        assert_eq!(m.safe_trips, 0, "ber {ber}: {} {:?}", m.name, m.safe_reason);
        assert!(!m.safe_now, "ber {ber}: {}", m.name);
    }
    eprintln!(
        "ber {ber}: {} samples (1/20 cycle), oldest heartbeat {oldest} cycle(s), error frames {}",
        samples.len(),
        r.run.bus.error_frames
    );
    if ber > 0.0 {
        assert!(r.run.bus.error_frames > 50, "errors happen");
    }
}

#[test]
fn no_module_shown_missing_in_a_clean_10s_run() {
    no_false_missing(0.0, 1);
}

#[test]
fn no_module_shown_missing_at_ber_1e_4() {
    no_false_missing(1e-4, 2);
}
