#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! Issue 10 on the command line: `check` rejects a guard the slot timer path does not
//! fit (exit 1, `guard-too-short`); `sim` runs on the CPU model by default, reports it in
//! JSON, and takes `--cpu off`, `--cpu-design`, `--cpi` (bad values exit 2).
mod common;
use common::rtcan;

#[test]
fn check_rejects_a_guard_shorter_than_the_timer_path() {
    let (code, out, err) = rtcan(&["check", "robots/broken/guard-too-short.toml"]);
    assert_eq!(code, 1, "{err}");
    assert!(out.contains("not admissible"));
    assert!(
        err.starts_with("error[guard-too-short]: module `main`: worst-case latency from a slot boundary to its TXRQ ("),
        "{err}"
    );
    let (code, out, _) = rtcan(&["check", "robot.toml"]);
    assert_eq!(code, 0);
    assert!(out.contains("\ntiming (guard 5 us;"), "{out}");
}

/// The slot timer's TXRQ latency bounds of the prioritised design with every activation
/// at its max: (path alone, the timing check's worst case incl. the critical section), ns.
fn txrq_bounds() -> (u64, u64) {
    let t = rtcan_model::costs::Design::Prioritised.table().unwrap();
    let ns = |instr: u32| ((12.0 + f64::from(instr) * 1.25) * 1e9 / 72e6_f64).ceil() as u64;
    let txrq = t.path("slot_boundary_to_txrq").max;
    let alone = (txrq - t.path("critical_section_slot").max).min(t.path("isr_slot_timer").max);
    (ns(alone), ns(txrq))
}

/// `"key":<integer>` in `text` after `from`.
fn int_after(text: &str, from: usize, key: &str) -> u64 {
    let at = from + text[from..].find(&format!("\"{key}\":")).unwrap() + key.len() + 3;
    let digits: String = text[at..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().unwrap()
}

#[test]
fn sim_reports_the_cpu_model() {
    let sim = |extra: &[&str]| {
        let mut a = vec!["sim", "robot.toml", "--seconds", "1", "--json"];
        a.extend_from_slice(extra);
        let (code, out, err) = rtcan(&a);
        assert_eq!(code, 0, "{err}");
        out
    };
    let out = sim(&[]);
    assert!(
        out.contains(r#","cpu":{"design":"prioritised","cpi":1.25,"clock_hz":72000000,"cost":"max","modules":[{"name":"gateway","load":"#),
        "{out}"
    );
    let (alone, worst) = txrq_bounds();
    for name in ["gateway", "motor1", "motor2", "motor3", "proximity", "psu"] {
        let at = out.find(&format!(r#"{{"name":"{name}","load":"#)).unwrap();
        let (max, p99) = (int_after(&out, at, "max"), int_after(&out, at, "p99"));
        if int_after(&out, at, "samples") == 0 {
            assert_eq!(name, "psu", "the only module without HRT frames");
            continue;
        }
        assert!(
            alone <= p99 && p99 <= max && p99 <= worst,
            "{name}: {p99} {max}"
        );
    }
    let out = sim(&["--cpu", "off"]);
    assert!(!out.contains(r#""cpu":"#), "no model, no cpu report");
    let out = sim(&["--cpu-design", "old", "--cpi", "2"]);
    assert!(
        out.contains(
            r#""cpu":{"design":"single-priority","cpi":2.0,"clock_hz":72000000,"cost":"max","#
        ),
        "{out}"
    );
    assert!(
        !out.contains(r#""slot_overlaps":0,"#),
        "the old design overlaps slots"
    );
    let out = sim(&["--cpu-cost", "mean"]);
    assert!(out.contains(r#""cost":"mean""#), "{out}");
    let at = out.find(r#""cpu":"#).unwrap();
    assert!(int_after(&out, at, "max") < alone, "mean paths are shorter");
}

#[test]
fn sim_rejects_bad_cpu_options() {
    for (args, msg) in [
        (&["--cpi", "abc"][..], "invalid value 'abc' for '--cpi"),
        (&["--cpi", "0"][..], "--cpi must be in [0.5, 10]"),
        (&["--cpi", "NaN"][..], "--cpi must be in [0.5, 10]"),
        (&["--cpu-design", "fast"][..], "unknown --cpu-design `fast`"),
        (&["--cpu", "maybe"][..], "--cpu must be `on` or `off`"),
        (
            &["--cpu-cost", "p99"][..],
            "--cpu-cost must be `max` or `mean`",
        ),
    ] {
        let mut a = vec!["sim", "robot.toml", "--seconds", "1"];
        a.extend_from_slice(args);
        let (code, _, err) = rtcan(&a);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(msg), "{args:?}: {err}");
    }
}
