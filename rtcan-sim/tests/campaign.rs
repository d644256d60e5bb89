//! The fault campaign, shortened (7 s per case): every case meets its goals (no bad
//! delivery, no cycle with two syncs beyond the one a healed partition allows, the safe
//! state when the robot cannot work and not otherwise, the expected master, temporal
//! isolation on the wire where no error forces retransmissions), and the figures that
//! show each fault did its harm are there.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]
use rtcan_sim::campaign;

#[test]
fn every_case_meets_its_goals() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robot.toml");
    let plan = rtcan_model::Robot::load(&path).unwrap_or_else(|d| panic!("{}", d.render()));
    let base = rtcan_sim::run::SimConfig {
        seconds: 7.0,
        seed: 1,
        ..Default::default()
    };
    let rows = campaign::run(&plan, &base, &mut |_, _| {}).unwrap();
    eprintln!("{}", campaign::table(&rows));
    assert_eq!(rows.len(), campaign::cases().len());
    for r in &rows {
        assert!(r.goals().is_empty(), "{}: {:?}", r.case.name, r.goals());
    }
    let by = |n: &str| rows.iter().find(|r| r.case.name == n).unwrap();
    // No fault, no loss.
    let nominal = by("nominal");
    assert_eq!((nominal.hrt_sum().2, nominal.srt_misses), (0, 0));
    // The takeover outage: SYNC_LOSS_CYCLES + 2 cycles of 10 ms, not more.
    let gap = by("master-dies-2s-returns-5s").longest_sync_gap_ms.unwrap();
    assert!((50.0..=80.0).contains(&gap), "{gap}");
    // No master left: the silence runs to the end of the run.
    let dead = by("backup-dies-during-takeover")
        .longest_sync_gap_ms
        .unwrap();
    assert!(dead > 4_900.0, "{dead}");
    // Errors are seen and survived: error frames, EOF errors, no bad delivery.
    assert!(by("paper-ber-1e-3").error_frames > 100);
    assert!(by("ber-1e-3").error_frames > 100);
    assert!(by("eof-errors-1e-3").eof_errors > 10);
    assert!(by("paper-eof-errors-1e-3").eof_errors > 100);
    assert_eq!(by("paper-eof-errors-1e-3").bad_deliveries, Some(0));
    // The stuck bus: everyone error-passive, one bus-off; detected within 4 cycles,
    // recovered within 1.1 s of the fault (released after 1 s).
    let stuck = by("stuck-dominant-1s-to-2s");
    assert_eq!((stuck.error_passive, stuck.bus_off), (5, 1));
    assert!(stuck.detect_ms.unwrap() <= 40.0, "{:?}", stuck.detect_ms);
    assert!(
        stuck.recover_ms.unwrap() <= 1_100.0,
        "{:?}",
        stuck.recover_ms
    );
    // The guardian cut exactly the babbler; without it the babbler breaks isolation.
    assert_eq!(by("babbling-idiot-guardian").guardian_cuts, 1);
    assert!(by("babbling-idiot-from-1s").slot_violations.unwrap() > 1000);
    assert!(by("rx-overrun-stall-20ms").fifo_overruns > 3);
    // The robot noticed its master's death, and came back after a partition.
    assert!(by("master-dies-2s").detect_ms.is_some());
    assert!(by("partition-master-2s-to-4s").recover_ms.is_some());
}
