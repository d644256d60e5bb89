//! Who sends the sync, seen from the wire: cycles with two syncs (two masters), the
//! longest silence between syncs (a takeover's outage), the last time either happened.
//! Streamed frame by frame; constant memory.
use rtcan_core::Nanos;

use crate::bus::WireFrame;

/// Sync frames observed on the wire.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SyncWatch {
    cycle_ns: Nanos,
    last: Option<Nanos>,
    /// Sync frames completed.
    pub syncs: u64,
    /// Syncs that started less than half a cycle after the previous one: a cycle with
    /// two syncs (two masters, or a master and a stale one).
    pub doubled: u64,
    /// Start of the last doubled sync, ns.
    pub last_doubled_at: Option<Nanos>,
    /// Longest time between the starts of two consecutive syncs, ns, and where it ended.
    pub longest_gap: (Nanos, Nanos),
}

impl SyncWatch {
    /// A watch for a bus with cycles of `cycle_ns`.
    pub fn new(cycle_ns: Nanos) -> Self {
        SyncWatch {
            cycle_ns,
            ..SyncWatch::default()
        }
    }

    /// Feeds one frame of the wire log.
    pub fn frame(&mut self, w: &WireFrame) {
        if !w.ok || !w.frame.id().is_sync() {
            return;
        }
        self.syncs += 1;
        if let Some(prev) = self.last {
            let gap = w.sof.saturating_sub(prev);
            if gap < self.cycle_ns / 2 {
                self.doubled += 1;
                self.last_doubled_at = Some(w.sof);
            }
            if gap > self.longest_gap.0 {
                self.longest_gap = (gap, w.sof);
            }
        }
        self.last = Some(w.sof);
    }
}

impl SyncWatch {
    /// The run ended at `end`: the silence since the last sync (or since the start, if
    /// there was none) counts as a gap too, so a bus that never recovers shows it.
    pub fn finish(&mut self, end: Nanos) {
        let gap = end.saturating_sub(self.last.unwrap_or(0));
        if gap > self.longest_gap.0 {
            self.longest_gap = (gap, end);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtcan_core::{CanId, Frame};

    fn sync(sof: Nanos) -> WireFrame {
        let id = CanId::from_raw(0).unwrap();
        assert!(id.is_sync());
        WireFrame {
            sof,
            end: sof + 50_000,
            node: 0,
            frame: Frame::from_parts(id, 0, [0; 8]).unwrap(),
            ok: true,
            partial: false,
        }
    }

    #[test]
    fn counts_doubled_cycles_and_the_longest_silence() {
        let mut s = SyncWatch::new(10_000_000);
        for t in [
            0, 10_000_000, 20_000_000, 24_000_000, 30_000_000, 80_000_000,
        ] {
            s.frame(&sync(t));
        }
        assert_eq!(s.syncs, 6);
        assert_eq!(s.doubled, 1);
        assert_eq!(s.last_doubled_at, Some(24_000_000));
        assert_eq!(s.longest_gap, (50_000_000, 80_000_000));
        // A destroyed sync is not a sync.
        let mut bad = sync(81_000_000);
        bad.ok = false;
        s.frame(&bad);
        assert_eq!((s.syncs, s.doubled), (6, 1));
        // A bus that went silent for good: the trailing silence is the longest gap.
        s.finish(80_000_000 + 40_000_000);
        assert_eq!(s.longest_gap, (50_000_000, 80_000_000));
        s.finish(80_000_000 + 70_000_000);
        assert_eq!(s.longest_gap, (70_000_000, 150_000_000));
        let mut never = SyncWatch::new(10_000_000);
        never.finish(5_000_000_000);
        assert_eq!(never.longest_gap, (5_000_000_000, 5_000_000_000));
    }

    #[test]
    fn slot_check_places_frames_by_the_last_sync() {
        // 10 slots of 100 us; the sync reserves slots 0 and 3 (mask 0b1001).
        let mut c = SlotCheck::new(100_000, 10, 2_000);
        let at = |sof: Nanos, len: Nanos, raw: u32, ok: bool| WireFrame {
            sof,
            end: sof + len,
            node: 1,
            frame: Frame::from_parts(
                CanId::from_raw(raw).unwrap(),
                2,
                [0b1001, 0, 0, 0, 0, 0, 0, 0],
            )
            .unwrap(),
            ok,
            partial: false,
        };
        let hrt = 0x0000_A000; // laxity 0, a topic
        let srt = 0x0800_A000; // laxity 1
        c.frame(&at(1_000_000, 1, hrt, true)); // before any sync: unchecked
        assert_eq!(c.checked, 0);
        c.frame(&at(2_002_000, 50_000, 0, true)); // the sync, slot 0
        c.frame(&at(2_304_000, 90_000, hrt, true)); // HRT in slot 3: fine
        c.frame(&at(2_104_000, 90_000, hrt, true)); // HRT in free slot 1: bad
        c.frame(&at(2_350_000, 90_000, hrt, true)); // HRT across slots 3-4: bad
        c.frame(&at(2_104_000, 150_000, srt, true)); // SRT in slots 1-2: fine
        c.frame(&at(2_204_000, 150_000, srt, true)); // SRT into slot 3: bad
        c.frame(&at(2_904_000, 150_000, srt, true)); // SRT into the next sync slot: bad
        assert_eq!((c.bad, c.checked), (4, 7));
        c.frame(&at(3_100_000, 1, hrt, true)); // more than a cycle later: unchecked
        assert_eq!((c.bad, c.checked), (4, 7));
        // With a tolerance of 1 us, an HRT frame 500 ns early into slot 3 passes, 2 us
        // early does not.
        let mut t = SlotCheck::new(100_000, 10, 2_000).with_tolerance(1_000);
        t.frame(&at(2_002_000, 50_000, 0, true));
        t.frame(&at(2_299_500, 90_000, hrt, true));
        assert_eq!((t.bad, t.checked), (0, 2));
        t.frame(&at(2_298_000, 90_000, hrt, true));
        assert_eq!((t.bad, t.checked), (1, 3));
    }
}

/// Temporal isolation checked against the wire alone, whoever the master is: a frame
/// that starts within one cycle of the last sync is placed by that sync (slot 0 starts
/// `lead` ns before the sync's start of frame; the sync's payload is the reservation mask
/// of its cycle, docs/PROTOCOL.md §3.2). An HRT frame must lie within one reserved slot,
/// any other frame (SRT, NRT, heartbeat) outside every reserved slot. Frames more than a
/// cycle after the last sync (no master) are not checked.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SlotCheck {
    slot_ns: Nanos,
    slots: u64,
    lead: Nanos,
    /// A frame may reach this far into a neighbouring slot (the sync sender's own grid
    /// drifts from the one its sync's start of frame gives the wire: its clock rate).
    tol: Nanos,
    anchor: Option<(Nanos, u64)>,
    /// Frames outside their slots or windows.
    pub bad: u64,
    /// Frames checked.
    pub checked: u64,
}

impl SlotCheck {
    /// A check for slots of `slot_ns`, `slots` per cycle; the master's sync starts
    /// `lead` ns into slot 0 (its timer interrupt latency).
    pub fn new(slot_ns: Nanos, slots: u8, lead: Nanos) -> Self {
        SlotCheck {
            slot_ns: slot_ns.max(1),
            slots: u64::from(slots.max(1)),
            lead,
            ..SlotCheck::default()
        }
    }

    /// Accepts frames that reach up to `tol` ns into a neighbouring slot: one bit time
    /// plus what the sync sender's clock drifts over a cycle (its frames follow its own
    /// grid, which runs at its rate; the wire only shows where its sync started).
    pub fn with_tolerance(mut self, tol: Nanos) -> Self {
        self.tol = tol;
        self
    }

    /// Feeds one frame of the wire log.
    pub fn frame(&mut self, w: &WireFrame) {
        let id = w.frame.id();
        if w.ok && id.is_sync() {
            let mut b = [0u8; 8];
            for (d, s) in b.iter_mut().zip(w.frame.data()) {
                *d = *s;
            }
            self.anchor = Some((w.sof.saturating_sub(self.lead), u64::from_le_bytes(b)));
        }
        let Some((start, mask)) = self.anchor else {
            return;
        };
        let cycle = self.slot_ns * self.slots;
        let (Some(s), Some(e)) = (
            w.sof.checked_sub(start),
            w.end.checked_sub(start).map(|e| e.saturating_sub(1)),
        ) else {
            return;
        };
        if s >= cycle {
            return;
        }
        self.checked += 1;
        // Slot `slots` is the next cycle's slot 0: the next sync's, reserved.
        let slots = self.slots;
        let reserved = |k: u64| {
            if k < slots {
                k < 64 && mask & (1u64 << k) != 0
            } else {
                k.is_multiple_of(slots)
            }
        };
        let (s, e) = (s + self.tol, e.saturating_sub(self.tol).max(s + self.tol));
        let (first, last) = (s / self.slot_ns, e / self.slot_ns);
        let ok = if id.laxity() == 0 {
            first == last && reserved(first)
        } else {
            (first..=last).all(|k| !reserved(k))
        };
        if !ok {
            self.bad += 1;
        }
    }
}
