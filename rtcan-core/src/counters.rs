//! Counters for everything dropped, late or aborted: nothing is lost silently.

/// Engine counters (saturating).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counters {
    /// Frames received whose message ID nobody here subscribes to (filters let it pass).
    pub rx_unknown_id: u32,
    /// Fragments with a wrong DLC.
    pub rx_bad_dlc: u32,
    /// Fragments out of order (loss or overrun upstream).
    pub rx_out_of_order: u32,
    /// Fragments of another transfer than the one in progress (its rest and the other's
    /// start were lost): transfer discarded, never mixed (docs/PROTOCOL.md §7.4).
    pub rx_other_transfer: u32,
    /// Transfers abandoned by the sender mid-way (a new first fragment arrived).
    pub rx_incomplete: u32,
    /// Frames for a topic whose configured size does not fit its buffer (a build bug).
    pub rx_bad_size: u32,
    /// Malformed sync frames.
    pub rx_bad_sync: u32,
    /// Malformed heartbeats.
    pub rx_bad_heartbeat: u32,
    /// RX FIFO overruns reported by the driver.
    pub rx_overrun: u32,
    /// Messages delivered to the host.
    pub rx_delivered: u32,
    /// Frames sent.
    pub tx_frames: u32,
    /// Frames aborted at a window close (re-queued).
    pub tx_aborted: u32,
    /// Frames that failed (arbitration lost / error with no automatic retransmission).
    pub tx_failed: u32,
    /// SRT messages dropped because their deadline passed.
    pub deadline_missed: u32,
    /// Submissions refused because the queue was full.
    pub queue_full: u32,
    /// HRT slots where the host had nothing to send.
    pub hrt_empty: u32,
    /// HRT slots missed (handler ran too late).
    pub hrt_late: u32,
    /// Sync frames missed (cycles without sync on a slave).
    pub sync_missed: u32,
    /// Bus-off entries reported by the driver (`Engine::on_error_state`).
    pub bus_off: u32,
    /// Whole cycles skipped without handling any of their slots, because `poll` came
    /// more than a cycle late (a forward jump of the local clock, or a long stall).
    pub cycles_skipped: u32,
    /// Entries into error-passive reported by the driver (`Engine::on_error_state`).
    pub error_passive: u32,
    /// Times this module stopped being master because it heard another master's sync
    /// (split brain detected, docs/PROTOCOL.md §5.6).
    pub master_yields: u32,
}

impl Counters {
    /// Adds one, saturating.
    pub fn bump(c: &mut u32) {
        *c = c.saturating_add(1);
    }
    /// Adds `n`, saturating.
    pub fn add(c: &mut u32, n: u64) {
        *c = c.saturating_add(u32::try_from(n).unwrap_or(u32::MAX));
    }
}
