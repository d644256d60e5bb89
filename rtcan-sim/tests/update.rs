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

/// A power cut (the module's supply) during every request of a small update, at the
/// first, a middle and the last flash operation of the request: the module boots the
/// old image or the new one, never nothing, and running the update again completes.
#[test]
fn power_cut_at_every_protocol_step_leaves_a_bootable_module() {
    let fp = rtcan::robot_toml::FINGERPRINT;
    let old = test_image(4096, fp, 0);
    let new = test_image(2000, fp, 7);
    let t = Target {
        module: 3,
        image: new.clone(),
        fingerprint: fp,
    };
    // Flash operations per request: Begin erases 30 pages, each Data programs 125
    // half-words (the last 0 bytes… 2000 = 8 × 250), End commits the 9-half-word header.
    let ops: Vec<u32> = [30].into_iter().chain([125; 8]).chain([9]).collect();
    let mut cuts = 0;
    for (request, &n) in ops.iter().enumerate() {
        for op in [0, n / 2, n - 1] {
            let mut j = job(vec![t.clone(), t.clone()]);
            j.cut = Some((
                3,
                Cut {
                    request: request as u32,
                    op,
                    down_ns: 50_000_000,
                },
            ));
            let r = run(6.0, Some(j));
            let (at, boots) = &r.update_cuts[3];
            assert_eq!(at.len(), 1, "request {request} op {op}: the cut hit");
            cuts += 1;
            // After the cut: the old image (slot 0), never nothing.
            assert_eq!(boots[0], Some((0, crc(&old))), "request {request} op {op}");
            // The second run (or already the first, resumed by a repeated Begin) completes.
            let last = r.update.last().unwrap();
            assert!(
                matches!(last.outcome, Some(Outcome::Done { .. })),
                "request {request} op {op}: {:?}",
                r.update
            );
            assert_eq!(r.booted[3].map(|b| (b.1, b.2)), Some((2000, crc(&new))));
        }
    }
    assert_eq!(cuts, 30);
}

#[test]
fn images_for_another_robot_are_refused() {
    let fp = rtcan::robot_toml::FINGERPRINT;
    let old = test_image(4096, fp, 0);
    let r = run(
        3.0,
        Some(job(vec![
            // Announced for another robot: refused at Begin, nothing erased.
            Target {
                module: 2,
                image: test_image(3000, fp ^ 1, 1),
                fingerprint: fp ^ 1,
            },
            // Built for another robot, announced as this one: refused at End.
            Target {
                module: 4,
                image: test_image(3000, fp ^ 1, 2),
                fingerprint: fp,
            },
        ])),
    );
    assert_eq!(r.update[0].outcome, Some(Outcome::Failed(Why::Fingerprint)));
    assert_eq!(r.update[0].frames, 32, "one Begin");
    assert_eq!(r.update[1].outcome, Some(Outcome::Failed(Why::Fingerprint)));
    assert_eq!(r.update[1].frames, 14 * 32, "Begin, 12 Data, End");
    for m in [2, 4] {
        assert_eq!(r.booted[m], Some((0, 4096, crc(&old))), "module {m}");
    }
}
