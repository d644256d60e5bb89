//! Determinism of the simulator and the candump → decode round trip.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]
use rtcan_core::engine::Policy;
use rtcan_sim::candump;
use rtcan_sim::decode::{decode, render, scenario_catalog, Decoded};
use rtcan_sim::paper;
use rtcan_sim::policy::PolicyKind;
use rtcan_sim::run::{run_engine, SimConfig};
use rtcan_sim::traffic::{fill_payload, payload_seq};

fn log(seed: u64) -> String {
    let cfg = SimConfig {
        seconds: 0.2,
        seed,
        ..SimConfig::default()
    };
    let sc = paper::scenario(paper::our_laxity(), 1.0).unwrap();
    candump::log(
        &run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS)
            .unwrap()
            .wire,
        "can0",
    )
}

#[test]
fn same_seed_gives_the_identical_log_and_another_seed_does_not() {
    let a = log(7);
    assert!(a.lines().count() > 1000);
    assert_eq!(a, log(7));
    assert_ne!(a, log(8));
}

#[test]
fn decode_reassembles_every_sent_message_of_a_sim_log() {
    let cfg = SimConfig {
        seconds: 0.2,
        seed: 3,
        ..SimConfig::default()
    };
    let sc = paper::scenario(paper::our_laxity(), 1.0).unwrap();
    let run = run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS).unwrap();
    let text = candump::log(&run.wire, "can0");
    let entries = candump::parse(&text).unwrap();
    assert_eq!(entries.len(), run.wire.iter().filter(|w| w.ok).count());
    let cat = scenario_catalog(&sc);
    let out = decode(&entries, &cat);
    let mut messages = 0;
    let mut syncs = 0;
    for d in &out {
        match d {
            Decoded::Message {
                topic,
                payload,
                fragments,
                ..
            } => {
                messages += 1;
                let t = &cat.topics[*topic];
                assert_eq!(payload.len(), usize::from(t.size));
                let mut expect = vec![0u8; payload.len()];
                fill_payload(&mut expect, payload_seq(payload), payload[4], payload[5]);
                assert_eq!(&expect, payload, "{}", t.name);
                assert_eq!(
                    *fragments as usize,
                    rtcan_core::fragment::fragment_count(payload.len()) as usize
                );
            }
            Decoded::Sync { .. } => syncs += 1,
            Decoded::Heartbeat { fingerprint, .. } => {
                assert_eq!(*fingerprint, sc.tables[0].bus.fingerprint)
            }
            Decoded::Refused { .. } => panic!("own log refused: {}", render(d, &cat)),
            Decoded::Unattributed { why, .. } => {
                // Only transfers the sender dropped half-way (deadline) may be left over.
                assert_eq!(why, "unfinished transfer discarded", "{}", render(d, &cat));
            }
        }
    }
    assert_eq!(syncs, 20, "one sync per 10 ms cycle in 0.2 s");
    // Every message whose last fragment is on the wire is decoded: count last fragments.
    let last = run
        .wire
        .iter()
        .filter(|w| {
            // The fragment field carries the transfer ID too: the counter needs the size.
            let size = cat
                .topics
                .iter()
                .find(|t| t.msg_id == w.frame.id().msg_id().0)
                .map(|t| usize::from(t.size));
            w.ok && size
                .is_some_and(|n| rtcan_core::fragment::counter_of(n, w.frame.id().fragment()) == 0)
                && w.frame.id().laxity() != 63
                && !w.frame.id().is_sync()
        })
        .count();
    assert_eq!(messages, last);
    let line = render(
        out.iter()
            .find(|d| matches!(d, Decoded::Message { fragments: 3, .. }))
            .unwrap(),
        &cat,
    );
    assert!(
        line.contains(" SRT S_") && line.contains("[3 frames] seq="),
        "{line}"
    );
}

#[test]
fn decode_reports_frames_it_cannot_attribute() {
    let sc = paper::scenario(paper::our_laxity(), 1.0).unwrap();
    let cat = scenario_catalog(&sc);
    let text = "(0.000100) can0 00FFFF80#01\n(0.000200) can0 123#00\n";
    let out = decode(&candump::parse(text).unwrap(), &cat);
    assert_eq!(out.len(), 2);
    assert!(render(&out[0], &cat).contains("00FFFF80 not attributed: unknown message ID"));
    assert!(render(&out[1], &cat).contains("standard identifier"));
}
