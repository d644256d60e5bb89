//! `proximity_read` (robot.toml `[services]`) on the simulated Triskar2 (issue 15): the
//! gateway calls, the proximity module serves from its rangers, over the simulated bus
//! as SRT frames with the service's deadline. Replies carry the readings, concurrent
//! calls, a lost reply times out at its deadline, a dead server is reported absent.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan::robot_toml as robot;
use rtcan_core::Nanos;
use rtcan_pubsub::service::CallError;
use rtcan_sim::fault;
use rtcan_sim::run::SimConfig;
use rtcan_sim::triskar::services::{Outcome, ServiceLog, ServiceScript, NO_RANGER};
use rtcan_sim::triskar::{self, TriskarConfig, MODULES};

const MS: Nanos = 1_000_000;

fn plan() -> rtcan_model::Plan {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robot.toml");
    rtcan_model::Robot::load(&path).unwrap_or_else(|d| panic!("{}", d.render()))
}

fn run(seconds: f64, script: ServiceScript, faults: &[&str]) -> ServiceLog {
    let cfg = TriskarConfig {
        sim: SimConfig {
            seconds,
            record_wire: false,
            ..SimConfig::default()
        },
        faults: faults
            .iter()
            .map(|f| fault::parse(f, &MODULES).unwrap())
            .collect(),
        ..TriskarConfig::default()
    };
    triskar::run_with_services(&plan(), &cfg, &script)
        .unwrap()
        .1
}

fn script(period_ms: u64, burst: usize) -> ServiceScript {
    ServiceScript {
        period_ns: Some(period_ms * MS),
        burst,
        from_ns: 1000 * MS,
        lose_replies: Vec::new(),
        request: None,
    }
}

/// Every replied call: its reply is one the server gave (same sensor and range, served
/// between the call and the reply), for the sensor it asked.
fn check_replies(log: &ServiceLog) -> usize {
    let mut n = 0;
    for c in &log.calls {
        if let Outcome::Replied {
            global_ns,
            sensor,
            range_mm,
            ..
        } = c.outcome
        {
            assert_eq!(sensor, c.sensor, "{c:?}");
            assert!(
                log.served.iter().any(|s| s.sensor == sensor
                    && s.range_mm == range_mm
                    && s.global_ns >= c.global_ns
                    && s.global_ns <= global_ns),
                "{c:?} not served"
            );
            if sensor == 4 {
                assert_eq!(range_mm, NO_RANGER);
            } else {
                assert!(range_mm < 5000, "{c:?}");
            }
            n += 1;
        }
    }
    n
}

#[test]
fn replies_carry_the_readings_within_two_deadlines() {
    let log = run(3.0, script(100, 1), &[]);
    // Calls at 1.0, 1.1, ..., 2.9 s: 20, every one answered.
    assert_eq!(log.calls.len(), 20);
    assert_eq!(check_replies(&log), 20);
    assert_eq!(log.served.len(), 20);
    let c = log.counters;
    assert_eq!(
        (c.calls, c.replies, c.timeouts, c.late_or_unknown, c.busy),
        (20, 20, 0, 0, 0)
    );
    // Sensors 0..4 in turn: 4 calls each (sensor 4 answered with NO_RANGER).
    let front: Vec<u16> = log
        .calls
        .iter()
        .filter_map(|c| match c.outcome {
            Outcome::Replied {
                sensor: 0,
                range_mm,
                ..
            } => Some(range_mm),
            _ => None,
        })
        .collect();
    assert_eq!(front.len(), 4);
    let f = log.figures();
    // Request and reply each within the 5 ms deadline; at least two frames' time.
    let deadline = plan().service("proximity_read").unwrap().deadline_ns;
    assert!(f.latency_max_ns <= 2 * deadline, "{f:?}");
    assert!(f.latency_mean_ns >= 2 * 100_000, "{f:?}");
    assert!(!f.server_absent);
    eprintln!(
        "proximity_read: {} calls, latency max {} us, mean {} us",
        f.calls,
        f.latency_max_ns / 1000,
        f.latency_mean_ns / 1000
    );
}

#[test]
fn concurrent_calls_are_matched_and_the_third_is_refused() {
    // Three calls at once per period; in_flight = 2: the third is refused (Busy).
    let log = run(2.0, script(50, 3), &[]);
    let periods = 20;
    assert_eq!(log.calls.len(), 3 * periods);
    let busy = log
        .calls
        .iter()
        .filter(|c| c.outcome == Outcome::Refused(CallError::Busy))
        .count();
    assert_eq!(busy, periods);
    assert_eq!(check_replies(&log), 2 * periods);
    let c = log.counters;
    assert_eq!((c.calls, c.replies, c.timeouts, c.busy), (40, 40, 0, 20));
    // Two calls were in flight together each period, for different sensors.
    for pair in log.calls.chunks(3) {
        assert_eq!(pair[0].global_ns, pair[1].global_ns);
        assert_ne!(pair[0].sensor, pair[1].sensor);
    }
}

#[test]
fn a_lost_reply_times_out_at_its_deadline() {
    let mut s = script(100, 1);
    s.lose_replies = vec![3];
    let log = run(2.0, s, &[]);
    assert_eq!(log.lost_frames, 1);
    let lost: Vec<_> = log.calls.iter().filter(|c| c.call == Some(3)).collect();
    assert_eq!(lost.len(), 1);
    match lost[0].outcome {
        Outcome::TimedOut { local_ns, .. } => {
            // On the client's clock, exactly the timeout after the call, plus the
            // interrupt latency of the timer wake-up the client asked for at the deadline.
            let irq = SimConfig::default().node_irq_latency_ns();
            assert_eq!(
                local_ns - lost[0].local_ns,
                robot::gateway::services::ProximityReadClient::TIMEOUT_NS + irq
            );
            assert_eq!(local_ns - lost[0].local_ns, 20 * MS + 2_000);
        }
        o => panic!("{o:?}"),
    }
    let c = log.counters;
    assert_eq!(
        (c.calls, c.replies, c.timeouts, c.late_or_unknown),
        (10, 9, 1, 0)
    );
    assert_eq!(check_replies(&log), 9);
    // The server answered all ten: the reply was lost on the way.
    assert_eq!(log.served.len(), 10);
    assert!(log.absent_at.is_none());
}

#[test]
fn a_dead_server_is_absent_after_three_timeouts() {
    let log = run(3.0, script(100, 1), &["proximity:dies@2s"]);
    // Calls at 1.0..1.9 s answered; from 2.0 s every call times out.
    let c = log.counters;
    assert_eq!((c.calls, c.replies, c.timeouts), (20, 10, 10));
    assert_eq!(check_replies(&log), 10);
    let timed_out: Vec<Nanos> = log
        .calls
        .iter()
        .filter_map(|c| match c.outcome {
            Outcome::TimedOut { global_ns, .. } => Some(global_ns),
            _ => None,
        })
        .collect();
    assert_eq!(timed_out.len(), 10);
    // Absent exactly at the third timeout (2.2 s call + 20 ms), not before.
    assert_eq!(log.absent_at, Some(timed_out[2]));
    assert!(
        timed_out[2] >= 2220 * MS - MS && timed_out[2] <= 2220 * MS + MS,
        "{timed_out:?}"
    );
    assert!(log.figures().server_absent);
}
