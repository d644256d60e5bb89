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
