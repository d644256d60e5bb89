//! Firmware update over the bus on the simulated Triskar2 (docs/SERVICES.md §4): the
//! 28 KiB budget with the robot's traffic running, power cuts at every protocol step,
//! bad images refused.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use rtcan_boot::sender::{Config, Outcome};
use rtcan_boot::update::Why;
use rtcan_sim::run::SimConfig;
use rtcan_sim::triskar::{self, TriskarConfig, TriskarRun};
use rtcan_sim::update::{crc, test_image, Cut, Target, UpdateJob};

fn plan() -> rtcan_model::Plan {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml");
    rtcan_model::Robot::load(std::path::Path::new(path)).unwrap()
}

fn run(seconds: f64, update: Option<UpdateJob>) -> TriskarRun {
    let cfg = TriskarConfig {
        sim: SimConfig {
            seconds,
            seed: 1,
            ..SimConfig::default()
        },
        update,
        ..TriskarConfig::default()
    };
    triskar::run(&plan(), &cfg).unwrap()
}

fn job(targets: Vec<Target>) -> UpdateJob {
    UpdateJob {
        targets,
        start_ns: 500_000_000,
        config: Config::default(),
        flash: Vec::new(),
        cut: None,
    }
}

#[test]
fn a_28_kib_image_in_budget_with_the_robot_running() {
    let fp = rtcan::robot_toml::FINGERPRINT;
    let img = test_image(28 * 1024, fp, 0x5A);
    let seconds = 12.0;
    let base = run(seconds, None);
    let r = run(
        seconds,
        Some(job(vec![Target {
            module: 1,
            image: img.clone(),
            fingerprint: fp,
        }])),
    );
    let u = &r.update[0];
    eprintln!(
        "28 KiB to motor1: {} frames, {} retries, {:.3} s bus time, {:?}",
        u.frames,
        u.retries,
        u.bus_time_ns as f64 / 1e9,
        u.outcome
    );
    // Begin, 115 Data, End: 32 frames each, nothing repeated.
    assert_eq!((u.frames, u.retries), (117 * 32, 0));
    assert_eq!(u.outcome, Some(Outcome::Done { slot: 1, seq: 2 }));
    assert!(u.bus_time_ns <= 10_000_000_000, "{} ns", u.bus_time_ns);
    assert_eq!(r.booted[1], Some((1, 28 * 1024, crc(&img))));
    // The robot did not notice: no HRT miss, SRT as without the update.
    for (h, b) in r.run.figures.hrt.iter().zip(&base.run.figures.hrt) {
        eprintln!("{} {} {}", h.name, h.misses, b.misses);
        assert_eq!(h.misses, 0, "{}", h.name);
    }
    assert_eq!(r.run.figures.srt.len(), base.run.figures.srt.len());
    for (s, b) in r.run.figures.srt.iter().zip(&base.run.figures.srt) {
        let (worst, worst_base) = (s.percentile_ns(100.0), b.percentile_ns(100.0));
        eprintln!(
            "{}: {} sent, {} missed, worst {worst} ns (without update {worst_base} ns)",
            s.name, s.count, s.misses
        );
        assert_eq!((s.count, s.misses), (b.count, b.misses), "{}", s.name);
        assert_eq!(s.misses, 0, "{}", s.name);
        // An update frame already on the wire delays an SRT frame by one frame at most
        // (CAN is not preemptive): 160 µs at 1 Mbit/s.
        assert!(worst <= worst_base + 160_000, "{}", s.name);
    }
    assert!(r.stopped_short());
}
