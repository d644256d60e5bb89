#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! Exhaustive model check of the sync-master arbitration (`rtcan_core::arbiter`,
//! docs/PROTOCOL.md §5.6) at cycle granularity.
//!
//! World: three master-capable modules, ranks 0 (the configured master), 1 and 2. In every
//! cycle each live master sends one sync frame and every other live module hears it. When
//! two or more masters send in one cycle, the order on the wire decides who hears whom
//! first: any master may be the one that heard nothing before it yielded the bus, so the
//! checker branches over "all senders yield" and "all but sender k yield" for every k.
//! Events, at most `MAX_EVENTS` of them in the first `EVENT_CYCLES` cycles, any number in
//! one cycle: a live module fails; a dead one returns resumed (its state, stale: the
//! engine's stall rule), reset and listening, or (rank 0 only) reset as a cold-started
//! master that sends at once. Every interleaving is enumerated (memoised on the full state).
//!
//! Checked in every reachable state:
//! - a split brain (a cycle with two or more syncs) lasts at most 2 consecutive cycles;
//! - a running master is never joined by a module that listens first (only a cold start
//!   can add a second sync to a cycle that follows a single-sync cycle);
//! - while no event happens and some module is alive, a cycle without sync is followed by
//!   a sync within `takeover_cycles(2)` cycles;
//! - `CONVERGE` cycles after the last event, every cycle has exactly one sync, always from
//!   the same module, whenever any module is alive.
use rtcan_core::arbiter::{takeover_cycles, Arbiter, Step};
use std::collections::HashSet;

const N: usize = 3;
const MAX_EVENTS: u8 = 3;
const EVENT_CYCLES: u32 = 14;
const HORIZON: u32 = EVENT_CYCLES + 40;
/// Worst case after the last event: a pending takeover of the worst rank, a split brain it
/// collides into, and the re-election after it.
const CONVERGE: u32 = 2 * (takeover_cycles(2) + 1) + 1;
/// Longest run of sync-less cycles without an event while a module is alive.
const MAX_GAP: u32 = takeover_cycles(2);

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct Node {
    alive: bool,
    arb: Arbiter,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Ev {
    Fail,
    Resume,
    ResetListening,
    ResetCold,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
struct State {
    cycle: u32,
    nodes: [Node; N],
    events_left: u8,
    /// Consecutive cycles with >= 2 syncs.
    split_run: u32,
    /// Consecutive sync-less cycles with a live module, since the last event.
    gap_run: u32,
    /// Cycle of the last event (0 if none).
    last_event: u32,
    /// Senders of the previous cycle (bitmask).
    prev_senders: u8,
    /// A cold-started master joined in this cycle (bitmask of such nodes).
    cold: u8,
}

fn fresh(rank: usize, ev: Ev) -> Arbiter {
    match ev {
        Ev::ResetCold => Arbiter::cold_master(),
        _ => Arbiter::listening(Some(rank as u8)),
    }
}

struct Checker {
    seen: HashSet<State>,
    states: u64,
    split_cycles: u64,
    converged_runs: u64,
}

impl Checker {
    fn explore(&mut self, s: State, path: &mut Vec<String>) {
        if s.cycle >= HORIZON {
            self.converged_runs += 1;
            return;
        }
        if !self.seen.insert(s.clone()) {
            return;
        }
        self.states += 1;
        // 1. Events of this cycle: every subset of nodes, every applicable event kind.
        let mut choices: Vec<Vec<Option<Ev>>> = Vec::new();
        for (i, n) in s.nodes.iter().enumerate() {
            let mut c = vec![None];
            if s.cycle < EVENT_CYCLES && s.events_left > 0 {
                if n.alive {
                    c.push(Some(Ev::Fail));
                } else {
                    c.push(Some(Ev::Resume));
                    c.push(Some(Ev::ResetListening));
                    if i == 0 {
                        c.push(Some(Ev::ResetCold));
                    }
                }
            }
            choices.push(c);
        }
        for a in &choices[0] {
            for b in &choices[1] {
                for c in &choices[2] {
                    let evs = [*a, *b, *c];
                    let count = evs.iter().filter(|e| e.is_some()).count() as u8;
                    if count > s.events_left {
                        continue;
                    }
                    let mut t = s.clone();
                    t.events_left -= count;
                    t.cold = 0;
                    if count > 0 {
                        t.last_event = s.cycle;
                        t.gap_run = 0;
                    }
                    for (i, e) in evs.iter().enumerate() {
                        let n = &mut t.nodes[i];
                        match e {
                            None => {}
                            Some(Ev::Fail) => n.alive = false,
                            Some(Ev::Resume) => {
                                n.alive = true;
                                n.arb.stalled();
                            }
                            Some(ev) => {
                                n.alive = true;
                                n.arb = fresh(i, *ev);
                                if *ev == Ev::ResetCold {
                                    t.cold |= 1 << i;
                                }
                            }
                        }
                    }
                    path.push(format!("c{} {:?}", s.cycle, evs));
                    self.cycle(t, path);
                    path.pop();
                }
            }
        }
    }

    /// Sends, checks, observes, for state `t` whose events are applied.
    fn cycle(&mut self, t: State, path: &mut Vec<String>) {
        let senders: u8 = (0..N)
            .filter(|&i| t.nodes[i].alive && t.nodes[i].arb.is_master())
            .fold(0, |m, i| m | 1 << i);
        let count = senders.count_ones();
        let any_alive = t.nodes.iter().any(|n| n.alive);
        let cyc = t.cycle;
        let ctx = || format!("cycle {cyc} senders {senders:03b}\n{}", path.join("\n"));
        let mut t = t;
        // Split brain at most 2 cycles.
        t.split_run = if count >= 2 { t.split_run + 1 } else { 0 };
        assert!(t.split_run <= 2, "split brain > 2 cycles: {}", ctx());
        if count >= 2 {
            self.split_cycles += 1;
        }
        // A running master is never joined by a module that listened first.
        if t.prev_senders.count_ones() == 1 && count >= 2 {
            let newcomers = senders & !t.prev_senders & !t.cold;
            assert_eq!(
                newcomers,
                0,
                "a listening module joined a running master: {}",
                ctx()
            );
        }
        // Liveness between events.
        t.gap_run = if count == 0 && any_alive {
            t.gap_run + 1
        } else {
            0
        };
        assert!(
            t.gap_run <= MAX_GAP,
            "no sync for {} cycles: {}",
            t.gap_run,
            ctx()
        );
        // Convergence after the last event.
        if t.cycle >= t.last_event + CONVERGE && any_alive {
            assert_eq!(count, 1, "not converged: {}", ctx());
            assert_eq!(
                senders,
                t.prev_senders,
                "master changed after convergence: {}",
                ctx()
            );
        }
        // Who survives a split brain: nobody, or any one sender.
        let mut survivors: Vec<Option<usize>> = vec![None];
        if count >= 2 {
            survivors.extend((0..N).filter(|&i| senders & 1 << i != 0).map(Some));
        }
        for keep in survivors {
            let mut u = t.clone();
            for i in 0..N {
                let n = &mut u.nodes[i];
                if !n.alive {
                    continue;
                }
                let heard = senders & !(1 << i) != 0;
                let step = if heard && Some(i) != keep {
                    n.arb.foreign_sync()
                } else {
                    n.arb.silent_cycle()
                };
                match step {
                    Step::Yield => assert!(senders & 1 << i != 0),
                    Step::Send => assert!(senders & 1 << i != 0),
                    Step::TakeOver => assert_eq!(count, 0, "took over while hearing a sync"),
                    Step::Follow | Step::Listen => {}
                }
            }
            u.prev_senders = senders;
            u.cycle += 1;
            self.explore(u, path);
        }
    }
}

fn check(start: [Node; N]) -> Checker {
    let mut c = Checker {
        seen: HashSet::new(),
        states: 0,
        split_cycles: 0,
        converged_runs: 0,
    };
    let s = State {
        cycle: 0,
        nodes: start,
        events_left: MAX_EVENTS,
        split_run: 0,
        gap_run: 0,
        last_event: 0,
        prev_senders: 0,
        cold: 0,
    };
    c.explore(s, &mut Vec::new());
    c
}

fn node(alive: bool, arb: Arbiter) -> Node {
    Node { alive, arb }
}

#[test]
fn arbitration_converges_from_a_cold_start_under_every_fail_and_return_sequence() {
    let c = check([
        node(true, Arbiter::cold_master()),
        node(true, Arbiter::listening(Some(1))),
        node(true, Arbiter::listening(Some(2))),
    ]);
    eprintln!(
        "{} states, {} split-brain cycles reached, {} complete runs",
        c.states, c.split_cycles, c.converged_runs
    );
    // The checker really explored the hard cases.
    assert!(c.states > 10_000, "{} states", c.states);
    assert!(c.split_cycles > 0, "no split brain was ever reached");
}

#[test]
fn backups_take_over_when_the_master_is_absent_from_start_up() {
    let c = check([
        node(false, Arbiter::listening(Some(0))),
        node(true, Arbiter::listening(Some(1))),
        node(true, Arbiter::listening(Some(2))),
    ]);
    assert!(c.states > 1_000, "{} states", c.states);
}

/// Without events: the first sync of backup 1 comes after exactly `takeover_cycles(1)`
/// silent cycles and backup 2 follows it.
#[test]
fn absent_master_schedule_is_exact() {
    let mut b1 = Arbiter::listening(Some(1));
    let mut b2 = Arbiter::listening(Some(2));
    let mut first = None;
    for cycle in 0..20u32 {
        let s1 = b1.is_master();
        let s2 = b2.is_master();
        assert!(!(s1 && s2), "two masters in cycle {cycle}");
        if s1 && first.is_none() {
            first = Some(cycle);
        }
        if s1 {
            b2.foreign_sync();
        } else {
            b2.silent_cycle();
        }
        if s2 {
            b1.foreign_sync();
        } else {
            b1.silent_cycle();
        }
    }
    assert_eq!(first, Some(takeover_cycles(1)));
    assert!(b1.is_master() && !b2.is_master());
}
