//! `rtcan_sim::apps`: any robot's own module apps on the simulated bus (what the `sim`
//! crate of an `rtcan new` workspace runs), here on Triskar2's generated code: the HRT
//! figures come from what the node code publishes, so a topic nobody publishes is missed
//! and one published at its period is not.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan::robot_toml as robot;
use rtcan_sim::apps::{run, AppModule, AppSpec, PollApp};
use rtcan_sim::run::SimConfig;

type Nanos = u64;

fn plan() -> rtcan_model::Plan {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robot.toml");
    rtcan_model::Robot::load(&path).unwrap_or_else(|d| panic!("{}", d.render()))
}

/// Publishes nothing.
struct Silent;

impl PollApp for Silent {
    fn poll(&mut self, _now: Nanos) -> Nanos {
        Nanos::MAX
    }
    fn published(&self) -> u64 {
        0
    }
    fn publish_errors(&self) -> u64 {
        0
    }
    fn received(&self) -> u64 {
        0
    }
}

/// motor1's `encoder1` (HRT, 200 Hz) published every 5 ms.
struct Encoder1 {
    next: Nanos,
    sent: u64,
    errors: u64,
}

impl PollApp for Encoder1 {
    fn poll(&mut self, now: Nanos) -> Nanos {
        if now >= self.next {
            let r = robot::motor1::nodes::motor_ctrl1::encoder1_pub().send(
                robot::Encoder {
                    ticks: 1,
                    speed: 0.5,
                },
                now,
            );
            match r {
                Ok(()) => self.sent += 1,
                Err(_) => self.errors += 1,
            }
            self.next = now + 5_000_000;
        }
        self.next
    }
    fn published(&self) -> u64 {
        self.sent
    }
    fn publish_errors(&self) -> u64 {
        self.errors
    }
    fn received(&self) -> u64 {
        0
    }
}

macro_rules! spec {
    ($m:ident, $app:expr) => {
        AppSpec {
            build: Box::new(|now| {
                Box::new(AppModule::new(
                    stringify!($m),
                    robot::$m::engine(now),
                    robot::$m::host(),
                    &robot::$m::STATUS,
                    $app,
                ))
            }),
            filters: robot::$m::FILTERS,
            reset: robot::$m::reset,
        }
    };
}

#[test]
fn hrt_misses_follow_what_the_node_code_publishes() {
    let specs = vec![
        spec!(gateway, Silent),
        spec!(
            motor1,
            Encoder1 {
                next: 0,
                sent: 0,
                errors: 0
            }
        ),
        spec!(motor2, Silent),
        spec!(motor3, Silent),
        spec!(proximity, Silent),
        spec!(psu, Silent),
    ];
    let cfg = SimConfig {
        seconds: 1.0,
        ..SimConfig::default()
    };
    let r = run(&plan(), &specs, &cfg).unwrap();
    assert!(r.modules.iter().all(|m| m.synced), "{}", r.text());
    let misses = |name: &str| {
        r.figures
            .hrt
            .iter()
            .find(|h| h.name.starts_with(&format!("{name}@")))
            .unwrap_or_else(|| panic!("{name}: {}", r.text()))
            .misses
    };
    assert_eq!(misses("encoder1"), 0, "{}", r.text());
    // At power-on, then every 5 ms up to and including the end of the 1 s run: 201.
    let m1 = &r.modules[1];
    assert_eq!(
        (m1.name, m1.published, m1.publish_errors),
        ("motor1", 201, 0)
    );
    // Published by nobody: every instance of the 1 s window after the warm-up is missed
    // (encoder2 is motor2's local topic, never on the bus). Seeded, so exact.
    for (silent, n) in [
        ("wheel_setpoints", 97),
        ("odometry", 48),
        ("encoder3", 194),
        ("proximity", 24),
    ] {
        assert_eq!(misses(silent), n, "{silent}: {}", r.text());
    }
    assert_eq!(r.hrt_misses(), 363);
    assert!(r.text().starts_with("simulated 1.000 s; HRT misses "));
}

#[test]
fn a_module_list_not_matching_the_plan_is_refused() {
    let specs = vec![spec!(gateway, Silent)];
    let plan = plan();
    let e = run(&plan, &specs, &SimConfig::default()).unwrap_err();
    assert_eq!(e, format!("1 modules given, {} has 6", plan.file));
}
