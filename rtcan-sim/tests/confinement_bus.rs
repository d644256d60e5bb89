//! Fault confinement on the simulated bus: a transmitter whose frames keep failing goes
//! error-passive after 16 errors and bus-off after 32 (TEC 256 > 255), stops sending,
//! and comes back after 128 runs of 11 recessive bits — on an idle bus 1408 bit times,
//! on a busy one 128 frames later. Receivers count too, and every level change reaches
//! the module (`Module::error_state`).
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]
use rtcan_core::confinement::{ErrorState, Level};
use rtcan_core::driver::{Mailbox, TxResult};
use rtcan_core::{CanId, Controller, Frame, Nanos};
use rtcan_sim::bus::{Bus, Module, NodeSetup};
use rtcan_sim::SimController;

/// Records the error states reported; reloads its frame after each success if `flood`.
#[derive(Default)]
struct Probe {
    states: Vec<(ErrorState, Nanos)>,
    flood: Option<Frame>,
    sent: u32,
}

impl Module for Probe {
    fn start(&mut self, _: Nanos, _: &mut SimController) -> Option<Nanos> {
        None
    }
    fn wake(&mut self, _: Nanos, _: &mut SimController) -> Option<Nanos> {
        None
    }
    fn rx(&mut self, _: &Frame, _: Nanos, _: Nanos, _: &mut SimController) -> Option<Nanos> {
        None
    }
    fn tx_done(
        &mut self,
        mb: Mailbox,
        r: TxResult,
        _: Nanos,
        can: &mut SimController,
    ) -> Option<Nanos> {
        if r == TxResult::Sent {
            self.sent += 1;
            if let Some(f) = self.flood {
                can.load(mb, &f);
            }
        }
        None
    }
    fn rx_overrun(&mut self, _: Nanos) {}
    fn error_state(&mut self, now: Nanos, s: ErrorState, _: &mut SimController) -> Option<Nanos> {
        self.states.push((s, now));
        None
    }
}

fn frame(raw: u32) -> Frame {
    Frame::new(CanId::from_raw(raw).unwrap(), &[0x55; 8]).unwrap()
}

/// Node 0's frame fails 32 times in a row (BER 0.5: a frame survives with 2^-100).
fn bus_off_node_0() -> Bus<Probe> {
    let mut b = Bus::new(1_000_000, 0.5, 7);
    for _ in 0..3 {
        b.add_node(Probe::default(), NodeSetup::default());
    }
    b.with_node(0, |_, _, can| {
        can.load(Mailbox(0), &frame(0x0100_0000));
        None
    });
    // Step to the bus-off (at most 32 error frames of < 130 bits).
    let mut t = 0;
    while !b.controller(0).unwrap().conf.is_bus_off() && t < 20_000_000 {
        t += 10_000;
        b.run_until(t);
    }
    b
}

#[test]
fn passive_after_16_errors_bus_off_after_32_and_silent() {
    let mut b = bus_off_node_0();
    // Silent from the bus-off on, for 1 ms (it recovers after 1.408 ms).
    b.run_until(b.wire[31].end + 1_000_000);
    assert_eq!(b.stats.error_frames, 32);
    assert_eq!(b.wire.len(), 32);
    assert!(b.wire.iter().all(|w| w.node == 0 && !w.ok));
    let c0 = b.controller(0).unwrap();
    assert!(c0.conf.is_bus_off());
    assert_eq!(c0.conf.bus_off_entries, 1);
    assert_eq!(c0.conf.state().tec, 256);
    // The 16th error made it passive (TEC 128), the 32nd bus-off; reported in order.
    let p = b.module(0).unwrap();
    let levels: Vec<Level> = p.states.iter().map(|s| s.0.level()).collect();
    assert_eq!(levels, [Level::Passive, Level::BusOff]);
    assert_eq!(p.states[0].0.tec, 128);
    assert!(p.states[0].1 >= b.wire[15].end && p.states[0].1 < b.wire[16].end);
    assert!(p.states[1].1 >= b.wire[31].end);
    // Receivers saw 32 errors: REC 32, still active, nothing reported.
    for n in 1..3 {
        let c = b.controller(n).unwrap();
        assert_eq!(
            c.conf.state(),
            ErrorState {
                tec: 0,
                rec: 32,
                bus_off: false
            }
        );
        assert!(b.module(n).unwrap().states.is_empty());
    }
    // Its frame stays loaded (the engine withdraws it on the bus-off report).
    assert!(c0.has_pending());
    // Left alone in the noise it cycles: 32 errors, bus-off, 1408 bits, again.
    b.run_until(20_000_000);
    let c0 = b.controller(0).unwrap();
    assert!(c0.conf.bus_off_entries >= 4);
    assert_eq!(
        b.stats.error_frames,
        // Completed cycles, plus the errors of the one under way (TEC 8 per error).
        32 * u64::from(c0.conf.bus_off_entries - u32::from(c0.conf.is_bus_off()))
            + u64::from(c0.conf.state().tec / 8)
    );
}

#[test]
fn recovery_on_an_idle_bus_after_1408_bits() {
    let mut b = bus_off_node_0();
    b.set_bit_error_rate(0.0);
    let off_at = b.wire[31].end;
    b.run_until(20_000_000);
    // Nobody else sends: the error frame's 11 trailing recessive bits (3 of them the
    // intermission after `end`) and 1397 idle bits.
    let p = b.module(0).unwrap();
    let back = p.states.last().unwrap();
    assert_eq!(back.0, ErrorState::default());
    assert_eq!(back.1, off_at + 3_000 + 1397 * 1_000);
    // Recovered, its waiting frame goes out right away.
    let last = b.wire.last().unwrap();
    assert!(last.ok && last.node == 0 && last.sof == back.1);
}

#[test]
fn a_start_of_frame_counts_the_idle_run_and_the_rest_completes_idle() {
    let mut b = bus_off_node_0();
    b.set_bit_error_rate(0.0);
    b.with_node(0, |_, _, can| {
        can.abort(Mailbox(0));
        None
    });
    let off_at = b.wire[31].end;
    // Node 1 sends 500 us after the bus-off: its start of frame ends a run of
    // 11 + 497 bits = 46 runs; after its frame 82 more runs are due on the idle bus.
    b.run_until(off_at + 500_000);
    b.with_node(1, |_, _, can| {
        can.load(Mailbox(0), &frame(0x0200_0000));
        None
    });
    b.run_until(40_000_000);
    let c0 = b.controller(0).unwrap();
    assert_eq!(c0.conf.state(), ErrorState::default());
    // Off the bus while node 1's frame passed: not received.
    assert_eq!(c0.stats.rx_frames, 0);
    let f1 = b.wire.last().unwrap();
    assert_eq!(f1.node, 1);
    let back = b.module(0).unwrap().states.last().unwrap().1;
    assert_eq!(back, f1.end + 3_000 + (82 * 11 - 11) * 1_000);
}

#[test]
fn recovery_on_a_busy_bus_takes_128_frames() {
    let mut b = bus_off_node_0();
    b.set_bit_error_rate(0.0);
    let f = frame(0x0200_0000);
    b.module_mut(1).unwrap().flood = Some(f);
    b.with_node(1, |_, _, can| {
        can.load(Mailbox(0), &f);
        None
    });
    b.run_until(60_000_000);
    let p = b.module(0).unwrap();
    let back = p.states.last().unwrap();
    assert_eq!(back.0, ErrorState::default());
    // Node 0's own frame was waiting: after recovery it competes again and, with the
    // lower identifier, goes out right after the 128th frame of node 1.
    let ok: Vec<_> = b.wire.iter().filter(|w| w.ok).collect();
    assert_eq!(ok[..128].iter().filter(|w| w.node == 1).count(), 128);
    assert_eq!(back.1, ok[127].sof + 1_000);
    assert_eq!(ok[128].node, 0);
}
