//! Nodes driven from outside the bus (rtcan-emu's emulated STM32F103s): their controller
//! is a register model with its own mailboxes and FIFOs, run instruction by instruction by
//! a co-simulation loop, not a `Module` reacting to events. The loop steps the emulated
//! CPUs up to each bus decision, hands the bus what each controller offers
//! (`set_offer`), lets the bus arbitrate and time the frame, and reads what happens on
//! the wire (`activity`, `takes_frame`) to deliver the frame to the emulated receivers at
//! their own receive point. Arbitration, frame lengths, error frames, fault confinement
//! and the bus faults (`set_stuck`, `set_partitioned`, bit errors) stay this bus's.
//!
//! Nothing here changes what the bus does for `Module` nodes: these are read accessors
//! and one setter of a node's mailboxes.
use rtcan_core::driver::MAILBOXES;
use rtcan_core::{Frame, Nanos};

use super::{key_time, Bus, Ev, Module, State};
use crate::controller::Pending;

/// The frame on the wire, as the arbitration decided it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OnWire {
    /// Transmitting node and its mailbox.
    pub node: usize,
    pub mailbox: usize,
    pub frame: Frame,
    /// Start of frame, global ns.
    pub sof: Nanos,
    /// End of EOF, or of the error delimiter if the frame is destroyed, global ns.
    pub end: Nanos,
    /// The receivers take the frame (no bit error, the bus not held dominant); receivers
    /// that see an error of their own in EOF are `takes_frame`'s business.
    pub ok: bool,
}

/// What the bus is doing now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Activity {
    /// Idle; a frame may start from `from` (the end of the last intermission) on.
    Idle { from: Nanos },
    /// A start of frame at `sof`; the bus decides the arbitration one bit later.
    Arbitrating { sof: Nanos },
    /// A frame on the wire.
    Busy(OnWire),
}

impl<M: Module> Bus<M> {
    /// What the bus is doing now.
    pub fn activity(&self) -> Activity {
        match self.state {
            State::Idle { from } => Activity::Idle { from },
            State::Arbitrating { sof } => Activity::Arbitrating { sof },
            State::Busy {
                node,
                mb,
                sof,
                frame,
                ok,
                ..
            } => {
                let end = match self.bus_ev {
                    Some((k, Ev::FrameEnd)) => key_time(k),
                    _ => self.now,
                };
                Activity::Busy(OnWire {
                    node,
                    mailbox: mb,
                    frame,
                    sof,
                    end,
                    ok,
                })
            }
        }
    }

    /// The node whose transceiver holds the bus dominant (`set_stuck`), if any.
    pub fn stuck_node(&self) -> Option<usize> {
        self.stuck
    }

    /// Global time of the next scheduled event (bus or node), if any.
    pub fn next_event_at(&self) -> Option<Nanos> {
        self.next_event().map(|(k, _)| key_time(k))
    }

    /// Node `n` will take the frame on the wire when it ends: it is a receiver, the
    /// frame is good, `n` saw no error of its own in EOF, is not bus-off and not cut off
    /// (the conditions `frame_end` applies before its acceptance filter).
    pub fn takes_frame(&self, n: usize) -> bool {
        let State::Busy {
            node: tx,
            ok,
            rejects,
            ..
        } = self.state
        else {
            return false;
        };
        let rejected = n < 64 && rejects & (1u64 << n) != 0;
        n != tx
            && ok
            && !rejected
            && self
                .nodes
                .get(n)
                .is_some_and(|node| !node.partitioned && !node.can.conf.is_bus_off())
    }

    /// The controller of node `i` (driven from outside) offers `offer` = (mailbox, frame)
    /// from now, or nothing: its mailboxes become exactly that, except the one whose frame
    /// is on the wire (the bus owns it until its end). No completion is reported for a
    /// mailbox emptied this way: the outside controller knows why it withdrew it. An
    /// idle bus starts a frame as for a `Controller::load`.
    pub fn set_offer(&mut self, i: usize, offer: Option<(usize, Frame)>) {
        let now = self.now;
        let Some(node) = self.nodes.get_mut(i) else {
            return;
        };
        node.can.now = now;
        for mb in 0..MAILBOXES {
            if node.can.on_wire == Some(mb) {
                continue;
            }
            let want = offer.and_then(|(m, f)| (m == mb).then_some(f));
            let have = node.can.mailbox(mb);
            match (have, want) {
                (Some(p), Some(f)) if p.frame == f => {}
                (_, Some(frame)) => {
                    if let Some(slot) = node.can.mailboxes.get_mut(mb) {
                        *slot = Some(Pending {
                            frame,
                            loaded_at: now,
                        });
                    }
                    node.can.stats.loads += 1;
                }
                (Some(_), None) => {
                    node.can.take_mailbox(mb);
                }
                (None, None) => {}
            }
        }
        self.maybe_start_arbitration();
    }

    /// The offers of the last arbitration: (raw identifier, node, mailbox).
    pub fn arbitration_offers(&self) -> &[(u32, usize, usize)] {
        &self.offers
    }

    /// Node `i`'s controller is reset with its MCU (power-on values, RM0008 §24.9.2):
    /// pending mailboxes and received frames gone, error counters back to 0 (a frame
    /// already on the wire completes, as for a power loss).
    pub fn reset_controller(&mut self, i: usize) {
        if let Some(node) = self.nodes.get_mut(i) {
            node.can.power_off();
            node.can.conf.reset();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bus::NodeSetup;
    use crate::controller::{Filter, SimController};
    use rtcan_core::driver::{Mailbox, TxResult};
    use rtcan_core::id::CanId;
    use rtcan_core::timing::{bits_to_ns, exact_bits, INTERMISSION_BITS};

    /// A node whose controller is driven from outside: it reacts to nothing.
    struct Outside;
    impl Module for Outside {
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
            _: Mailbox,
            _: TxResult,
            _: Nanos,
            _: &mut SimController,
        ) -> Option<Nanos> {
            None
        }
        fn rx_overrun(&mut self, _: Nanos) {}
    }

    fn frame(raw: u32) -> Frame {
        Frame::new(CanId::from_raw(raw).unwrap(), &[1, 2, 3]).unwrap()
    }

    fn bus(n: usize) -> Bus<Outside> {
        let mut b = Bus::new(1_000_000, 0.0, 1);
        for _ in 0..n {
            b.add_node(
                Outside,
                NodeSetup {
                    filter: Filter::Rules(Vec::new()),
                    ..NodeSetup::default()
                },
            );
        }
        b.run_until(0);
        b
    }

    #[test]
    fn offers_arbitrate_and_time_the_frame_exactly() {
        let mut b = bus(3);
        b.run_until(5_000);
        assert_eq!(b.activity(), Activity::Idle { from: 0 });
        b.set_offer(1, Some((2, frame(0x300))));
        b.set_offer(2, Some((0, frame(0x200))));
        // The start of frame now; the decision one bit later.
        assert_eq!(b.activity(), Activity::Arbitrating { sof: 5_000 });
        assert_eq!(b.next_event_at(), Some(6_000));
        b.run_until(6_000);
        let body = exact_bits(&frame(0x200)) - INTERMISSION_BITS;
        let end = 5_000 + bits_to_ns(body, 1_000_000);
        let Activity::Busy(w) = b.activity() else {
            panic!("no frame on the wire: {:?}", b.activity());
        };
        assert_eq!(
            w,
            OnWire {
                node: 2,
                mailbox: 0,
                frame: frame(0x200),
                sof: 5_000,
                end,
                ok: true
            }
        );
        assert_eq!(b.arbitration_offers(), &[(0x300, 1, 2), (0x200, 2, 0)][..]);
        // Receivers: everyone but the transmitter; no filter or FIFO of the bus's.
        assert_eq!(
            (0..3).map(|n| b.takes_frame(n)).collect::<Vec<_>>(),
            vec![true, true, false]
        );
        // The loser withdraws; the winner's mailbox stays the bus's until the end.
        b.set_offer(1, None);
        b.set_offer(2, None);
        assert!(b.controller(2).unwrap().mailbox(0).is_some());
        assert!(!b.controller(1).unwrap().has_pending());
        b.run_until(end);
        assert_eq!(b.wire.len(), 1);
        assert_eq!(b.wire[0].end, end);
        assert!(b.wire[0].ok);
        assert_eq!(
            b.activity(),
            Activity::Idle {
                from: end + bits_to_ns(INTERMISSION_BITS, 1_000_000)
            }
        );
        assert!(!b.controller(2).unwrap().has_pending());
        assert_eq!(b.controller(2).unwrap().conf.state().tec, 0);
    }

    #[test]
    fn a_bus_held_dominant_destroys_the_frame_and_takes_the_sender_bus_off() {
        let mut b = bus(2);
        b.set_offer(0, Some((0, frame(0x400))));
        b.run_until(1_000);
        assert!(b.takes_frame(1));
        b.set_stuck(0, true);
        assert_eq!(b.stuck_node(), Some(0));
        let Activity::Busy(w) = b.activity() else {
            panic!("no frame");
        };
        assert!(!w.ok);
        assert!(!b.takes_frame(1));
        assert!(b.controller(0).unwrap().conf.is_bus_off());
        assert_eq!(b.controller(1).unwrap().conf.state().rec, 255);
        // A controller reset with its MCU: counters back to power-on values, the frame
        // on the wire still the bus's.
        b.reset_controller(0);
        let c = b.controller(0).unwrap();
        assert_eq!(
            c.conf.state(),
            rtcan_core::confinement::ErrorState::default()
        );
        assert_eq!(c.conf.bus_off_entries, 1);
        assert!(c.mailbox(0).is_some());
    }
}
