//! `candump`: bytes → `rtcan_sim::candump` line parser → `rtcan_sim::decode` (reassembly,
//! heartbeat verdicts, rendering) with the catalog of the RTCAN paper robot. Never a
//! panic; a parsed frame has a 29-bit identifier and `data().len() == dlc`; writing a
//! parsed frame back (`candump::line`) and parsing it again gives the same frame, with
//! the time truncated to microseconds; the decoder's counts add up.
use std::sync::OnceLock;

use rtcan_sim::candump::{classify, line, parse, Line};
use rtcan_sim::decode::{plan_catalog, render, Catalog, Decoded, Decoder};

/// The catalog of `robots/rtcan-paper.toml`, planned once per process.
fn catalog() -> &'static Catalog {
    static CAT: OnceLock<Catalog> = OnceLock::new();
    CAT.get_or_init(|| {
        let src = include_str!("../../robots/rtcan-paper.toml");
        let plan = rtcan_model::Robot::parse("rtcan-paper.toml", src)
            .expect("the paper robot is admissible");
        plan_catalog(&plan)
    })
}

/// One fuzz run. Panics (assert) on a finding.
pub fn run(data: &[u8]) {
    let Some((&flags, rest)) = data.split_first() else {
        return;
    };
    let text = String::from_utf8_lossy(rest);
    let cat = catalog();
    let mut decoder = Decoder::new(cat);
    decoder.force = flags & 1 != 0;
    let mut fed = 0u64;
    let mut records = 0u64;
    for l in text.lines() {
        let Ok(Line::Frame(e)) = classify(l) else {
            continue;
        };
        assert!(e.frame.id().raw() <= 0x1FFF_FFFF);
        assert_eq!(e.frame.data().len(), usize::from(e.frame.dlc()));
        assert!(e.frame.dlc() <= 8);
        let again = line(e.time_ns, &e.iface, &e.frame);
        match classify(&again) {
            Ok(Line::Frame(back)) if !e.standard => {
                assert_eq!(back.frame, e.frame, "{again}");
                assert_eq!(back.iface, e.iface, "{again}");
                assert_eq!(back.time_ns, e.time_ns / 1_000 * 1_000, "{again}");
            }
            // A standard frame is written back with 8 digits (an extended frame).
            Ok(Line::Frame(back)) => assert_eq!(back.frame, e.frame, "{again}"),
            other => panic!("`{l}` parsed, its rewrite `{again}` gives {other:?}"),
        }
        fed += 1;
        if let Some(d) = decoder.push(&e) {
            records += 1;
            let _ = render(&d, cat);
            if let Decoded::Message { payload, topic, .. } = &d {
                let size = cat.topics.get(*topic).map(|t| usize::from(t.size));
                assert_eq!(Some(payload.len()), size, "payload of the topic's size");
            }
        }
    }
    let c = decoder.counts;
    assert_eq!(c.frames, fed);
    assert!(c.messages + c.refused + c.unattributed <= records);
    // The whole-log parser agrees with the line classifier: when it accepts the log,
    // every line was blank or a frame, and it returns exactly those frames.
    if let Ok(entries) = parse(&text) {
        assert_eq!(entries.len() as u64, fed);
    }
}
