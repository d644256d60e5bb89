//! What the slot-timer interrupt does at the next wake-up, prepared ahead of time by the
//! protocol task: the frames to load (the sync frame on the master, this module's HRT
//! fragment, window frames), as ready register images, and the mailboxes to abort (window
//! frames that must not run into a reserved slot). The interrupt, at the highest
//! priority, only applies it (`commit`): no engine, no table lookups, no division.
//!
//! Two phases, so that no critical section against the slot timer copies or computes
//! much (issue 10: its longest one is the slot timer's blocking): the protocol task
//! *stages* loads and aborts while it runs the engine for the wake-up (`arm`, then one
//! short section per load: four words and a mask bit), then *publishes* the plan together
//! with the commit compare (`publish`: one store). The interrupt commits only a
//! published plan, so a stale compare flag can never apply a plan still being staged.
use crate::tx_image::{TxImage, TxPort};
use rtcan_core::driver::MAILBOXES;
use rtcan_core::time::Nanos;

/// `state`: loads and aborts are being staged (the interrupt ignores the plan).
const STAGING: u8 = 1;
/// `state`: published with its compare; the interrupt applies it.
const READY: u8 = 2;
/// `state`: bus-off seen by the status-change interrupt; nothing is applied.
const BLOCKED: u8 = 4;

/// The plan of one wake-up (slot boundary or window-close abort).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SlotPlan {
    /// `STAGING` or `READY`, plus `BLOCKED`: one byte, so the interrupt's test is one
    /// compare (`== READY`).
    state: u8,
    /// Bit m: `images[m]` is to be loaded into mailbox m.
    loads: u8,
    /// Bit m: mailbox m is to be aborted.
    aborts: u8,
    at: Nanos,
    images: [TxImage; MAILBOXES],
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
            state: 0,
            loads: 0,
            aborts: 0,
            at: 0,
            images: [TxImage {
                tir: 0,
                tdtr: 0,
                tdlr: 0,
                tdhr: 0,
            }; MAILBOXES],
        }
    }

    /// Starts staging a plan for local time `at` (what an earlier plan held is dropped:
    /// call only when none is armed). The images are not cleared: the masks say which
    /// are valid.
    pub fn arm(&mut self, at: Nanos) {
        self.state = (self.state & BLOCKED) | STAGING;
        self.at = at;
        self.loads = 0;
        self.aborts = 0;
    }

    /// The staged plan goes to the slot timer: from now on its interrupt applies it (call
    /// in the critical section that arms the commit compare). False (and nothing done)
    /// unless a plan was being staged.
    pub fn publish(&mut self) -> bool {
        let staging = self.state & STAGING != 0;
        if staging {
            self.state = (self.state & BLOCKED) | READY;
        }
        staging
    }

    /// True from `arm` to `commit` (or `disarm`): staging or published.
    pub const fn is_armed(&self) -> bool {
        self.state & (STAGING | READY) != 0
    }

    /// True from `publish` to `commit` (or `disarm`).
    pub const fn is_published(&self) -> bool {
        self.state & READY != 0
    }

    /// Local time the plan is for.
    pub const fn at(&self) -> Nanos {
        self.at
    }

    /// Stages a load into `mailbox` (also into a published plan: its commit has not come);
    /// false if no plan is armed (load it now).
    pub fn stage_load(&mut self, mailbox: usize, image: TxImage) -> bool {
        if !self.is_armed() {
            return false;
        }
        match self.images.get_mut(mailbox) {
            Some(slot) => {
                *slot = image;
                self.loads |= 1 << mailbox;
                true
            }
            None => false,
        }
    }

    /// Stages an abort of `mailbox`.
    pub fn stage_abort(&mut self, mailbox: usize) -> StagedAbort {
        if !self.is_armed() || mailbox >= MAILBOXES {
            return StagedAbort::NotArmed;
        }
        let bit = 1 << mailbox;
        if self.loads & bit != 0 {
            self.loads &= !bit;
            StagedAbort::Cancelled
        } else {
            self.aborts |= bit;
            StagedAbort::Deferred
        }
    }

    /// The slot-timer interrupt's work: loads (TXRQ) first, in mailbox order — the
    /// boundary's frame is the latency-critical store —, then the aborts; disarms. False
    /// if no plan was published (or it is blocked). Inline, unrolled: the interrupt's path
    /// to the first TXRQ is a few instructions per mailbox (issue 10's 3 µs goal).
    #[inline(always)]
    pub fn commit(&mut self, port: &mut impl TxPort) -> bool {
        if self.state != READY {
            return false;
        }
        let loads = self.loads;
        let [m0, m1, m2] = &self.images;
        if loads & 0b001 != 0 {
            port.write(0, m0);
        }
        if loads & 0b010 != 0 {
            port.write(1, m1);
        }
        if loads & 0b100 != 0 {
            port.write(2, m2);
        }
        if self.aborts != 0 {
            port.abort(self.aborts);
        }
        self.state = 0;
        true
    }

    /// Bus-off (status-change interrupt): nothing is applied until `unblock`, so a frame
    /// prepared before the bus-off cannot be loaded after the interrupt aborted the
    /// mailboxes (it would go out late after the recovery).
    pub fn block(&mut self) {
        self.state |= BLOCKED;
    }

    /// Transmitting again (recovered and re-synchronised).
    pub fn unblock(&mut self) {
        self.state &= !BLOCKED;
    }

    /// True between `block` and `unblock`.
    pub const fn is_blocked(&self) -> bool {
        self.state & BLOCKED != 0
    }

    /// Drops the plan (bus-off): returns the mask of mailboxes whose staged load never
    /// reached the controller (to be reported aborted).
    pub fn disarm(&mut self) -> u8 {
        let cancelled = self.loads;
        self.state &= BLOCKED;
        self.loads = 0;
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
        assert!(!p.is_published());
        assert_eq!(p.at(), 5_000);
        assert!(p.stage_load(2, img(7)));
        assert_eq!(p.stage_abort(1), StagedAbort::Deferred);
        assert!(!p.stage_load(3, img(9)), "no mailbox 3");
        assert_eq!(p.stage_abort(3), StagedAbort::NotArmed);
        // A compare flag left from an earlier match must not apply a plan being staged.
        assert!(!p.commit(&mut port), "staging: not applied");
        assert!(port.writes.is_empty() && port.aborts.is_empty());
        assert!(p.publish());
        assert!(p.is_published() && p.is_armed());
        // Staged after publishing (a refill before the boundary): still applied with it.
        assert!(p.stage_load(0, img(3)));
        assert!(p.commit(&mut port));
        assert_eq!(port.writes, vec![(0, img(3)), (2, img(7))]);
        assert_eq!(port.aborts, vec![0b010]);
        assert!(!p.is_armed() && !p.is_published());
        assert!(!p.commit(&mut port), "a plan commits once");
        assert_eq!(port.writes.len(), 2);
        // Publishing without staging is a no-op.
        assert!(!p.publish());
        assert!(!p.is_armed());
        assert!(!p.commit(&mut port));
    }

    #[test]
    fn every_mailbox_mask_is_written_in_mailbox_order() {
        for mask in 0u8..8 {
            let mut p = SlotPlan::new();
            let mut port = Log::default();
            p.arm(1);
            // Staged in reverse order: the commit still writes mailbox 0 first.
            for m in (0..3).rev() {
                if mask & (1 << m) != 0 {
                    assert!(p.stage_load(m, img(10 + m as u32)));
                }
            }
            assert!(p.publish());
            assert!(p.commit(&mut port));
            let expect: Vec<(usize, TxImage)> = (0..3)
                .filter(|m| mask & (1 << m) != 0)
                .map(|m| (m, img(10 + m as u32)))
                .collect();
            assert_eq!(port.writes, expect, "mask {mask:03b}");
            assert!(port.aborts.is_empty());
        }
    }

    #[test]
    fn a_blocked_plan_is_not_applied_until_unblocked() {
        let mut p = SlotPlan::new();
        let mut port = Log::default();
        p.arm(1);
        assert!(p.stage_load(0, img(1)));
        assert!(p.publish());
        p.block();
        assert!(!p.commit(&mut port), "blocked: nothing applied");
        assert!(port.writes.is_empty());
        assert!(p.is_armed(), "the plan stays for the protocol task to drop");
        assert_eq!(p.disarm(), 0b001);
        assert!(!p.is_armed() && p.is_blocked());
        p.arm(2);
        assert!(p.stage_load(1, img(2)));
        assert!(p.publish());
        assert!(p.is_blocked(), "arming and publishing keep the block");
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
        p.arm(2);
        assert!(p.publish());
        assert!(p.commit(&mut port));
        assert!(
            port.writes.is_empty() && port.aborts.is_empty(),
            "arm clears"
        );
    }
}
