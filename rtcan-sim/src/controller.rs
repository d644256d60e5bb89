//! A simulated bxCAN-like controller: three transmit mailboxes sent in identifier
//! priority (lowest raw ID first, then lowest mailbox number), abort of pending mailboxes
//! (a frame already on the wire completes), optional no-automatic-retransmission (NART),
//! two receive FIFOs of depth 3 in FIFO-locked mode (a fourth frame is discarded and
//! counted as an overrun), acceptance filters assigning a FIFO. The bus (`bus.rs`) owns
//! arbitration and timing; this type only holds the controller's state.
use std::collections::VecDeque;

use rtcan_core::driver::{Mailbox, TxResult, MAILBOXES};
use rtcan_core::{Controller, Frame, Nanos};

/// Depth of each receive FIFO (bxCAN: 3).
pub const RX_FIFO_DEPTH: usize = 3;
/// Number of receive FIFOs (bxCAN: 2).
pub const RX_FIFOS: usize = 2;

/// Acceptance filtering: first matching rule wins; no match = frame not received.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Filter {
    /// Every frame to FIFO 0.
    AcceptAll,
    /// `(mask, value, fifo)`: accepted into `fifo` when `raw_id & mask == value`.
    Rules(Vec<(u32, u32, u8)>),
}

impl Filter {
    /// FIFO for a frame with raw identifier `raw`, or `None` if filtered out.
    pub fn fifo_for(&self, raw: u32) -> Option<usize> {
        match self {
            Filter::AcceptAll => Some(0),
            Filter::Rules(rules) => rules
                .iter()
                .find(|(mask, value, _)| raw & mask == *value)
                .map(|&(_, _, fifo)| usize::from(fifo).min(RX_FIFOS - 1)),
        }
    }
}

/// A loaded transmit mailbox.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pending {
    /// The frame.
    pub frame: Frame,
    /// Global time it was loaded.
    pub loaded_at: Nanos,
}

/// Controller counters (what a driver could read from status registers, plus misuse).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ControllerStats {
    /// Frames loaded.
    pub loads: u64,
    /// Loads into a mailbox that was not free (an engine contract violation; ignored).
    pub load_busy: u64,
    /// Aborts that removed a pending frame.
    pub aborted: u64,
    /// Abort requests on a frame already on the wire (it completed).
    pub abort_too_late: u64,
    /// Frames sent and acknowledged.
    pub tx_ok: u64,
    /// Transmissions reported failed (NART: lost arbitration or error).
    pub tx_failed: u64,
    /// Frames that entered a receive FIFO.
    pub rx_frames: u64,
    /// Frames lost to a full FIFO, per FIFO.
    pub rx_overrun: [u64; RX_FIFOS],
}

/// State of one simulated controller.
#[derive(Clone, Debug)]
pub struct SimController {
    /// Global time of the callback in progress (set by the bus before each callback).
    pub(crate) now: Nanos,
    pub(crate) mailboxes: [Option<Pending>; MAILBOXES],
    pub(crate) abort_requested: [bool; MAILBOXES],
    /// Mailbox whose frame is on the wire.
    pub(crate) on_wire: Option<usize>,
    /// Start of frame of each mailbox's last transmission attempt (global time; what
    /// bxCAN's TTCM stamps into TDTR): the sample-age meter reads it at completion.
    pub(crate) tx_sof: [Nanos; MAILBOXES],
    /// Completions produced synchronously (aborts), turned into TX interrupts by the bus.
    pub(crate) reports: Vec<(Mailbox, TxResult)>,
    pub(crate) fifos: [VecDeque<(Frame, Nanos)>; RX_FIFOS],
    pub(crate) rx_irq_pending: [bool; RX_FIFOS],
    /// No automatic retransmission.
    pub nart: bool,
    /// Acceptance filters.
    pub filter: Filter,
    /// Counters.
    pub stats: ControllerStats,
    /// Fault confinement (TEC, REC, bus-off).
    pub conf: crate::confinement::Confinement,
}

impl SimController {
    /// Idle controller.
    pub fn new(nart: bool, filter: Filter) -> Self {
        SimController {
            now: 0,
            mailboxes: [None; MAILBOXES],
            abort_requested: [false; MAILBOXES],
            on_wire: None,
            tx_sof: [0; MAILBOXES],
            reports: Vec::new(),
            fifos: [VecDeque::new(), VecDeque::new()],
            rx_irq_pending: [false; RX_FIFOS],
            nart,
            filter,
            stats: ControllerStats::default(),
            conf: crate::confinement::Confinement::default(),
        }
    }

    /// The mailbox this controller offers to arbitration: lowest raw ID, then lowest
    /// mailbox number (bxCAN with TXFP = 0).
    pub fn best_pending(&self) -> Option<(usize, Pending)> {
        // A plain loop (asked for every node at every arbitration): strict `<` keeps the
        // lowest mailbox number among equal identifiers.
        let mut best: Option<(usize, &Pending)> = None;
        for (i, p) in self.mailboxes.iter().enumerate() {
            if let Some(p) = p {
                if best.is_none_or(|(_, b)| p.frame.id().raw() < b.frame.id().raw()) {
                    best = Some((i, p));
                }
            }
        }
        best.map(|(i, p)| (i, *p))
    }

    /// True when some mailbox holds a frame.
    pub fn has_pending(&self) -> bool {
        self.mailboxes.iter().any(Option::is_some)
    }

    /// Frames waiting in receive FIFO `fifo`.
    pub fn fifo_len(&self, fifo: usize) -> usize {
        self.fifos.get(fifo).map_or(0, VecDeque::len)
    }

    /// Global time of the callback in progress (the module's own `now` is local).
    pub fn global_now(&self) -> Nanos {
        self.now
    }

    /// Start of frame of mailbox `mb`'s last transmission attempt, global time.
    pub fn tx_sof(&self, mb: usize) -> Option<Nanos> {
        self.tx_sof.get(mb).copied()
    }

    /// Pending mailbox `mb`, if loaded.
    pub fn mailbox(&self, mb: usize) -> Option<Pending> {
        self.mailboxes.get(mb).copied().flatten()
    }

    /// Power loss: pending mailboxes and received frames are gone (a frame already on
    /// the wire completes: the bus owns it from its start of frame).
    pub(crate) fn power_off(&mut self) {
        for mb in 0..MAILBOXES {
            if self.on_wire != Some(mb) {
                self.take_mailbox(mb);
            }
        }
        for q in &mut self.fifos {
            q.clear();
        }
    }

    pub(crate) fn take_mailbox(&mut self, mb: usize) -> Option<Pending> {
        if let Some(f) = self.abort_requested.get_mut(mb) {
            *f = false;
        }
        self.mailboxes.get_mut(mb).and_then(Option::take)
    }
}

impl Controller for SimController {
    fn load(&mut self, mailbox: Mailbox, frame: &Frame) {
        let mb = usize::from(mailbox.0);
        match self.mailboxes.get_mut(mb) {
            Some(slot @ None) => {
                *slot = Some(Pending {
                    frame: *frame,
                    loaded_at: self.now,
                });
                self.stats.loads += 1;
                if let Some(f) = self.abort_requested.get_mut(mb) {
                    *f = false;
                }
            }
            _ => self.stats.load_busy += 1,
        }
    }

    fn abort(&mut self, mailbox: Mailbox) {
        let mb = usize::from(mailbox.0);
        if self.on_wire == Some(mb) {
            // bxCAN: ABRQ on a transmitting mailbox only takes effect if it fails.
            if let Some(f) = self.abort_requested.get_mut(mb) {
                *f = true;
            }
            self.stats.abort_too_late += 1;
        } else if self.take_mailbox(mb).is_some() {
            self.stats.aborted += 1;
            self.reports.push((mailbox, TxResult::Aborted));
        }
    }
}
