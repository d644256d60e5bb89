//! Sync-master arbitration (docs/PROTOCOL.md §5.6): which module sends the sync frame.
//!
//! Pure and HAL-free: the engine feeds it what it observed (a foreign sync heard, cycles of
//! silence, a stall of its own) and asks it for its role. `rtcan-core/tests/arbiter_model.rs`
//! model-checks it exhaustively at cycle granularity over small configurations.
//!
//! The sync frame does not say who sent it (its identifier is the cycle counter, §3.1), so
//! the rules use only what every module can observe:
//!
//! 1. **Listen before sending.** A module that was not master a moment ago (start-up of a
//!    backup, a stalled or reset master coming back, a master that yielded) sends a sync
//!    only after `takeover_cycles(rank)` cycles in which it heard none. A running master is
//!    heard within one cycle, so a module coming back defers to it (it becomes a backup of
//!    its rank) and never produces a cycle with two syncs.
//! 2. **Ranks stagger the takeovers.** Rank 0 is the configured master, 1, 2, … the
//!    backups; rank `r` waits `SYNC_LOSS_CYCLES + 2·r` silent cycles, so the best-ranked
//!    live module takes over first and its sync (heard within one cycle) resets the
//!    others' silence 2 cycles before their own takeover.
//! 3. **A master that hears another sync yields.** Two masters can only exist after a
//!    partition heals, after a cold-started master met a running one, or when two
//!    takeovers started from different silences coincide. Every master that hears a
//!    foreign sync stops sending at once and listens (rule 1); if both yielded, rule 2
//!    elects one. Without a sender identity there is no better tie-break, and a symmetric
//!    one is deterministic: the split brain lasts the cycle in which it is detected.

/// Cycles without any sync after which a module stops trusting its slot clock
/// (docs/PROTOCOL.md §5.5) and a rank-0 module takes over.
pub const SYNC_LOSS_CYCLES: u32 = 4;

/// Extra silent cycles per rank: one cycle for the better-ranked module's first sync to be
/// heard, one of margin for clock differences between the modules' cycle timers.
pub const RANK_SPACING_CYCLES: u32 = 2;

/// Cycles of silence after which a module of `rank` takes over.
pub const fn takeover_cycles(rank: u8) -> u32 {
    SYNC_LOSS_CYCLES + RANK_SPACING_CYCLES * rank as u32
}

/// What the module does after an observation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Step {
    /// Master: keeps sending the sync frame.
    Send,
    /// Was master, heard another master's sync: stops sending and listens.
    Yield,
    /// Not master: follows the sync it heard.
    Follow,
    /// Not master, nothing heard yet (or never master-capable).
    Listen,
    /// Not master: silent long enough, sends the sync from the next cycle on.
    TakeOver,
}

/// Arbitration state of one module.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Arbiter {
    /// `None`: a plain slave, never master. `Some(0)`: the configured master.
    rank: Option<u8>,
    master: bool,
    /// Consecutive cycles without a sync heard or sent (only counted while not master).
    silent: u32,
}

impl Arbiter {
    /// The configured master at the robot's power-up: master at once (nobody else can be
    /// master yet: every other master-capable module listens first).
    pub const fn cold_master() -> Self {
        Arbiter {
            rank: Some(0),
            master: true,
            silent: 0,
        }
    }

    /// A module that listens first: a backup (`Some(rank)`, rank >= 1), the configured
    /// master restarting into a bus that may be running (`Some(0)`), or a plain slave
    /// (`None`).
    pub const fn listening(rank: Option<u8>) -> Self {
        Arbiter {
            rank,
            master: false,
            silent: 0,
        }
    }

    /// True while this module sends the sync frame.
    pub const fn is_master(&self) -> bool {
        self.master
    }

    /// Rank (0 = configured master), `None` for a plain slave.
    pub const fn rank(&self) -> Option<u8> {
        self.rank
    }

    /// Silent cycles after which this module takes over; `None` if it never does.
    pub const fn takeover_after(&self) -> Option<u32> {
        match self.rank {
            Some(r) => Some(takeover_cycles(r)),
            None => None,
        }
    }

    /// A valid sync frame sent by another module was heard.
    pub fn foreign_sync(&mut self) -> Step {
        self.silent = 0;
        if self.master {
            self.master = false;
            Step::Yield
        } else {
            Step::Follow
        }
    }

    /// This module has heard no sync for `cycles` consecutive cycles (not counting ones it
    /// sent): takes over once `cycles` reaches `takeover_after()`.
    pub fn silence(&mut self, cycles: u32) -> Step {
        if self.master {
            return Step::Send;
        }
        self.silent = cycles;
        match self.takeover_after() {
            Some(n) if cycles >= n => {
                self.master = true;
                self.silent = 0;
                Step::TakeOver
            }
            _ => Step::Listen,
        }
    }

    /// One more cycle without a sync heard (`silence` with the count kept here).
    pub fn silent_cycle(&mut self) -> Step {
        let cycles = self.silent.saturating_add(1);
        self.silence(cycles)
    }

    /// The module could not act for at least a cycle (stalled, partitioned, bus-off): its
    /// view of the bus is stale, so a master stops sending and listens again (rule 1).
    pub fn stalled(&mut self) {
        self.master = false;
        self.silent = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn takeover_counts_silent_cycles_by_rank() {
        assert_eq!(takeover_cycles(0), 4);
        assert_eq!(takeover_cycles(2), 8);
        let mut b = Arbiter::listening(Some(1));
        for _ in 0..5 {
            assert_eq!(b.silent_cycle(), Step::Listen);
        }
        assert_eq!(b.silent_cycle(), Step::TakeOver);
        assert!(b.is_master());
        assert_eq!(b.silent_cycle(), Step::Send);
        assert_eq!(b.foreign_sync(), Step::Yield);
        assert!(!b.is_master());
        // Heard syncs reset the silence.
        for _ in 0..5 {
            b.silent_cycle();
        }
        assert_eq!(b.foreign_sync(), Step::Follow);
        assert_eq!(b.silent_cycle(), Step::Listen);
    }

    #[test]
    fn plain_slave_never_takes_over_and_stall_demotes() {
        let mut s = Arbiter::listening(None);
        assert_eq!(s.silence(u32::MAX), Step::Listen);
        assert!(!s.is_master());
        let mut m = Arbiter::cold_master();
        assert!(m.is_master());
        m.stalled();
        assert!(!m.is_master());
        assert_eq!(m.silence(3), Step::Listen);
        assert_eq!(m.silence(4), Step::TakeOver);
    }
}
