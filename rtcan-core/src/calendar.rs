//! Calendars: per-node next own reserved slot in O(1), the master's per-cycle masks and
//! free windows. OWNER: scheduling helper. Signatures fixed.
use crate::tables::CalEntry;

/// Walks a node's sorted calendar as slots advance; O(1) amortised per slot.
#[derive(Clone, Copy, Debug, Default)]
pub struct CalendarCursor {
    next: usize,
}

impl CalendarCursor {
    /// Returns the calendar entry for `slot` (slot index within the hyperperiod), if this
    /// node owns it; advances past it. `slot` must be visited in increasing order modulo
    /// the hyperperiod (a jump forward, e.g. after resync, is handled).
    pub fn take<'c>(&mut self, calendar: &'c [CalEntry], slot: u32) -> Option<&'c CalEntry> {
        let _ = (calendar, slot, self.next);
        todo!()
    }
}

/// Number of consecutive free slots starting at `slot` within the cycle described by
/// `mask` (bit k = slot k reserved), up to the end of the cycle (slot 0 of the next
/// cycle is always the sync slot). 0 if `slot` itself is reserved.
pub const fn free_run(mask: u64, slot: u8, slots_per_cycle: u8) -> u8 {
    let _ = (mask, slot, slots_per_cycle);
    todo!()
}
