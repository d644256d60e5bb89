//! Incremental change in the simulator (issue 14): Triskar2 with a robot.lock gains an
//! IMU module publishing one HRT topic to the gateway. Only the IMU and the gateway (the
//! receiver and master) get images from the new plan; the five other modules run the
//! tables of the OLD plan. HRT must have 0 misses and every delivery must check. With the
//! gateway left on its old image (stale master masks), the new HRT topic is not
//! protected and the run shows it — the test can fail.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]
use rtcan_core::engine::Policy;
use rtcan_model::{analyze, analyze_locked, compat, lock, Plan};
use rtcan_sim::policy::PolicyKind;
use rtcan_sim::run::{run_engine, Run, SimConfig};

const TRISKAR: &str = include_str!("../../robot.toml");

const IMU: &str = "\n[modules.imu]\nboard = \"stm32f103c8\"\n\n[nodes.imu_driver]\nmodule = \"imu\"\npriority = 2\n\n\
[topics.imu_rate]\ntype = \"Encoder\"\npublisher = \"imu_driver\"\nclass = \"hrt\"\nrate = \"100Hz\"\n\
subscribers = [{ node = \"ros_bridge\", queue = 2 }]\n";

fn plans() -> (Plan, Plan) {
    let a = analyze("robot.toml", TRISKAR);
    let lock = lock::render(a.model.as_ref().unwrap(), a.plan.as_ref().unwrap(), None);
    let locked = |s: &str| {
        analyze_locked("robot.toml", s, Some(("robot.lock", &lock)))
            .plan
            .unwrap()
    };
    (locked(TRISKAR), locked(&format!("{TRISKAR}{IMU}")))
}

/// Runs the new plan's scenario with the modules named in `old_images` on the old plan's
/// tables.
fn run_mixed(old: &Plan, new: &Plan, old_images: &[&str]) -> Run {
    let sc = rtcan_sim::robot::mixed_scenario(old, new, old_images).unwrap();
    let cfg = SimConfig {
        seconds: 0.5,
        ..SimConfig::default()
    };
    run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS).unwrap()
}

#[test]
fn old_images_keep_working_beside_the_new_module_and_master() {
    let (old, new) = plans();
    let changed: Vec<String> = compat::images_to_change(&old, &new)
        .into_iter()
        .map(|c| c.module)
        .collect();
    // motor1 too: the backup master receives every module's health and the gateway's
    // module table, one row longer (robot.toml `on_missing`, docs/SERVICES.md §1).
    assert_eq!(changed, ["gateway", "motor1", "imu"]);
    let old_images = ["motor2", "motor3", "proximity", "psu"];
    // Old images announce the same fingerprint: no module is told its peer is foreign.
    for m in old_images {
        let oi = old.modules.iter().position(|o| o.name == m).unwrap();
        assert_eq!(
            old.tables(oi).unwrap().bus.fingerprint,
            new.fingerprint,
            "{m}"
        );
    }
    let run = run_mixed(&old, &new, &old_images);
    eprintln!("{}", rtcan_sim::report::text(&run));
    // Six HRT topics on the bus (encoder2 stays on motor2), the IMU's among them.
    assert_eq!(run.figures.hrt.len(), 6, "{:?}", run.figures.hrt);
    for h in &run.figures.hrt {
        assert!(
            h.count > 0 && h.misses == 0,
            "{} {} {}",
            h.name,
            h.count,
            h.misses
        );
    }
    // Exactly what the same robot does with every image built from the new plan.
    let all_new = run_mixed(&old, &new, &[]);
    for (a, b) in run.figures.hrt.iter().zip(&all_new.figures.hrt) {
        assert_eq!(
            (&a.name, a.count, a.misses, a.missed, a.max_response_ns),
            (&b.name, b.count, b.misses, b.missed, b.max_response_ns)
        );
    }
    assert_eq!((run.rx_ok, run.rx_bad), (all_new.rx_ok, all_new.rx_bad));
    assert!(run.figures.hrt.iter().any(|h| h.name.contains("imu_rate")));
    assert_eq!(run.rx_bad, 0);
    assert!(run.rx_ok > 200, "{}", run.rx_ok);
    // Every module's engine counters are those of the all-new run (the same frames
    // received, delivered and dropped), no size errors, no deadline misses.
    assert_eq!(run.counters.len(), 7);
    for (i, (c, n)) in run.counters.iter().zip(&all_new.counters).enumerate() {
        assert_eq!(c, n, "module {i}");
        assert_eq!(c.rx_bad_size, 0, "module {i}");
        assert_eq!(c.deadline_missed, 0, "module {i}");
    }
    // The gateway receives the new topic.
    assert!(run.counters[0].rx_delivered > 0);
}

#[test]
fn a_stale_master_image_is_caught() {
    let (old, new) = plans();
    // Gateway on its old image: the IMU's HRT slots are not in its reservation masks and
    // it does not expect `imu_rate`.
    let run = run_mixed(
        &old,
        &new,
        &["gateway", "motor1", "motor2", "motor3", "proximity", "psu"],
    );
    let unknown: u32 = run.counters.iter().map(|c| c.rx_unknown_id).sum();
    let imu = run
        .figures
        .hrt
        .iter()
        .find(|h| h.name.contains("imu_rate"))
        .unwrap();
    let delivered_gw = run.counters[0].rx_delivered;
    let fresh = run_mixed(
        &old,
        &new,
        &["motor1", "motor2", "motor3", "proximity", "psu"],
    );
    eprintln!(
        "stale: imu misses {} unknown {unknown} gw delivered {delivered_gw}; fresh gw delivered {}",
        imu.misses, fresh.counters[0].rx_delivered
    );
    // The stale gateway drops the IMU's frames as unknown and delivers fewer messages.
    assert!(unknown > 0);
    assert!(delivered_gw < fresh.counters[0].rx_delivered);
}
