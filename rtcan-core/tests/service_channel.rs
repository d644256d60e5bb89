#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! The update channel (docs/PROTOCOL.md §2.3, `rtcan_core::service`): frames the host
//! offers go out as NRT in free windows only, in order, after everything else; frames
//! of the range reach every host's `service_rx`; a frame outside the range or with
//! another laxity is never sent.
mod common;
mod paper_bus;

use common::*;
use paper_bus::{paper, SLOT_NS};
use rtcan_core::id::{CanId, MsgId};
use rtcan_core::Frame;

fn bus_of(nodes: usize) -> Bus {
    let p = paper(nodes);
    let mut bus = Bus::new(1_000_000);
    for (n, t) in p.tables.iter().enumerate() {
        bus.add(
            *t,
            [0.0, 1000.0, -1000.0][n % 3],
            [0.0, 3_333_333.0, 17_000.0][n % 3],
        );
    }
    for n in 0..nodes {
        bus.nodes[n].host.hrt = (0..3)
            .map(|k| Some(vec![n as u8, k as u8, 0, 0, 0, 0, 0, 0xAA]))
            .collect();
    }
    bus
}

fn request(k: u8) -> Frame {
    // Request to module 2 (0xFF82), fragment field k (as a 32-frame transfer would).
    Frame::new(
        CanId::new(63, MsgId(0xFF82), k & 0x1F).unwrap(),
        &[k, 1, 2, 3, 4, 5, 6, 7],
    )
    .unwrap()
}

#[test]
fn service_frames_go_in_windows_in_order_and_change_nothing_else() {
    let until = 200_000_000 + 40 * 60 * SLOT_NS;
    let mut plain = bus_of(3);
    plain.run(until);
    let mut bus = bus_of(3);
    // A frame with HRT priority in the range and one outside it: discarded, not sent.
    bus.nodes[1]
        .host
        .service_out
        .push_back(Frame::new(CanId::new(0, MsgId(0xFF82), 0).unwrap(), &[9]).unwrap());
    bus.nodes[1]
        .host
        .service_out
        .push_back(Frame::new(CanId::new(63, MsgId(0x0141), 0).unwrap(), &[9]).unwrap());
    bus.nodes[1].host.service_out.extend((0..200).map(request));
    bus.run(until);
    assert!(bus.nodes[1].host.service_out.is_empty());
    let on_wire: Vec<Frame> = bus
        .log
        .iter()
        .filter(|w| w.frame.id().msg_id().0 >= 0xFF80)
        .map(|w| w.frame)
        .collect();
    let want: Vec<Frame> = (0..200).map(request).collect();
    assert_eq!(
        on_wire, want,
        "every offered frame once, in order, nothing else"
    );
    assert!(!bus.log.iter().any(|w| w.frame.data() == [9]));
    // Every other node's host got them, in order (no filters on this bus).
    assert_eq!(bus.nodes[2].host.service_in, want);
    assert_eq!(bus.nodes[0].host.service_in, want);
    // Nothing else changed: the same HRT and SRT/NRT outcomes, the same counters but
    // the frames sent, and no unknown IDs counted.
    for n in 0..3 {
        assert_eq!(bus.nodes[n].host.done, plain.nodes[n].host.done, "node {n}");
        let (a, b) = (
            bus.nodes[n].engine.counters(),
            plain.nodes[n].engine.counters(),
        );
        assert_eq!(a.hrt_late, 0);
        assert_eq!(a.deadline_missed, b.deadline_missed);
        assert_eq!(a.rx_unknown_id, b.rx_unknown_id);
        assert_eq!(a.rx_delivered, b.rx_delivered, "node {n}");
    }
    assert_eq!(
        bus.nodes[1].engine.counters().tx_frames,
        plain.nodes[1].engine.counters().tx_frames + 200
    );
}
