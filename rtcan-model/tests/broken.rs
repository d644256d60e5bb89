//! Every file in robots/broken/ fails with its diagnostic, rendered exactly as in the
//! `.stderr` file beside it (file:line:col, excerpt, caret, help). `BLESS=1` rewrites the
//! expected files (review the diff).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan_model::{analyze, Code, Status};
use std::path::PathBuf;

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../robots/broken")
}

/// (file stem, codes expected in order, status).
const CASES: &[(&str, &[Code], Status)] = &[
    ("toml-syntax", &[Code::TomlSyntax], Status::Invalid),
    ("unknown-key", &[Code::UnknownKey], Status::Invalid),
    ("duplicate-name", &[Code::DuplicateName], Status::Invalid),
    (
        "duplicate-subscriber",
        &[Code::DuplicateName],
        Status::Invalid,
    ),
    ("unknown-type", &[Code::UnknownType], Status::Invalid),
    ("unknown-field-type", &[Code::UnknownType], Status::Invalid),
    ("unknown-node", &[Code::UnknownNode], Status::Invalid),
    ("unknown-module", &[Code::UnknownModule], Status::Invalid),
    (
        "master-not-a-module",
        &[Code::UnknownModule],
        Status::Invalid,
    ),
    ("no-master", &[Code::NoMaster], Status::Invalid),
    ("too-many-slots", &[Code::TooManySlots], Status::Invalid),
    (
        "slot-too-short",
        &[Code::SlotTooShort],
        Status::NotAdmissible,
    ),
    ("bad-value", &[Code::BadValue], Status::Invalid),
    ("wrong-type", &[Code::WrongType], Status::Invalid),
    ("missing-key", &[Code::MissingKey], Status::Invalid),
    ("bad-name", &[Code::BadName], Status::Invalid),
    (
        "keyword-name",
        &[Code::BadName, Code::BadName, Code::BadName],
        Status::Invalid,
    ),
    ("name-collision", &[Code::NameCollision], Status::Invalid),
    (
        "bitrate-unreachable",
        &[Code::BitrateUnreachable],
        Status::Invalid,
    ),
    ("unknown-board", &[Code::UnknownBoard], Status::Invalid),
    ("class-mismatch", &[Code::ClassMismatch], Status::Invalid),
    ("lead-not-hrt", &[Code::ClassMismatch], Status::Invalid),
    (
        "hrt-lead-out-of-range",
        &[Code::BadValue, Code::BadValue],
        Status::Invalid,
    ),
    ("queue-zero", &[Code::QueueZero], Status::Invalid),
    (
        "period-not-representable",
        &[Code::PeriodNotRepresentable],
        Status::NotAdmissible,
    ),
    (
        "inadmissible-hrt",
        &[Code::InadmissibleHrt],
        Status::NotAdmissible,
    ),
    (
        "hrt-over-capacity",
        &[Code::HrtOverCapacity],
        Status::NotAdmissible,
    ),
    (
        "hyperperiod-too-long",
        &[Code::HyperperiodTooLong],
        Status::NotAdmissible,
    ),
    (
        "payload-too-large",
        &[Code::PayloadTooLarge],
        Status::Invalid,
    ),
    (
        "filter-banks-exhausted",
        &[Code::FilterBanksExhausted],
        Status::Invalid,
    ),
    ("bus-overload", &[Code::BusOverload], Status::NotAdmissible),
    (
        "srt-deadline-too-short",
        &[Code::SrtDeadlineTooShort],
        Status::NotAdmissible,
    ),
    (
        "guard-too-short",
        &[Code::GuardTooShort, Code::GuardTooShort],
        Status::NotAdmissible,
    ),
    (
        "several-errors",
        &[Code::TooManySlots, Code::UnknownType, Code::QueueZero],
        Status::Invalid,
    ),
];

#[test]
fn every_broken_file_has_a_case() {
    let mut stems: Vec<String> = std::fs::read_dir(dir())
        .unwrap()
        .filter_map(|e| {
            let p = e.unwrap().path();
            (p.extension()? == "toml")
                .then(|| p.file_stem().unwrap().to_string_lossy().into_owned())
        })
        .collect();
    stems.sort();
    let mut cases: Vec<String> = CASES.iter().map(|c| c.0.to_string()).collect();
    cases.sort();
    assert_eq!(stems, cases);
}

#[test]
fn broken_files_render_their_exact_diagnostics() {
    let bless = std::env::var_os("BLESS").is_some();
    let mut failures = Vec::new();
    for (stem, codes, status) in CASES {
        let path = dir().join(format!("{stem}.toml"));
        let source = std::fs::read_to_string(&path).unwrap();
        let a = analyze(&format!("{stem}.toml"), &source);
        let got: Vec<Code> = a.diagnostics.items.iter().map(|d| d.code).collect();
        assert_eq!(&got, codes, "{stem}: codes");
        assert_eq!(a.status(), *status, "{stem}: status");
        assert!(a.plan.is_none(), "{stem}: no plan");
        let rendered = a.diagnostics.render();
        let expected_path = dir().join(format!("{stem}.stderr"));
        if bless {
            std::fs::write(&expected_path, &rendered).unwrap();
            continue;
        }
        let expected = std::fs::read_to_string(&expected_path).unwrap_or_default();
        if rendered != expected {
            failures.push(format!(
                "--- {stem}: expected\n{expected}\n--- got\n{rendered}"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn inadmissible_names_both_topics_and_suggests() {
    let source = std::fs::read_to_string(dir().join("inadmissible-hrt.toml")).unwrap();
    let a = analyze("robot.toml", &source);
    assert_eq!(
        a.diagnostics.render(),
        "error[inadmissible-hrt]: topic `speed` has period 3 slots (2000.008 Hz), not admissible with `enc1` \
         (period 2 slots (3000.012 Hz)): periods relatively prime\n  \
         --> robot.toml:35:8\n   |\n35 | rate = \"2kHz\"\n   |        ^^^^^^\n   \
         = help: admissible periods for `speed`: 4 slots (1500.006 Hz), 6 slots (1000.004 Hz)\n\n\
         error: 1 error in robot.toml\n"
    );
    let d = &a.diagnostics.items[0];
    // Structured form for the proc macro: the span is the value's byte range.
    assert_eq!(&source[d.span.clone().unwrap()], "\"2kHz\"");
}

#[test]
fn accept_all_fallback_fixes_exhausted_banks() {
    let path = dir().join("../accept-all.toml");
    let plan = rtcan_model::Robot::load(&path).unwrap();
    let sink = plan.module("sink").unwrap();
    assert_eq!(sink.banks.len(), 1);
    assert_eq!(sink.rx.len(), 13);
    assert_eq!(sink.filter_mode, rtcan_model::FilterMode::AcceptAll);
}
