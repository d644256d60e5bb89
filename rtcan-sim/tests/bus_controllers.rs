//! The bus and the bxCAN-like controllers on their own: arbitration, exact durations,
//! FIFO overrun, abort, NART, bit errors, timestamps in local clocks.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]
use rtcan_core::driver::{Mailbox, TxResult};
use rtcan_core::timing::exact_bits;
use rtcan_core::{CanId, Controller, Frame, Nanos};
use rtcan_sim::bus::{Bus, Module, NodeSetup};
use rtcan_sim::{Filter, NodeClock, SimController};

/// Records what the driver would hand the engine.
#[derive(Default)]
struct Probe {
    rx: Vec<(u32, Nanos, Nanos)>,
    done: Vec<(u8, TxResult, Nanos)>,
    overruns: u32,
}

impl Module for Probe {
    fn start(&mut self, _: Nanos, _: &mut SimController) -> Option<Nanos> {
        None
    }
    fn wake(&mut self, _: Nanos, _: &mut SimController) -> Option<Nanos> {
        None
    }
    fn rx(&mut self, f: &Frame, sof: Nanos, now: Nanos, _: &mut SimController) -> Option<Nanos> {
        self.rx.push((f.id().raw(), sof, now));
        None
    }
    fn tx_done(
        &mut self,
        mb: Mailbox,
        r: TxResult,
        now: Nanos,
        _: &mut SimController,
    ) -> Option<Nanos> {
        self.done.push((mb.0, r, now));
        None
    }
    fn rx_overrun(&mut self, _: Nanos) {
        self.overruns += 1;
    }
}

const US: Nanos = 1_000;

fn frame(raw: u32, data: &[u8]) -> Frame {
    Frame::new(CanId::from_raw(raw).unwrap(), data).unwrap()
}

fn bus(n: usize) -> Bus<Probe> {
    let mut b = Bus::new(1_000_000, 0.0, 1);
    for _ in 0..n {
        b.add_node(Probe::default(), NodeSetup::default());
    }
    b
}

fn load(b: &mut Bus<Probe>, node: usize, mb: u8, f: Frame) {
    b.with_node(node, |_, _, can| {
        can.load(Mailbox(mb), &f);
        None
    });
}

/// Frame length in µs at 1 Mbit/s, without the intermission.
fn body_us(f: &Frame) -> Nanos {
    Nanos::from(exact_bits(f) - 3) * US
}

#[test]
fn lowest_id_wins_and_loser_follows_after_intermission() {
    let mut b = bus(3);
    let hi = frame(0x0080_0100, &[1, 2, 3, 4, 5, 6, 7, 8]);
    let lo = frame(0x0100_0000, &[0xAA; 8]);
    load(&mut b, 0, 0, lo);
    load(&mut b, 1, 0, hi);
    b.run_until(10_000 * US);
    assert_eq!(b.wire.len(), 2);
    assert_eq!((b.wire[0].node, b.wire[0].frame), (1, hi));
    assert_eq!(b.wire[0].sof, 0);
    assert_eq!(b.wire[0].end, body_us(&hi));
    assert_eq!(
        b.wire[1].sof,
        body_us(&hi) + 3 * US,
        "next SOF right after the 3-bit intermission"
    );
    assert_eq!(b.wire[1].end, b.wire[1].sof + body_us(&lo));
    assert_eq!(b.stats.contended, 1);
    // Node 2 receives both, in wire order, with SOF stamps; the senders get Sent.
    let rx2: Vec<u32> = b.module(2).unwrap().rx.iter().map(|r| r.0).collect();
    assert_eq!(rx2, vec![hi.id().raw(), lo.id().raw()]);
    assert_eq!(
        b.module(1).unwrap().done,
        vec![(0, TxResult::Sent, body_us(&hi))]
    );
    // A transmitter does not receive its own frame.
    assert!(b.module(1).unwrap().rx.iter().all(|r| r.0 != hi.id().raw()));
}

#[test]
fn exact_duration_depends_on_stuffing() {
    // All-zero data stuffs heavily, alternating data hardly at all.
    let zeros = frame(0x0000_0000, &[0; 8]);
    let alt = frame(0x0AAA_AAAA, &[0x55; 8]);
    assert!(exact_bits(&zeros) > exact_bits(&alt));
    let mut b = bus(2);
    load(&mut b, 0, 0, zeros);
    b.run_until(1_000 * US);
    assert_eq!(b.wire[0].end - b.wire[0].sof, body_us(&zeros));
    assert_eq!(b.stats.busy_ns, Nanos::from(exact_bits(&zeros)) * US);
}

#[test]
fn mailboxes_go_in_id_order_not_load_order() {
    let mut b = bus(2);
    let f = [frame(0x300, &[3]), frame(0x100, &[1]), frame(0x200, &[2])];
    // Load while the bus is busy with another node's frame so all three wait together.
    load(&mut b, 1, 0, frame(0x50, &[0]));
    for (i, fr) in f.iter().enumerate() {
        load(&mut b, 0, i as u8, *fr);
    }
    b.run_until(2_000 * US);
    let ids: Vec<u32> = b.wire.iter().map(|w| w.frame.id().raw()).collect();
    assert_eq!(ids, vec![0x50, 0x100, 0x200, 0x300]);
}

#[test]
fn a_node_loading_after_the_sof_bit_waits() {
    let mut b = bus(2);
    let first = frame(0x700, &[1]);
    let urgent = frame(0x001, &[2]);
    load(&mut b, 0, 0, first);
    b.run_until(2 * US); // SOF at 0, arbitration decided at 1 µs
    load(&mut b, 1, 0, urgent);
    b.run_until(1_000 * US);
    assert_eq!(b.wire[0].frame, first);
    assert_eq!(b.wire[1].frame, urgent);
}

#[test]
fn abort_of_pending_succeeds_abort_on_wire_completes() {
    let mut b = bus(2);
    let a = frame(0x100, &[1; 8]);
    let c = frame(0x200, &[2; 8]);
    load(&mut b, 0, 0, a);
    load(&mut b, 0, 1, c);
    b.run_until(10 * US); // `a` is on the wire
    b.with_node(0, |_, _, can| {
        can.abort(Mailbox(0));
        can.abort(Mailbox(1));
        None
    });
    b.run_until(1_000 * US);
    assert_eq!(b.wire.len(), 1);
    let done = &b.module(0).unwrap().done;
    assert_eq!(done[0], (1, TxResult::Aborted, 10 * US));
    assert_eq!(done[1], (0, TxResult::Sent, body_us(&a)));
    let st = b.controller(0).unwrap().stats;
    assert_eq!((st.aborted, st.abort_too_late, st.tx_ok), (1, 1, 1));
}

#[test]
fn nart_loser_fails_instead_of_retrying() {
    let mut b = Bus::new(1_000_000, 0.0, 1);
    b.add_node(Probe::default(), NodeSetup::default());
    b.add_node(
        Probe::default(),
        NodeSetup {
            nart: true,
            ..NodeSetup::default()
        },
    );
    load(&mut b, 0, 0, frame(0x10, &[]));
    load(&mut b, 1, 2, frame(0x20, &[]));
    b.run_until(1_000 * US);
    assert_eq!(b.wire.len(), 1);
    assert_eq!(b.module(1).unwrap().done, vec![(2, TxResult::Failed, US)]);
    assert_eq!(b.controller(1).unwrap().stats.tx_failed, 1);
}

#[test]
fn fifo_of_three_overruns_when_the_isr_is_late() {
    let mut b = Bus::new(1_000_000, 0.0, 1);
    b.add_node(Probe::default(), NodeSetup::default());
    // The receiver's ISR runs 1 ms after each event: four frames arrive before it.
    b.add_node(
        Probe::default(),
        NodeSetup {
            irq_latency_ns: 1_000 * US,
            ..NodeSetup::default()
        },
    );
    for (i, raw) in [0x10u32, 0x11, 0x12].iter().enumerate() {
        load(&mut b, 0, i as u8, frame(*raw, &[0; 8]));
    }
    b.run_until(400 * US);
    load(&mut b, 0, 0, frame(0x13, &[0; 8]));
    b.run_until(5_000 * US);
    assert_eq!(b.wire.len(), 4);
    let rx = &b.module(1).unwrap();
    assert_eq!(
        rx.rx.iter().map(|r| r.0).collect::<Vec<_>>(),
        vec![0x10, 0x11, 0x12]
    );
    assert_eq!(rx.overruns, 1);
    assert_eq!(b.controller(1).unwrap().stats.rx_overrun, [1, 0]);
    // The ISR ran at first EOF + latency and read all three.
    let first_end = b.wire[0].end;
    assert!(rx.rx.iter().all(|r| r.2 == first_end + 1_000 * US));
}

#[test]
fn filters_route_to_fifos_and_drop() {
    let f = Filter::Rules(vec![(0xF00, 0x100, 1), (0xF00, 0x200, 0)]);
    assert_eq!(f.fifo_for(0x123), Some(1));
    assert_eq!(f.fifo_for(0x2FF), Some(0));
    assert_eq!(f.fifo_for(0x300), None);
    let mut b = Bus::new(1_000_000, 0.0, 1);
    b.add_node(Probe::default(), NodeSetup::default());
    b.add_node(
        Probe::default(),
        NodeSetup {
            filter: f,
            ..NodeSetup::default()
        },
    );
    load(&mut b, 0, 0, frame(0x300, &[]));
    load(&mut b, 0, 1, frame(0x123, &[]));
    b.run_until(1_000 * US);
    assert_eq!(
        b.module(1)
            .unwrap()
            .rx
            .iter()
            .map(|r| r.0)
            .collect::<Vec<_>>(),
        vec![0x123]
    );
}

#[test]
fn sof_timestamp_is_in_the_receivers_local_clock() {
    let mut b = Bus::new(1_000_000, 0.0, 1);
    b.add_node(Probe::default(), NodeSetup::default());
    let clock = NodeClock::new(5_000, 100.0);
    b.add_node(
        Probe::default(),
        NodeSetup {
            clock,
            irq_latency_ns: 7 * US,
            ..NodeSetup::default()
        },
    );
    b.run_until(1_000_000 * US); // 1 s
    load(&mut b, 0, 0, frame(0x42, &[9]));
    b.run_until(1_001_000 * US);
    let (_, sof, now) = b.module(1).unwrap().rx[0];
    let g_sof = b.wire[0].sof;
    assert_eq!(g_sof, 1_000_000 * US);
    assert_eq!(sof, clock.local(g_sof));
    assert_eq!(sof, 1_000_000 * US + 5_000 + 100 * US);
    assert_eq!(now, clock.local(b.wire[0].end + 7 * US));
}

#[test]
fn bit_errors_destroy_frames_and_retransmit() {
    let mut b = Bus::new(1_000_000, 1e-3, 42);
    b.add_node(Probe::default(), NodeSetup::default());
    b.add_node(Probe::default(), NodeSetup::default());
    let f = frame(0x77, &[0x11; 8]);
    for k in 0..200u64 {
        b.run_until(k * 1_000 * US);
        load(&mut b, 0, 0, f);
    }
    b.run_until(300_000 * US);
    let errors = b.wire.iter().filter(|w| !w.ok).count();
    // ~13 % of 120-bit frames hit at BER 1e-3: expect some, and every frame arrives.
    assert!(errors > 5, "errors {errors}");
    assert_eq!(b.stats.error_frames as usize, errors);
    assert_eq!(b.module(1).unwrap().rx.len(), 200);
    assert_eq!(b.module(0).unwrap().done.len(), 200);
    for w in b.wire.iter().filter(|w| !w.ok) {
        assert!(w.end - w.sof < body_us(&f) + 14 * US);
    }
    // Same seed, same errors.
    let mut b2 = Bus::new(1_000_000, 1e-3, 42);
    b2.add_node(Probe::default(), NodeSetup::default());
    b2.add_node(Probe::default(), NodeSetup::default());
    for k in 0..200u64 {
        b2.run_until(k * 1_000 * US);
        load(&mut b2, 0, 0, f);
    }
    b2.run_until(300_000 * US);
    assert_eq!(b.wire, b2.wire);
}
