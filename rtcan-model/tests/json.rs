//! Shape of `rtcan check --json` (documented in docs/ROBOT_TOML.md).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan_model::{analyze, report};
use serde_json::Value;
use std::path::PathBuf;

fn load(rel: &str) -> Value {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel);
    let src = std::fs::read_to_string(path).unwrap();
    let text = report::json_text(&analyze(rel, &src));
    serde_json::from_str(&text).unwrap()
}

#[test]
fn admissible_json_has_placements_that_never_collide() {
    for rel in ["robot.toml", "robots/rtcan-paper.toml"] {
        let v = load(rel);
        assert_eq!(v["admissible"], true);
        assert_eq!(v["status"], "admissible");
        assert_eq!(v["slots_per_cycle"], 60);
        assert_eq!(v["slot_ns"], 166_666);
        let slots = 60u64;
        let hyper = v["hyperperiod_slots"].as_u64().unwrap();
        let mut owner = vec![None; hyper as usize];
        for s in (0..hyper).step_by(slots as usize) {
            owner[s as usize] = Some("sync".to_string());
        }
        let hrt = v["hrt"].as_array().unwrap();
        assert!(!hrt.is_empty());
        for h in hrt {
            let keys: Vec<&str> = h.as_object().unwrap().keys().map(String::as_str).collect();
            for k in ["topic", "module", "period_slots", "phase_slot", "fragments"] {
                assert!(keys.contains(&k), "{rel}: {k}");
            }
            let (p, ph, f) = (
                h["period_slots"].as_u64().unwrap(),
                h["phase_slot"].as_u64().unwrap(),
                h["fragments"].as_u64().unwrap(),
            );
            let mut k = 0;
            while ph + k * p < hyper {
                for j in 0..f {
                    let s = (ph + k * p + j) as usize;
                    assert_eq!(owner[s], None, "{rel}: slot {s} taken twice");
                    owner[s] = Some(h["topic"].as_str().unwrap().to_string());
                }
                k += 1;
            }
        }
        // The masks say exactly the same.
        let masks = v["masks"].as_array().unwrap();
        for (c, m) in masks.iter().enumerate() {
            let m = u64::from_str_radix(m.as_str().unwrap().trim_start_matches("0x"), 16).unwrap();
            for s in 0..slots {
                assert_eq!(
                    m >> s & 1 == 1,
                    owner[c * slots as usize + s as usize].is_some(),
                    "{rel}: cycle {c} slot {s}"
                );
            }
        }
        assert_eq!(v["diagnostics"], Value::Array(vec![]));
    }
}

#[test]
fn failing_json_reports_status_and_diagnostics() {
    let v = load("robots/broken/inadmissible-hrt.toml");
    assert_eq!(v["admissible"], false);
    assert_eq!(v["status"], "not-admissible");
    assert_eq!(v["slots_per_cycle"], 60);
    assert_eq!(v["hrt"], Value::Array(vec![]));
    let d = &v["diagnostics"][0];
    assert_eq!(d["code"], "inadmissible-hrt");
    assert_eq!(d["category"], "schedule");
    assert_eq!(
        (d["line"].as_u64(), d["column"].as_u64()),
        (Some(35), Some(8))
    );
    assert!(d["help"][0]
        .as_str()
        .unwrap()
        .starts_with("admissible periods for `speed`"));

    let v = load("robots/broken/unknown-node.toml");
    assert_eq!(v["status"], "invalid");
    assert_eq!(v["diagnostics"][0]["code"], "unknown-node");
    assert_eq!(v["diagnostics"][0]["category"], "input");
}
