//! Calendars: per-node next own reserved slot in O(1), the master's per-cycle masks and
//! free windows.
//!
//! Every node walks only its own reserved slots (the paper's "local calendars", §3.3);
//! the master alone holds the mask of every cycle and broadcasts it in the sync frame.
use crate::tables::{BusConfig, CalEntry};

/// Walks a node's sorted calendar as slots advance; O(1) amortised per slot.
#[derive(Clone, Copy, Debug, Default)]
pub struct CalendarCursor {
    /// Index of the first entry not yet passed.
    next: usize,
    /// Last slot passed to `take`, to detect the wrap of the hyperperiod.
    last: u32,
}

impl CalendarCursor {
    /// A cursor at slot 0 of the hyperperiod.
    pub const fn new() -> Self {
        CalendarCursor { next: 0, last: 0 }
    }

    /// Returns the calendar entry for `slot` (slot index within the hyperperiod), if this
    /// node owns it; advances past it. `slot` must be visited in increasing order modulo
    /// the hyperperiod (a jump forward, e.g. after resync, is handled).
    pub fn take<'c>(&mut self, calendar: &'c [CalEntry], slot: u32) -> Option<&'c CalEntry> {
        if slot < self.last {
            // A smaller slot means the hyperperiod wrapped (possibly after a jump).
            self.next = 0;
        } else if calendar.get(self.next).is_some_and(|e| e.slot > slot) {
            // Fast path of most slots: this node's next entry is still ahead.
            self.last = slot;
            return None;
        }
        self.last = slot;
        // Skip entries behind `slot`: each entry is skipped at most once per hyperperiod.
        // A long jump uses binary search instead of a walk.
        let rest = calendar.get(self.next..)?;
        let skip = match rest.get(..8) {
            Some(head) if head.last().is_some_and(|e| e.slot < slot) => {
                rest.partition_point(|e| e.slot < slot)
            }
            _ => rest.iter().take_while(|e| e.slot < slot).count(),
        };
        self.next += skip;
        let e = calendar.get(self.next).filter(|e| e.slot == slot)?;
        self.next += 1;
        Some(e)
    }

    /// The next entry at or after `slot` without consuming it (`None` when no entry
    /// is left in this hyperperiod), e.g. to arm a timer for the node's next HRT slot.
    pub fn peek<'c>(&self, calendar: &'c [CalEntry], slot: u32) -> Option<&'c CalEntry> {
        let start = if slot < self.last { 0 } else { self.next };
        calendar.get(start..)?.iter().find(|e| e.slot >= slot)
    }
}

/// First reserved slot at or after `slot` in the cycle described by `mask` (bit k =
/// slot k reserved), or `slots_per_cycle` if none is left (the next cycle's sync slot
/// ends the window). Slots per cycle above 64 count as 64.
pub const fn next_reserved(mask: u64, slot: u8, slots_per_cycle: u8) -> u8 {
    let spc = if slots_per_cycle > 64 {
        64
    } else {
        slots_per_cycle
    };
    if slot >= spc {
        return spc;
    }
    let ahead = mask >> slot;
    let tz = ahead.trailing_zeros();
    let left = (spc - slot) as u32;
    if tz >= left {
        spc
    } else {
        slot + tz as u8
    }
}

/// Number of consecutive free slots starting at `slot` within the cycle described by
/// `mask` (bit k = slot k reserved), up to the end of the cycle (slot 0 of the next
/// cycle is always the sync slot). 0 if `slot` itself is reserved.
pub const fn free_run(mask: u64, slot: u8, slots_per_cycle: u8) -> u8 {
    next_reserved(mask, slot, slots_per_cycle).saturating_sub(slot)
}

/// The reservation mask the master broadcasts for absolute cycle `abs_cycle`: the
/// hyperperiod table repeats. An empty table (no HRT traffic) reserves only the sync.
pub fn mask_for_cycle(masks: &[u64], abs_cycle: u64) -> u64 {
    let len = masks.len() as u64;
    if len == 0 {
        return 1;
    }
    masks.get((abs_cycle % len) as usize).copied().unwrap_or(1)
}

/// Slot index within the hyperperiod (what `CalEntry::slot` counts) of `slot` in
/// absolute cycle `abs_cycle`.
pub fn hyper_slot(bus: &BusConfig, abs_cycle: u64, slot: u8) -> u32 {
    let cycles = u64::from(bus.hyperperiod_cycles.max(1));
    let s = (abs_cycle % cycles) * u64::from(bus.slots_per_cycle) + u64::from(slot);
    u32::try_from(s).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cal(slots: &[u32]) -> std::vec::Vec<CalEntry> {
        slots
            .iter()
            .enumerate()
            .map(|(i, &slot)| CalEntry {
                slot,
                tx: i as u8,
                fragment: 0,
            })
            .collect()
    }

    #[test]
    fn cursor_returns_own_slots_in_order_and_wraps() {
        let c = cal(&[3, 4, 70, 119]);
        let mut cur = CalendarCursor::new();
        for round in 0..3 {
            let mut got = std::vec::Vec::new();
            for slot in 0..120 {
                if let Some(e) = cur.take(&c, slot) {
                    got.push((slot, e.tx));
                }
            }
            assert_eq!(got, [(3, 0), (4, 1), (70, 2), (119, 3)], "round {round}");
        }
    }

    #[test]
    fn cursor_handles_forward_jumps_and_jump_across_wrap() {
        let c = cal(&(1..100).map(|k| k * 10).collect::<std::vec::Vec<_>>());
        let mut cur = CalendarCursor::new();
        assert_eq!(cur.take(&c, 10).map(|e| e.slot), Some(10));
        // Jump over 50 entries (binary-search path) onto an owned slot.
        assert_eq!(cur.take(&c, 520).map(|e| e.slot), Some(520));
        assert_eq!(cur.take(&c, 521), None);
        assert_eq!(cur.take(&c, 530).map(|e| e.slot), Some(530));
        // Resync lands in the next hyperperiod at slot 5, then 10 is owned again.
        assert_eq!(cur.take(&c, 5), None);
        assert_eq!(cur.take(&c, 10).map(|e| e.slot), Some(10));
        // Same slot twice is not returned twice.
        assert_eq!(cur.take(&c, 10), None);
        assert_eq!(cur.peek(&c, 11).map(|e| e.slot), Some(20));
        assert_eq!(cur.take(&c, 995), None);
        assert_eq!(cur.peek(&c, 995), None);
        assert_eq!(CalendarCursor::new().take(&[], 0), None);
    }

    #[test]
    fn free_runs_and_next_reserved() {
        // Slots 0 (sync), 4, 5 reserved in a 10-slot cycle.
        let m = 0b11_0001;
        assert_eq!(next_reserved(m, 0, 10), 0);
        assert_eq!(next_reserved(m, 1, 10), 4);
        assert_eq!(next_reserved(m, 6, 10), 10);
        assert_eq!(free_run(m, 0, 10), 0);
        assert_eq!(free_run(m, 1, 10), 3);
        assert_eq!(free_run(m, 4, 10), 0);
        assert_eq!(free_run(m, 6, 10), 4);
        assert_eq!(free_run(m, 9, 10), 1);
        assert_eq!(free_run(m, 10, 10), 0);
        // Bits past the cycle are ignored; a 64-slot cycle uses the top bit.
        assert_eq!(free_run(m | 1 << 12, 6, 10), 4);
        assert_eq!(free_run(1, 1, 64), 63);
        assert_eq!(free_run(1 | 1 << 63, 1, 64), 62);
        assert_eq!(next_reserved(1 | 1 << 63, 1, 64), 63);
    }

    #[test]
    fn masks_repeat_per_hyperperiod() {
        let masks = [0b11, 0b101, 0b1001];
        assert_eq!(mask_for_cycle(&masks, 4), 0b101);
        assert_eq!(mask_for_cycle(&[], 7), 1);
        let bus = BusConfig {
            bitrate: 1_000_000,
            slots_per_cycle: 60,
            slot_ns: 166_666,
            hyperperiod_cycles: 3,
            cycle_counter_wrap: 32_766,
            laxity: crate::laxity::LaxityEncoding::Linear { unit_ns: 1000 },
            guard_ns: 0,
            fingerprint: 0,
        };
        assert_eq!(hyper_slot(&bus, 4, 7), 67);
        assert_eq!(hyper_slot(&bus, 3, 0), 0);
    }
}
