//! HRT publishers' lead time (`lead`, R2P §3.4.5 synchronous publishers, issue 14): the
//! default, a declared value, the one-slot and period bounds; out-of-range values and
//! `lead` on SRT topics are in robots/broken (tests/broken.rs).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan_model::{analyze, Code};

/// A two-module robot (60 slots of 166 666 ns per 10 ms) with one HRT topic `enc`
/// whose extra keys are `keys`.
fn robot(rate: &str, keys: &str) -> String {
    format!(
        "[bus]\nbitrate = \"1Mbit/s\"\ncycle = \"10ms\"\nslots = 60\nmaster = \"main\"\n\
         [types.Encoder]\nticks = \"i32\"\n\
         [modules.main]\nboard = \"stm32f103c8\"\n[modules.motor]\nboard = \"stm32f103c8\"\n\
         [nodes.ctrl]\nmodule = \"main\"\n[nodes.pid]\nmodule = \"motor\"\n\
         [topics.enc]\ntype = \"Encoder\"\npublisher = \"pid\"\nclass = \"hrt\"\nrate = \"{rate}\"\n{keys}\
         subscribers = [\"ctrl\"]\n"
    )
}

fn lead_of(src: &str) -> Option<u64> {
    let a = analyze("lead.toml", src);
    assert!(a.diagnostics.is_empty(), "{}", a.diagnostics.render());
    let plan = a.plan.unwrap();
    plan.topics
        .iter()
        .find(|t| t.name == "enc")
        .unwrap()
        .lead_ns
}

#[test]
fn default_is_500_us_raised_to_a_slot_and_capped_at_the_period() {
    assert_eq!(lead_of(&robot("200Hz", "")), Some(500_000));
    // Period of 2 slots (333 332 ns) < 500 µs: capped at the period.
    assert_eq!(
        lead_of(&robot("200Hz", "").replace("rate = \"200Hz\"", "period_slots = 2")),
        Some(333_332)
    );
    // Slots of 1 ms (10 per cycle): raised to one slot.
    assert_eq!(
        lead_of(&robot("100Hz", "").replace("slots = 60", "slots = 10")),
        Some(1_000_000)
    );
}

#[test]
fn declared_lead_is_kept_from_one_slot_to_the_period() {
    assert_eq!(
        lead_of(&robot("200Hz", "lead = \"1ms\"\n")),
        Some(1_000_000)
    );
    assert_eq!(
        lead_of(&robot("200Hz", "lead = \"166666ns\"\n")),
        Some(166_666)
    );
    // 200 Hz = 30 slots = 4 999 980 ns: the period itself is allowed.
    assert_eq!(
        lead_of(&robot("200Hz", "lead = \"4999980ns\"\n")),
        Some(4_999_980)
    );
}

#[test]
fn out_of_range_and_malformed_leads_are_bad_values_at_the_value() {
    for (lead, msg) in [
        (
            "166665ns",
            "HRT topic `enc`: `lead` of 166.665 us is outside one slot (166.666 us) ..= its period (30 slots = 4999980 ns)",
        ),
        (
            "4999981ns",
            "HRT topic `enc`: `lead` of 5 ms is outside one slot (166.666 us) ..= its period (30 slots = 4999980 ns)",
        ),
    ] {
        let src = robot("200Hz", &format!("lead = \"{lead}\"\n"));
        let a = analyze("lead.toml", &src);
        let d = &a.diagnostics.items;
        assert_eq!(d.len(), 1, "{lead}");
        assert_eq!(d[0].code, Code::BadValue);
        assert_eq!(d[0].message, msg);
        assert!(a.diagnostics.render().contains("lead.toml:"), "file:line:col");
    }
    let a = analyze("lead.toml", &robot("200Hz", "lead = \"soon\"\n"));
    assert_eq!(a.diagnostics.items[0].code, Code::BadValue);
}
