#![allow(clippy::unwrap_used)]
//! Replays every committed corpus file and crash artifact of the fuzz targets
//! (`fuzz/corpus/<target>/`, `fuzz/artifacts/<target>/`) through the same harness
//! functions the cargo-fuzz targets call: a regression of any past finding, or of any
//! behaviour the corpus covers, fails here on stable (README "Fuzzing").
use std::path::{Path, PathBuf};

fn files(dir: &Path) -> Vec<PathBuf> {
    let Ok(read) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut out: Vec<PathBuf> = read
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    out.sort();
    out
}

fn replay(target: &str, run: fn(&[u8])) -> usize {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
    let mut n = 0;
    for sub in ["corpus", "artifacts"] {
        for path in files(&root.join(sub).join(target)) {
            let data = std::fs::read(&path).unwrap();
            let result = std::panic::catch_unwind(|| run(&data));
            assert!(result.is_ok(), "{target}: {} fails", path.display());
            n += 1;
        }
    }
    n
}

#[test]
fn every_corpus_file_and_artifact_replays_clean() {
    for (target, run) in rtcan_fuzz::TARGETS {
        let n = replay(target, run);
        // A corpus that vanished (moved, not committed) would make this test vacuous.
        assert!(n >= 20, "{target}: only {n} corpus files found");
        eprintln!("{target}: {n} inputs replayed");
    }
}

/// The committed `engine_rx` corpus reaches every receive rule the oracle models: each
/// drop counter of §3.3/§7.2/§9, multi-frame deliveries, both heartbeat verdicts, and the
/// transmit checks (frames loaded). A corpus that lost these would test little.
#[test]
fn engine_rx_corpus_exercises_every_receive_rule() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/engine_rx");
    let mut total = rtcan_fuzz::engine_rx::Stats::default();
    for path in files(&dir) {
        let s = rtcan_fuzz::engine_rx::run_stats(&std::fs::read(&path).unwrap());
        let (t, c) = (&mut total.counts, s.counts);
        t.unknown_id += c.unknown_id;
        t.bad_dlc += c.bad_dlc;
        t.out_of_order += c.out_of_order;
        t.other_transfer += c.other_transfer;
        t.incomplete += c.incomplete;
        t.bad_size += c.bad_size;
        t.bad_sync += c.bad_sync;
        t.bad_heartbeat += c.bad_heartbeat;
        t.overrun += c.overrun;
        t.delivered += c.delivered;
        total.heartbeats += s.heartbeats;
        total.multi_frame_deliveries += s.multi_frame_deliveries;
        total.loads += s.loads;
    }
    eprintln!("{total:?}");
    let c = total.counts;
    for (name, n) in [
        ("unknown_id", c.unknown_id),
        ("bad_dlc", c.bad_dlc),
        ("out_of_order", c.out_of_order),
        ("other_transfer", c.other_transfer),
        ("incomplete", c.incomplete),
        ("bad_size", c.bad_size),
        ("bad_sync", c.bad_sync),
        ("bad_heartbeat", c.bad_heartbeat),
        ("overrun", c.overrun),
        ("delivered", c.delivered),
    ] {
        assert!(n > 0, "no corpus input reaches `{name}`");
    }
    assert!(total.multi_frame_deliveries > 0);
    assert!(total.heartbeats > 0);
    assert!(total.loads > 0);
}
