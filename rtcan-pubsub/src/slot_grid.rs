//! Synchronous HRT publishers (R2P §3.4.5): a node's callback for an HRT topic runs a
//! declared lead time before each of the topic's slots, so the sample it publishes is at
//! most that old when its frame starts. The times come from the slot clock (the engine's
//! map of the master's cycles onto the module's local clock), not from a coarse tick:
//! the protocol side snapshots the grid ([`SlotGrid`], kept in the module's
//! `SystemStatus`), the app asks a topic's [`HrtSlots`] (generated from robot.toml) when
//! its publisher is next due.
use rtcan_core::clock::SlotClock;
use rtcan_core::time::Nanos;

/// The slot grid on the local clock: where slot 0 of one absolute cycle lies and how
/// long a bus cycle lasts locally (the clock's rate). Within a cycle or two of the
/// snapshot it places a slot boundary within a few ns of the engine's own (the clock
/// drifts by at most its rate error times the distance, ≤ 2 µs over 10 ms at 200 ppm).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SlotGrid {
    /// Absolute cycle whose slot 0 is at `start`.
    pub cycle: u64,
    /// Local time of slot 0 of `cycle`.
    pub start: Nanos,
    /// Local length of one bus cycle.
    pub cycle_local: Nanos,
}

impl SlotGrid {
    /// The grid of `clock` around local time `now` (the cycle whose slot 0 is nearest).
    /// `None` for a clock that maps a cycle onto no local time (not locked).
    pub fn of_clock(clock: &SlotClock, now: Nanos) -> Option<Self> {
        let cycle = clock.nearest_cycle(now);
        let start = clock.to_local(clock.cycle_start_bus(cycle));
        let end = clock.to_local(clock.cycle_start_bus(cycle.saturating_add(1)));
        let cycle_local = end.checked_sub(start).filter(|&d| d > 0)?;
        Some(SlotGrid {
            cycle,
            start,
            cycle_local,
        })
    }
}

/// One HRT topic's slots on the bus and its publisher's lead time (generated from
/// robot.toml's plan: `robot::<module>::nodes::<node>::<TOPIC>_SLOTS`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HrtSlots {
    /// First slot, counted from slot 0 of cycle 0 (the plan's phase).
    pub phase_slot: u32,
    /// Period in slots.
    pub period_slots: u32,
    /// Slots per cycle.
    pub slots_per_cycle: u32,
    /// Slot length on the bus, ns.
    pub slot_ns: Nanos,
    /// Cycle length on the bus, ns (slot boundaries: cycle start + slot × `slot_ns`).
    pub cycle_ns: Nanos,
    /// How long before each slot the publisher runs, ns (robot.toml `lead`).
    pub lead_ns: Nanos,
}

impl HrtSlots {
    /// When the publisher is next due after `now`: the local start of the first of the
    /// topic's slots that begins more than `lead_ns` after `now`, minus `lead_ns`
    /// (strictly after `now`, so a callback run at its due time asks for the next
    /// instance). `None` for a degenerate table or grid (zero lengths).
    pub fn next_due(&self, grid: &SlotGrid, now: Nanos) -> Option<Nanos> {
        let (slots, period) = (
            u64::from(self.slots_per_cycle),
            u64::from(self.period_slots),
        );
        if slots == 0 || period == 0 || self.slot_ns == 0 || self.cycle_ns == 0 {
            return None;
        }
        let cl = grid.cycle_local;
        let target = now.saturating_add(self.lead_ns);
        // Rebase the grid on the cycle that contains `target` (one division; the grid
        // may be a cycle ahead of `now`, e.g. just before a sync).
        let (cycle, start) = if target >= grid.start {
            let whole = (target - grid.start) / cl;
            (grid.cycle + whole, grid.start + whole * cl)
        } else {
            let back = (grid.start - target).div_ceil(cl);
            (
                grid.cycle.checked_sub(back)?,
                grid.start.checked_sub(back * cl)?,
            )
        };
        // Bus ns into the cycle: local offset × bus/local (< 1 cycle: no overflow for
        // cycles below 4 s).
        let into = (target - start).saturating_mul(self.cycle_ns) / cl;
        let slot = (into / self.slot_ns).min(slots - 1);
        // The slot holding `target` starts at or before it: the first candidate is the
        // next one, then up to the topic's phase modulo its period.
        let first = cycle.checked_mul(slots)?.checked_add(slot + 1)?;
        let phase = u64::from(self.phase_slot) % period;
        let n = first + (phase + period - first % period) % period;
        let (c, s) = (n / slots, n % slots);
        let local = start
            .checked_add((c - cycle).checked_mul(cl)?)?
            .checked_add(s.saturating_mul(self.slot_ns).saturating_mul(cl) / self.cycle_ns)?;
        Some(local.saturating_sub(self.lead_ns))
    }
}

/// A periodic publisher's schedule: on its HRT slots once the grid is known, else (not
/// synchronised yet, or a topic not on the bus) every `period` from its first run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SlotEvery {
    slots: Option<HrtSlots>,
    period: Nanos,
    next: Option<Nanos>,
}

impl SlotEvery {
    /// On `slots` (None: a plain period), `period` ns apart without a grid.
    pub const fn new(slots: Option<HrtSlots>, period: Nanos) -> Self {
        SlotEvery {
            slots,
            period,
            next: None,
        }
    }

    /// Whether the publisher is due at `now` (and if so, schedules the next run: the
    /// next slot's due time on `grid`, or one period on).
    pub fn due(&mut self, now: Nanos, grid: Option<SlotGrid>) -> bool {
        if let Some(n) = self.next {
            if now < n {
                // A grid that appeared (or moved) since the last run may bring the next
                // instance closer than the free-running period would.
                if let Some(at) = self.on_grid(now, grid) {
                    if at < n {
                        self.next = Some(at);
                    }
                }
                return false;
            }
        }
        let next = self
            .on_grid(now, grid)
            .unwrap_or_else(|| now.saturating_add(self.period));
        self.next = Some(next);
        true
    }

    fn on_grid(&self, now: Nanos, grid: Option<SlotGrid>) -> Option<Nanos> {
        self.slots?.next_due(&grid?, now)
    }

    /// When it is next due (`0`: at the first poll).
    pub fn next(&self) -> Nanos {
        self.next.unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Triskar2's bus: 60 slots of 166 666 ns in a 10 ms cycle.
    const SLOTS: HrtSlots = HrtSlots {
        phase_slot: 7,
        period_slots: 240,
        slots_per_cycle: 60,
        slot_ns: 166_666,
        cycle_ns: 10_000_000,
        lead_ns: 500_000,
    };

    #[test]
    fn due_lead_before_the_slot_on_an_exact_grid() {
        let grid = SlotGrid {
            cycle: 0,
            start: 1_000,
            cycle_local: 10_000_000,
        };
        // Slot 7 of cycle 0: 1 000 + 7 × 166 666 = 1 167 662; due 500 µs earlier.
        assert_eq!(SLOTS.next_due(&grid, 0), Some(667_662));
        // At the due time itself: the next instance, 240 slots = 4 cycles on.
        assert_eq!(SLOTS.next_due(&grid, 667_662), Some(40_667_662));
        assert_eq!(SLOTS.next_due(&grid, 667_661), Some(667_662));
        // Far ahead of the snapshot (cycle 9 → instance in cycle 12).
        assert_eq!(SLOTS.next_due(&grid, 95_000_000), Some(120_667_662));
    }

    #[test]
    fn due_follows_a_fast_local_clock_and_a_grid_ahead_of_now() {
        // Local clock 100 ppm fast: a cycle lasts 10 001 000 local ns.
        let grid = SlotGrid {
            cycle: 400,
            start: 4_000_400_000,
            cycle_local: 10_001_000,
        };
        // Cycle 400 is a multiple of 4: its slot 7 is an instance. 7 × 166 666 bus ns =
        // 1 166 662 → 1 166 778 local (× 1.0001, floored).
        assert_eq!(
            SLOTS.next_due(&grid, 4_000_000_000),
            Some(4_000_400_000 + 1_166_778 - 500_000)
        );
        // Asked before the snapshot's cycle (grid one cycle ahead): cycle 399 has no
        // instance, so the answer is still cycle 400's.
        assert_eq!(
            SLOTS.next_due(&grid, 3_990_500_000),
            Some(4_000_400_000 + 1_166_778 - 500_000)
        );
        // A grid whose cycle 0 starts just after now.
        let early = SlotGrid {
            cycle: 0,
            start: 50,
            cycle_local: 10_000_000,
        };
        assert_eq!(SLOTS.next_due(&early, 0), Some(50 + 1_166_662 - 500_000));
    }

    #[test]
    fn degenerate_tables_give_none_and_a_period_of_one_slot_is_every_slot() {
        let grid = SlotGrid {
            cycle: 0,
            start: 0,
            cycle_local: 10_000_000,
        };
        assert_eq!(
            HrtSlots {
                slot_ns: 0,
                ..SLOTS
            }
            .next_due(&grid, 0),
            None
        );
        assert_eq!(
            HrtSlots {
                period_slots: 0,
                ..SLOTS
            }
            .next_due(&grid, 0),
            None
        );
        let every = HrtSlots {
            phase_slot: 1,
            period_slots: 1,
            lead_ns: 166_666,
            ..SLOTS
        };
        // Slot 1 starts exactly lead after now, not more: slot 2, due at slot 1's start.
        assert_eq!(every.next_due(&grid, 0), Some(166_666));
        // The cycle's tail (10 ms > 60 × 166 666 ns) belongs to slot 59: the next is
        // slot 0 of cycle 1 (the sync's own slot, an instance of a period-1 topic).
        assert_eq!(
            every.next_due(&grid, 9_999_990 - 166_666),
            Some(10_000_000 - 166_666)
        );
    }

    #[test]
    fn slot_every_runs_free_until_the_grid_then_on_the_slots() {
        let mut e = SlotEvery::new(Some(SLOTS), 40_000_000);
        assert!(e.due(3, None), "first poll: at once");
        assert_eq!(e.next(), 40_000_003);
        assert!(!e.due(1_000, None));
        let grid = SlotGrid {
            cycle: 0,
            start: 0,
            cycle_local: 10_000_000,
        };
        // The grid arrived: the next instance (slot 7, due 666 662) is sooner.
        assert!(!e.due(2_000, Some(grid)));
        assert_eq!(e.next(), 666_662);
        assert!(e.due(666_700, Some(grid)), "38 ns late");
        assert_eq!(e.next(), 40_666_662);
        // Off the bus (no slots): a plain period from the last run.
        let mut p = SlotEvery::new(None, 5);
        assert!(p.due(10, Some(grid)));
        assert_eq!(p.next(), 15);
    }
}
