//! One node's controller on the software bus: three mailboxes like bxCAN, abortable
//! while they wait for arbitration (a frame on the wire cannot be aborted and completes
//! as sent), and acceptance filters like bxCAN's banks (a module's generated `FILTERS`),
//! so the engine only sees the frames the hardware would pass it.
use rtcan_core::driver::{Controller, Mailbox, TxResult, MAILBOXES};
use rtcan_core::frame::Frame;

/// Software CAN controller.
#[derive(Clone, Copy, Debug, Default)]
pub struct SoftCan {
    pending: [Option<Frame>; MAILBOXES],
    /// Mailbox whose frame is on the wire.
    on_wire: Option<usize>,
    completions: [Option<TxResult>; MAILBOXES],
    /// Frames loaded so far.
    pub loads: u32,
    /// Abort requests so far.
    pub aborts: u32,
    /// Acceptance filters as `(id, mask)` pairs; `None` accepts every frame.
    filters: Option<&'static [(u32, u32)]>,
    /// Frames the filters rejected.
    pub rejected: u32,
}

impl SoftCan {
    /// Empty mailboxes, accepting every frame.
    pub const fn new() -> Self {
        SoftCan {
            pending: [None; MAILBOXES],
            on_wire: None,
            completions: [None; MAILBOXES],
            loads: 0,
            aborts: 0,
            filters: None,
            rejected: 0,
        }
    }
    /// Empty mailboxes, accepting what one of `filters` (29-bit `(id, mask)` pairs, a
    /// module's generated `FILTERS`) passes.
    pub const fn with_filters(filters: &'static [(u32, u32)]) -> Self {
        let mut c = Self::new();
        c.filters = Some(filters);
        c
    }
    /// Whether the filters pass the 29-bit identifier `raw`; counts the rejected ones.
    pub fn accepts(&mut self, raw: u32) -> bool {
        let pass = self.filters.is_none_or(|f| rtcan::filters_pass(f, raw));
        if !pass {
            self.rejected = self.rejected.wrapping_add(1);
        }
        pass
    }
    /// The highest-priority (lowest ID) frame waiting for arbitration, and its mailbox;
    /// equal IDs go in mailbox order, like bxCAN with TXFP = 0.
    pub fn best(&self) -> Option<(usize, Frame)> {
        let mut best: Option<(usize, Frame)> = None;
        for (m, f) in self.pending.iter().enumerate() {
            if self.on_wire == Some(m) {
                continue;
            }
            if let Some(f) = f {
                if best.is_none_or(|(_, b)| f.id().raw() < b.id().raw()) {
                    best = Some((m, *f));
                }
            }
        }
        best
    }
    /// Mailbox `m` won arbitration.
    pub fn start(&mut self, m: usize) {
        self.on_wire = Some(m);
    }
    /// The frame on the wire finished: the mailbox is free and completes as sent.
    pub fn finish(&mut self) {
        if let Some(m) = self.on_wire.take() {
            if let Some(p) = self.pending.get_mut(m) {
                *p = None;
            }
            if let Some(c) = self.completions.get_mut(m) {
                *c = Some(TxResult::Sent);
            }
        }
    }
    /// The next completion to report to the engine.
    pub fn take_completion(&mut self) -> Option<(Mailbox, TxResult)> {
        self.completions
            .iter_mut()
            .enumerate()
            .find_map(|(m, c)| c.take().map(|r| (Mailbox(m as u8), r)))
    }
    /// True if any mailbox is loaded.
    pub fn busy(&self) -> bool {
        self.pending.iter().any(Option::is_some)
    }
}

impl Controller for SoftCan {
    fn load(&mut self, mailbox: Mailbox, frame: &Frame) {
        if let Some(p) = self.pending.get_mut(mailbox.0 as usize) {
            *p = Some(*frame);
            self.loads = self.loads.wrapping_add(1);
        }
    }
    fn abort(&mut self, mailbox: Mailbox) {
        let m = mailbox.0 as usize;
        self.aborts = self.aborts.wrapping_add(1);
        if self.on_wire == Some(m) {
            return; // already transmitting: completes as sent
        }
        if let (Some(p), Some(c)) = (self.pending.get_mut(m), self.completions.get_mut(m)) {
            if p.take().is_some() {
                *c = Some(TxResult::Aborted);
            }
        }
    }
}
