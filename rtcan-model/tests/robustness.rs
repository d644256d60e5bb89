//! Malformed input never panics: byte-level mutations (proptest), every line removed in
//! turn, and every value replaced by hostile ones.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use proptest::prelude::*;
use rtcan_model::{analyze, Status};
use std::path::PathBuf;

fn triskar2() -> String {
    std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../robot.toml"))
        .unwrap()
}

/// Analyses and renders (rendering touches every span).
fn check(src: &str) -> Status {
    let a = analyze("robot.toml", src);
    let _ = a.diagnostics.render();
    let _ = rtcan_model::report::json_text(&a);
    if let Some(p) = &a.plan {
        let _ = rtcan_model::report::text(p);
    }
    assert_eq!(a.plan.is_some(), a.status() == Status::Admissible);
    a.status()
}

#[test]
fn every_line_removed() {
    let src = triskar2();
    let lines: Vec<&str> = src.lines().collect();
    for i in 0..lines.len() {
        let mut l = lines.clone();
        l.remove(i);
        check(&l.join("\n"));
    }
}

#[test]
fn every_value_replaced_by_hostile_values() {
    let src = triskar2();
    let hostile = [
        "0",
        "-1",
        "99999999999999999",
        "\"\"",
        "[]",
        "{}",
        "1e308",
        "nan",
        "true",
        "\"0Hz\"",
        "\"1ns\"",
        "\"1000s\"",
        "\"999999Hz\"",
        "\"µs\"",
        "\"[u8; 99999]\"",
        "1979-05-27",
        "[\"x\", 1]",
        "{ node = 1 }",
        "\"ü\"",
        "\"1.5kHz\"",
    ];
    let lines: Vec<&str> = src.lines().collect();
    let mut statuses = [0usize; 3];
    for (i, line) in lines.iter().enumerate() {
        let Some(eq) = line.find(" = ") else { continue };
        for h in hostile {
            let mut l: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
            l[i] = format!("{}{h}", &line[..eq + 3]);
            statuses[check(&l.join("\n")).exit_code() as usize] += 1;
        }
    }
    // The loop really exercised failures, not only the happy path.
    assert!(statuses[2] > 100, "{statuses:?}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]
    #[test]
    fn byte_mutations_never_panic(edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>(), 0u8..3), 1..8)) {
        let mut bytes = triskar2().into_bytes();
        for (at, b, op) in edits {
            if bytes.is_empty() { break; }
            let i = at.index(bytes.len());
            match op {
                0 => bytes[i] = b,
                1 => { bytes.remove(i); }
                _ => bytes.insert(i, b),
            }
        }
        let src = String::from_utf8_lossy(&bytes);
        check(&src);
    }

    #[test]
    fn arbitrary_text_never_panics(s in "\\PC{0,200}") {
        check(&s);
    }
}
