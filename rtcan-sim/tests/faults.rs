//! The three failures of issue 11 as simulations: a master that returns after a backup
//! took over, a master absent from start-up, transfers that must never mix. Each ran
//! wrong before (two syncs in every cycle after the return; no takeover; a glued message
//! delivered with a valid transfer CRC).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan_core::engine::Policy;
use rtcan_sim::fault;
use rtcan_sim::paper;
use rtcan_sim::policy::PolicyKind;
use rtcan_sim::run::{run_engine, SimConfig};
use rtcan_sim::triskar::{self, TriskarConfig, TriskarRun, MODULES};

fn plan() -> rtcan_model::Plan {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robot.toml");
    rtcan_model::Robot::load(&path).unwrap_or_else(|d| panic!("{}", d.render()))
}

fn run(seconds: f64, faults: &[&str], dies_at: Option<f64>) -> TriskarRun {
    let cfg = TriskarConfig {
        sim: SimConfig {
            seconds,
            record_wire: false,
            ..SimConfig::default()
        },
        gateway_dies_at_s: dies_at,
        faults: faults
            .iter()
            .map(|f| fault::parse(f, &MODULES).unwrap())
            .collect(),
        ..TriskarConfig::default()
    };
    triskar::run(&plan(), &cfg).unwrap()
}

fn masters(r: &TriskarRun) -> Vec<&str> {
    r.modules
        .iter()
        .filter(|m| m.master)
        .map(|m| m.name)
        .collect()
}

#[test]
fn master_that_returns_defers_to_the_backup_no_cycle_has_two_syncs() {
    let r = run(8.0, &["gateway:dies@2s", "gateway:returns@5s"], None);
    eprintln!("{:?}", r.syncs);
    for m in &r.modules {
        eprintln!("{m:?}");
    }
    assert_eq!(r.modules[0].reboots, 1);
    // The backup took over and kept the bus; the returning gateway follows it.
    assert_eq!(masters(&r), ["motor1"]);
    assert!(r.modules.iter().all(|m| m.synced), "every module follows");
    // Not one cycle with two syncs in the whole run, in particular after the return.
    assert_eq!(r.syncs.doubled, 0, "{:?}", r.syncs);
    // The outage: from the gateway's death to motor1's first sync (takeover after
    // SYNC_LOSS_CYCLES + 2 silent cycles of 10 ms), not longer.
    let (gap, at) = r.syncs.longest_gap;
    assert!(
        (50_000_000..=80_000_000).contains(&gap),
        "longest sync gap {gap} ns"
    );
    assert!((2_000_000_000..2_100_000_000).contains(&at), "{at}");
    // HRT on time: no frame outside its slot as the sync on the wire places it, whoever
    // sent it (nearly every frame checked), and no module loaded an HRT frame late.
    assert_eq!(r.slots_live.0, 0, "{:?}", r.slots_live);
    assert!(r.slots_live.1 > 6_000, "{:?}", r.slots_live);
    assert_eq!(r.run.overlaps, 0);
    for m in &r.modules {
        assert_eq!(m.counters.hrt_late, 0, "{}", m.name);
    }
    // The gateway, back (fresh counters), sends again: its HRT frames and heartbeats.
    assert!(r.modules[0].counters.tx_frames > 100);
}

#[test]
fn module_reset_mid_run_rejoins_without_two_masters() {
    let r = run(5.0, &["motor2:reset@3.2s", "gateway:reset@4s"], None);
    eprintln!("{:?}", r.syncs);
    assert_eq!((r.modules[0].reboots, r.modules[2].reboots), (1, 1));
    assert_eq!(r.syncs.doubled, 0);
    assert_eq!(masters(&r).len(), 1);
    assert!(r.modules.iter().all(|m| m.synced));
    assert_eq!(r.run.overlaps, 0);
    assert_eq!(r.slots_live.0, 0);
    for m in &r.modules {
        assert_eq!(m.counters.hrt_late, 0, "{}", m.name);
    }
}

#[test]
fn master_absent_from_start_up_the_backup_takes_over() {
    // `rtcan sim --seconds 4 --master-dies-at 0.01`
    let r = run(4.0, &[], Some(0.01));
    eprintln!("{:?}", r.syncs);
    assert_eq!(masters(&r), ["motor1"]);
    assert!(r.modules[1..].iter().all(|m| m.synced));
    assert_eq!(r.syncs.doubled, 0);
    // One sync per 10 ms cycle from the takeover on (within the first 100 ms).
    assert!(r.syncs.syncs >= 390, "{}", r.syncs.syncs);
    assert!(r.syncs.longest_gap.0 <= 100_000_000, "{:?}", r.syncs);
    // Motor1's schedule, checked on the wire: every frame in its slot or window.
    assert_eq!(r.slots_live.0, 0, "{:?}", r.slots_live);
    assert!(r.slots_live.1 > 3_000, "{:?}", r.slots_live);
    for m in &r.modules {
        assert_eq!(m.counters.hrt_late, 0, "{}", m.name);
    }
    // Motor2 receives motor1's HRT setpoints again (the bus is not silent).
    assert!(r.modules[2].counters.rx_delivered > 1000);
}

#[test]
fn transfers_never_mix_under_bit_errors() {
    // The paper scenario carries identity bytes (source, topic, sequence) in every
    // payload: a message glued from two transfers would not check. At 1e-4 errors many
    // transfers lose fragments (window ends abort them mid-transfer).
    let cfg = SimConfig {
        seconds: 2.0,
        bit_error_rate: 1e-4,
        record_wire: false,
        ..SimConfig::default()
    };
    let sc = paper::scenario(paper::our_laxity(), 1.0).unwrap();
    let run = run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS).unwrap();
    let broken: u64 = run
        .counters
        .iter()
        .map(|c| u64::from(c.rx_incomplete) + u64::from(c.rx_other_transfer))
        .sum();
    eprintln!(
        "rx ok {} bad {} broken transfers {broken} error frames {}",
        run.rx_ok, run.rx_bad, run.bus.error_frames
    );
    assert!(run.bus.error_frames > 100);
    assert!(broken > 0, "the errors must break some transfers");
    assert!(run.rx_ok > 10_000);
    assert_eq!(run.rx_bad, 0);
}

#[test]
fn babbling_idiot_without_guardian_floods_everything_but_the_sync() {
    let r = run(3.0, &["motor3:babble@1s"], None);
    eprintln!("{:?}", r.syncs);
    for h in &r.run.figures.hrt {
        eprintln!("{} frames {} missed {}", h.name, h.count, h.misses);
    }
    for m in &r.modules {
        eprintln!(
            "{} safe {} trips {} {:?}",
            m.name, m.safe_now, m.safe_trips, m.counters
        );
    }
    // The sync (lower identifier) still wins: one master, one sync per cycle.
    assert_eq!(masters(&r), ["gateway"]);
    assert_eq!(r.syncs.doubled, 0);
    assert!(r.syncs.longest_gap.0 < 11_000_000, "{:?}", r.syncs);
    // Every HRT topic of the other modules loses arbitration from 1 s on: of the 2 s
    // measured after it, nearly everything is missed.
    let missed: u64 = r.run.figures.hrt.iter().map(|h| h.misses).sum();
    let frames: u64 = r.run.figures.hrt.iter().map(|h| h.count).sum();
    assert!(missed > frames, "missed {missed} frames {frames}");
    // The robot goes to its safe state: the modules that watch the master's heartbeat
    // no longer receive it. Not the master itself, not the babbler, and not motor1: the
    // first backup, still synced, follows itself once the master's heartbeat is stale
    // (pubsub `SystemStatus::current_master`, issue 15).
    for m in &r.modules[1..] {
        let expect = !matches!(m.name, "motor3" | "motor1");
        assert_eq!(m.safe_now, expect, "{} {:?}", m.name, m.safe_reason);
    }
    // Its frames land in the heartbeat range: dropped and counted by every receiver.
    assert!(r.modules[1].counters.rx_bad_heartbeat > 10_000);
}
