//! What the slot-timer interrupt does at the next wake-up, prepared ahead of time by the
//! protocol task: the frames to load (the sync frame on the master, this module's HRT
//! fragment, window frames), as ready register images, and the mailboxes to abort (window
//! frames that must not run into a reserved slot). The interrupt, at the highest
//! priority, only applies it (`commit`): no engine, no table lookups, no division.
use crate::tx_image::{TxImage, TxPort};
use rtcan_core::driver::MAILBOXES;
use rtcan_core::time::Nanos;

/// The plan of one wake-up (slot boundary or window-close abort).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SlotPlan {
    armed: bool,
    /// Set by the status-change interrupt at bus-off, before the protocol task has seen
    /// it: the plan stays but is not applied (the protocol task then drops it).
    blocked: bool,
    at: Nanos,
    loads: [Option<TxImage>; MAILBOXES],
    aborts: u8,
}

/// What a staged abort did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StagedAbort {
    /// The mailbox's load was still staged: it is dropped, nothing reached the
    /// controller; the caller reports the mailbox as aborted to the engine.
    Cancelled,
    /// The abort is applied with the plan.
    Deferred,
    /// No plan is armed: abort now.
    NotArmed,
}

impl SlotPlan {
    /// Nothing armed.
    pub const fn new() -> Self {
        SlotPlan {
            armed: false,
            blocked: false,
            at: 0,
            loads: [None; MAILBOXES],
            aborts: 0,
        }
    }

    /// Starts a plan for local time `at` (what an earlier plan held is dropped: call only
    /// when none is armed).
    pub fn arm(&mut self, at: Nanos) {
        // Field by field: this runs in a critical section against the slot timer.
        self.armed = true;
        self.at = at;
        for load in self.loads.iter_mut() {
            *load = None;
        }
        self.aborts = 0;
    }

    /// True from `arm` to `commit` (or `disarm`).
    pub const fn is_armed(&self) -> bool {
        self.armed
    }

    /// Local time the plan is for.
    pub const fn at(&self) -> Nanos {
        self.at
    }

    /// Stages a load into `mailbox`; false if no plan is armed (load it now).
    pub fn stage_load(&mut self, mailbox: usize, image: TxImage) -> bool {
        match self.loads.get_mut(mailbox) {
            Some(slot) if self.armed => {
                *slot = Some(image);
                true
            }
            _ => false,
        }
    }

    /// Stages an abort of `mailbox`.
    pub fn stage_abort(&mut self, mailbox: usize) -> StagedAbort {
        if !self.armed {
            return StagedAbort::NotArmed;
        }
        match self.loads.get_mut(mailbox) {
            Some(slot @ Some(_)) => {
                *slot = None;
                StagedAbort::Cancelled
            }
            Some(None) => {
                self.aborts |= 1 << mailbox;
                StagedAbort::Deferred
            }
            None => StagedAbort::NotArmed,
        }
    }

    /// The slot-timer interrupt's work: loads (TXRQ) first — the boundary's frame is the
    /// latency-critical store —, then the aborts; disarms. False if nothing was armed.
    pub fn commit(&mut self, port: &mut impl TxPort) -> bool {
        if !self.armed || self.blocked {
            return false;
        }
        for (m, load) in self.loads.iter().enumerate() {
            if let Some(image) = load {
                port.write(m, image);
            }
        }
        if self.aborts != 0 {
            port.abort(self.aborts);
        }
        self.armed = false;
        true
    }

    /// Bus-off (status-change interrupt): nothing is applied until `unblock`, so a frame
    /// prepared before the bus-off cannot be loaded after the interrupt aborted the
    /// mailboxes (it would go out late after the recovery).
    pub fn block(&mut self) {
        self.blocked = true;
    }

    /// Transmitting again (recovered and re-synchronised).
    pub fn unblock(&mut self) {
        self.blocked = false;
    }

    /// True between `block` and `unblock`.
    pub const fn is_blocked(&self) -> bool {
        self.blocked
    }

    /// Drops the plan (bus-off): returns the mask of mailboxes whose staged load never
    /// reached the controller (to be reported aborted).
    pub fn disarm(&mut self) -> u8 {
        let mut cancelled = 0;
        for (m, load) in self.loads.iter_mut().enumerate() {
            if load.take().is_some() {
                cancelled |= 1 << m;
            }
        }
        self.armed = false;
        self.aborts = 0;
        cancelled
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Default)]
    struct Log {
        writes: Vec<(usize, TxImage)>,
        aborts: Vec<u8>,
    }
    impl TxPort for Log {
        fn write(&mut self, mailbox: usize, image: &TxImage) {
            self.writes.push((mailbox, *image));
        }
        fn abort(&mut self, mask: u8) {
            self.aborts.push(mask);
        }
        fn is_bus_off(&self) -> bool {
            false
        }
    }

    fn img(n: u32) -> TxImage {
        TxImage {
            tir: n,
            ..TxImage::default()
        }
    }

    #[test]
    fn staged_work_reaches_the_port_only_at_commit_loads_first() {
        let mut p = SlotPlan::new();
        let mut port = Log::default();
        assert!(!p.stage_load(0, img(1)), "nothing armed: load directly");
        assert_eq!(p.stage_abort(0), StagedAbort::NotArmed);
        assert!(!p.commit(&mut port));
        p.arm(5_000);
        assert!(p.is_armed());
        assert_eq!(p.at(), 5_000);
        assert!(p.stage_load(2, img(7)));
        assert_eq!(p.stage_abort(1), StagedAbort::Deferred);
        assert!(!p.stage_load(3, img(9)), "no mailbox 3");
        assert!(port.writes.is_empty() && port.aborts.is_empty());
        assert!(p.commit(&mut port));
        assert_eq!(port.writes, vec![(2, img(7))]);
        assert_eq!(port.aborts, vec![0b010]);
        assert!(!p.is_armed());
        assert!(!p.commit(&mut port), "a plan commits once");
        assert_eq!(port.writes.len(), 1);
    }

    #[test]
    fn a_blocked_plan_is_not_applied_until_unblocked() {
        let mut p = SlotPlan::new();
        let mut port = Log::default();
        p.arm(1);
        assert!(p.stage_load(0, img(1)));
        p.block();
        assert!(!p.commit(&mut port), "blocked: nothing applied");
        assert!(port.writes.is_empty());
        assert!(p.is_armed(), "the plan stays for the protocol task to drop");
        assert_eq!(p.disarm(), 0b001);
        p.arm(2);
        assert!(p.stage_load(1, img(2)));
        assert!(p.is_blocked(), "arming keeps the block");
        assert!(!p.commit(&mut port));
        p.unblock();
        assert!(p.commit(&mut port));
        assert_eq!(port.writes, vec![(1, img(2))]);
    }

    #[test]
    fn aborting_a_staged_load_cancels_it_and_disarm_reports_the_rest() {
        let mut p = SlotPlan::new();
        let mut port = Log::default();
        p.arm(1);
        assert!(p.stage_load(0, img(1)));
        assert!(p.stage_load(1, img(2)));
        assert_eq!(p.stage_abort(0), StagedAbort::Cancelled);
        assert_eq!(p.disarm(), 0b010);
        assert!(!p.commit(&mut port));
        assert!(port.writes.is_empty());
        p.arm(2);
        assert!(p.commit(&mut port));
        assert!(
            port.writes.is_empty() && port.aborts.is_empty(),
            "arm clears"
        );
    }
}
