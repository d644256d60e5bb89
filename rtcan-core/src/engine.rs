//! The protocol engine of one module: events in (slot timer, RX, TX done, submit),
//! actions out (load/abort mailboxes through `Controller`, deliver through `Host`,
//! next timer deadline as the return value of `poll`).
//!
//! Time: every `now` is the node-local clock. The slot clock (`clock.rs`) maps it to
//! bus time; laxities, deadlines and slot boundaries are bus time (docs/PROTOCOL.md §5).
//!
//! Per slot boundary the engine does O(1) work: advance the slot counters, look up its
//! own calendar with a cursor, and either load the sync frame (master, slot 0), load an
//! HRT fragment (own reserved slot), or open a free window and fill the mailboxes from
//! the EDF queue (frames that fit before the window ends, docs/PROTOCOL.md §8).
use crate::arbiter::{Arbiter, Step};
use crate::calendar::{free_run, CalendarCursor};
use crate::clock::SlotClock;
use crate::confinement::{ErrorState, Level};
use crate::counters::Counters;
use crate::driver::{Controller, Event, Host, Mailbox, Token, TxOutcome, TxResult, MAILBOXES};
use crate::fragment::{fragment_count, fragment_data, fragment_field, RxState, RxStep};
use crate::frame::Frame;
use crate::heartbeat::{heartbeat_frame, parse_heartbeat, Heartbeat};
use crate::id::{CanId, Class, FIRST_TOPIC_MSG_ID, HEARTBEAT_BASE, LAXITY_HRT, LAXITY_NRT};
use crate::queue::EdfQueue;
use crate::sync::{sync_frame, Sync, SyncFormat};
use crate::tables::NodeTables;
use crate::time::{Nanos, SNanos};
use crate::timing::{bits_to_ns, worst_case_bits};

/// A slave that has not seen a sync frame for this many cycles stops transmitting
/// and reports `Event::SyncLost` (its slot clock can no longer be trusted).
pub const SYNC_LOSS_CYCLES: u64 = crate::arbiter::SYNC_LOSS_CYCLES as u64;
/// Every module sends its heartbeat once every this many cycles (staggered by module).
pub use crate::heartbeat::HEARTBEAT_PERIOD_CYCLES as HEARTBEAT_CYCLES;
/// Queue key of NRT messages: after every SRT deadline, FIFO among themselves.
const NRT_KEY: u64 = u64::MAX;

/// Why `Engine::submit` refused a message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SubmitError {
    /// The transmit queue is full (capacity `Q`).
    QueueFull,
    /// `tx` is not a topic of this module, or it is HRT (HRT is sampled, not submitted),
    /// or the payload length is not the topic's size.
    NotSubmittable,
}

/// A table set that does not fit the engine's const generics or is inconsistent.
/// Generated tables are checked at compile time (`const _: () = assert!(...)`), so this
/// is a build error, never a run-time surprise.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TablesError {
    /// More receive topics than `RX`.
    TooManyRx,
    /// A reassembly buffer (`wire_len(size)` bytes: payload plus the transfer CRC of
    /// multi-frame topics) ends past `ARENA`.
    ArenaTooSmall,
    /// A reassembly buffer starts before the previous one (in table order) ends: the
    /// two would overwrite each other (e.g. laid out with `size` instead of `wire_len`,
    /// so a CRC lands in the next topic's bytes).
    RxOverlap,
    /// `rx` not sorted by message ID (binary search on receive).
    RxNotSorted,
    /// A topic larger than `MAX_PAYLOAD` (more than 128 fragments).
    BadSize,
    /// A calendar entry names a missing transmit topic or a fragment the topic does not
    /// have, lies outside the hyperperiod, or the calendar is not sorted.
    BadCalendar,
    /// Slots per cycle outside 2..=64, zero slot length, bit rate or hyperperiod.
    BadBus,
}

/// Checks `tables` against the engine sizes `rx`, `arena` (const: usable in a const assert).
/// Linear in the tables: receive buffers must be laid out in table order (as rtcan-model
/// does), each starting at or after the end of the previous one.
pub const fn check_tables(
    tables: &NodeTables<'_>,
    rx: usize,
    arena: usize,
) -> Result<(), TablesError> {
    use crate::fragment::{wire_len, MAX_PAYLOAD};
    let bus = &tables.bus;
    if bus.slots_per_cycle < 2
        || bus.slots_per_cycle > 64
        || bus.slot_ns == 0
        || bus.bitrate == 0
        || bus.hyperperiod_cycles == 0
        || bus.cycle_counter_wrap == 0
    {
        return Err(TablesError::BadBus);
    }
    if tables.rx.len() > rx {
        return Err(TablesError::TooManyRx);
    }
    // Slice patterns instead of indexing: const fn, and nothing that can panic.
    let mut rest = tables.rx;
    let mut prev: Option<u16> = None;
    let mut prev_end = 0usize;
    while let [t, tail @ ..] = rest {
        let size = t.size as usize;
        if size > MAX_PAYLOAD {
            return Err(TablesError::BadSize);
        }
        if let Some(p) = prev {
            if p >= t.msg_id.0 {
                return Err(TablesError::RxNotSorted);
            }
        }
        let start = t.arena_offset as usize;
        if start < prev_end {
            return Err(TablesError::RxOverlap);
        }
        prev_end = start + wire_len(size);
        if prev_end > arena {
            return Err(TablesError::ArenaTooSmall);
        }
        prev = Some(t.msg_id.0);
        rest = tail;
    }
    let mut rest = tables.tx;
    while let [t, tail @ ..] = rest {
        if t.size as usize > MAX_PAYLOAD {
            return Err(TablesError::BadSize);
        }
        rest = tail;
    }
    let hyper_slots = bus.hyperperiod_cycles as u64 * bus.slots_per_cycle as u64;
    let mut rest = tables.calendar;
    let mut prev: Option<u32> = None;
    while let [c, tail @ ..] = rest {
        let Some((_, [topic, ..])) = tables.tx.split_at_checked(c.tx as usize) else {
            return Err(TablesError::BadCalendar);
        };
        if c.fragment >= fragment_count(topic.size as usize) || c.slot as u64 >= hyper_slots {
            return Err(TablesError::BadCalendar);
        }
        if let Some(p) = prev {
            if p >= c.slot {
                return Err(TablesError::BadCalendar);
            }
        }
        prev = Some(c.slot);
        rest = tail;
    }
    Ok(())
}

/// SRT policy knobs, so the simulator can run the paper's published policy next to ours
/// on the same engine (no protocol logic re-implemented elsewhere).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Policy {
    /// Near a window end, load a shorter, less urgent frame that fits when the most
    /// urgent one does not (false: strict EDF head, wait for the next window).
    pub fit_window_end: bool,
    /// Drop a message as soon as it can no longer make its deadline (remaining
    /// fragments × worst-case frame time > laxity), instead of spending the bus on it.
    pub drop_hopeless: bool,
    /// At each free slot boundary, abort a waiting SRT frame whose laxity code has aged
    /// (its encoding would now be more urgent) so it is reloaded with the fresh code:
    /// otherwise a frame loaded early keeps a stale priority and loses arbitration to
    /// less urgent frames loaded later. Aborting a pending frame costs no bus time.
    pub refresh_laxity: bool,
    /// Window frames take at most `MAILBOXES − 1` mailboxes, so the next sync or HRT
    /// fragment always finds one free, even before the completions of the window's last
    /// frames have reached the engine (on a real CPU they are processed by a task after
    /// the TX interrupt, which may run after the next slot's frame is loaded or prepared;
    /// issue 10). Costs no throughput: two mailboxes already keep the bus busy back to
    /// back (one transmits while the other waits).
    pub keep_tdma_mailbox: bool,
}

impl Policy {
    /// Our policy.
    pub const OURS: Policy = Policy {
        fit_window_end: true,
        drop_hopeless: true,
        refresh_laxity: true,
        keep_tdma_mailbox: true,
    };
    /// The RTCAN paper's policy as published: EDF head only, drop only once the
    /// deadline has passed.
    pub const PAPER: Policy = Policy {
        fit_window_end: false,
        drop_hopeless: false,
        refresh_laxity: false,
        keep_tdma_mailbox: false,
    };
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Item {
    /// A topic message: `fragment` is the counter of the next frame to send.
    Topic {
        tx: u8,
        token: Token,
        fragment: u8,
        /// Transfer ID (docs/PROTOCOL.md §7.4), taken when the first fragment is first
        /// loaded; kept across aborts and reloads.
        tid: Option<u8>,
        deadline: Nanos,
    },
    /// This module's heartbeat.
    Heartbeat,
    /// The host's update-channel frame (`Host::service_tx`), `dlc` data bytes.
    Service { dlc: u8 },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Loaded {
    Free,
    Sync,
    /// HRT fragment of transfer `seq`. The mailbox holding fragment 0 (the last) owns
    /// the transfer's report from the moment it is loaded; `broken`: an earlier
    /// fragment of it failed, so even if this one is sent the transfer is not.
    Hrt {
        tx: u8,
        token: Token,
        fragment: u8,
        seq: u8,
        broken: bool,
    },
    /// Free-window frame; `latest_start` (local) is when it must be aborted if it has
    /// not started, so it cannot overrun the next reserved slot.
    Window {
        item: Item,
        key: u64,
        latest_start: Nanos,
        abort_requested: bool,
        /// Laxity code in the loaded identifier (it ages while the frame waits).
        laxity: u8,
    },
}

/// Where the slot sequence stands: the cycle being executed and a linear map from its
/// bus time to local time. Boundaries are computed from the map with one multiply and a
/// shift, so the per-slot path does no 64-bit division (a library call on Cortex-M3);
/// the map is refreshed from the slot clock once per sync.
#[derive(Clone, Copy, Debug)]
struct Position {
    /// Absolute cycle being executed.
    abs_cycle: u64,
    /// `abs_cycle` modulo the hyperperiod (in cycles).
    cycle_in_hyper: u32,
    /// `abs_cycle` modulo `cycle_counter_wrap` (the sync frame's counter).
    counter: u32,
    /// Next boundary to handle within `abs_cycle`; `slots_per_cycle` = the next cycle's slot 0.
    next_slot: u8,
    /// Local time of slot 0 of `abs_cycle`.
    start_local: Nanos,
    /// Bus time of slot 0 of `abs_cycle`.
    start_bus: Nanos,
    /// Local slot length, ns × 2^16.
    slot_q16: u64,
    /// Bus ns per local ns × 2^32.
    inv_q32: u64,
    /// Cycles until this module's next heartbeat.
    heartbeat_in: u8,
}

impl Position {
    /// Local time of boundary `slot` of this cycle (saturating at the end of time).
    fn boundary(&self, slot: u8) -> Nanos {
        self.start_local
            .saturating_add((slot as u64 * self.slot_q16) >> 16)
    }
}

/// The HRT transfer whose fragments are being loaded. Reported exactly once: here if it
/// is abandoned before its last fragment is loaded, else by that fragment's mailbox
/// when it completes (a last fragment still retransmitting when the next transfer's
/// first fragment is loaded completes, and is reported, on its own).
#[derive(Clone, Copy, Debug)]
struct HrtTransfer {
    tx: u8,
    token: Token,
    /// Transfer ID carried in every fragment's ID (docs/PROTOCOL.md §7).
    tid: u8,
    /// Names this transfer's mailboxes (tokens may be reused by the host).
    seq: u8,
    /// Fragment 0 is loaded: its mailbox reports the outcome.
    last_loaded: bool,
}

/// Engine of one module. `RX`: receive topics; `ARENA`: reassembly bytes; `Q`: SRT/NRT
/// queue capacity. All sizes come from the generated per-module constants.
pub struct Engine<'t, const RX: usize, const ARENA: usize, const Q: usize> {
    tables: NodeTables<'t>,
    policy: Policy,
    counters: Counters,
    clock: SlotClock,
    master: bool,
    /// Worst-case duration of a frame with DLC 0..=8, ns (precomputed: no division on
    /// the per-frame path).
    wc_ns: [Nanos; 9],
    /// Local time of the next boundary to handle (`pos.next_slot`); MAX when a slave is
    /// not following the sync.
    next_boundary: Nanos,
    pos: Position,
    cursor: CalendarCursor,
    /// Reservation mask of the cycle being executed.
    cycle_mask: u64,
    /// Absolute cycle whose reservation mask `cycle_mask` is (u64::MAX: none).
    mask_cycle: u64,
    last_sync_cycle: u64,
    /// Local time at which the current free window ends (guard applied); 0 = not in a window.
    window_end: Nanos,
    mailboxes: [Loaded; MAILBOXES],
    hrt: Option<HrtTransfer>,
    /// `seq` of the next HRT transfer (wraps; at most a few are in mailboxes at once).
    hrt_seq: u8,
    queue: EdfQueue<Item, Q>,
    in_flight: usize,
    heartbeat_pending: bool,
    /// Heartbeat period in cycles (`HEARTBEAT_CYCLES` unless `set_heartbeat_cycles`).
    heartbeat_cycles: u8,
    /// Backup master: rank (1 = first to take over) and the hyperperiod's masks.
    backup: Option<(u8, &'t [u64])>,
    /// Local time at which this backup takes over mastership (MAX: not pending).
    promote_at: Nanos,
    /// Who sends the sync (docs/PROTOCOL.md §5.6).
    arbiter: Arbiter,
    /// Local time since which this module has heard no sync (takeover countdown).
    silent_since: Nanos,
    /// Cycle length (ns), precomputed for the per-slot stall test.
    cycle_ns: Nanos,
    /// The sync frame's checks for this bus (precomputed: a slave parses one per cycle).
    sync_format: SyncFormat,
    /// Last fault-confinement state reported by the driver.
    error: ErrorState,
    /// Next transfer ID of each transmit topic (index = `TxIndex`, a `u8`, so every
    /// index has an entry; docs/PROTOCOL.md §7.4).
    tx_tid: [u8; 256],
    rx_state: [RxState; RX],
    arena: [u8; ARENA],
}

impl<'t, const RX: usize, const ARENA: usize, const Q: usize> Engine<'t, RX, ARENA, Q> {
    /// A master if `tables.master_masks` is non-empty, else a slave waiting for sync.
    /// `now` is the local time; a master starts cycle 0 one slot later.
    pub fn new(tables: NodeTables<'t>, now: Nanos) -> Self {
        let bus = tables.bus;
        let master = !tables.master_masks.is_empty();
        let start = now + bus.slot_ns;
        let clock = if master {
            SlotClock::master(&bus, start)
        } else {
            SlotClock::slave(&bus)
        };
        let mut wc_ns = [0; 9];
        let mut dlc = 0;
        while dlc < 9 {
            if let Some(w) = wc_ns.get_mut(dlc) {
                *w = bits_to_ns(worst_case_bits(dlc as u8), bus.bitrate);
            }
            dlc += 1;
        }
        Engine {
            tables,
            policy: Policy::OURS,
            counters: Counters::default(),
            clock,
            master,
            wc_ns,
            next_boundary: if master { start } else { Nanos::MAX },
            pos: Position {
                abs_cycle: 0,
                cycle_in_hyper: 0,
                counter: 0,
                next_slot: 0,
                start_local: start,
                start_bus: 0,
                // At least 1 ns per slot: boundaries always advance (even with
                // unchecked tables), so the walk in `poll` ends.
                slot_q16: bus.slot_ns.max(1) << 16,
                inv_q32: 1 << 32,
                heartbeat_in: tables.module % HEARTBEAT_CYCLES as u8,
            },
            cursor: CalendarCursor::default(),
            cycle_mask: 0,
            mask_cycle: u64::MAX,
            last_sync_cycle: 0,
            window_end: 0,
            mailboxes: [Loaded::Free; MAILBOXES],
            hrt: None,
            hrt_seq: 0,
            queue: EdfQueue::new(),
            in_flight: 0,
            heartbeat_pending: false,
            heartbeat_cycles: HEARTBEAT_CYCLES as u8,
            // The configured master keeps its masks to take mastership back after a yield.
            backup: if master {
                Some((0, tables.master_masks))
            } else {
                None
            },
            promote_at: Nanos::MAX,
            arbiter: if master {
                Arbiter::cold_master()
            } else {
                Arbiter::listening(None)
            },
            silent_since: now,
            cycle_ns: bus.cycle_ns(),
            sync_format: SyncFormat::new(bus.slots_per_cycle),
            error: ErrorState {
                tec: 0,
                rec: 0,
                bus_off: false,
            },
            tx_tid: [0; 256],
            rx_state: [RxState::default(); RX],
            arena: [0; ARENA],
        }
    }

    /// Like `new`, after `check_tables`.
    pub fn try_new(tables: NodeTables<'t>, now: Nanos) -> Result<Self, TablesError> {
        check_tables(&tables, RX, ARENA)?;
        Ok(Self::new(tables, now))
    }

    /// Heartbeat every `cycles` cycles (1..=`HEARTBEAT_CYCLES`, others clamped) instead of
    /// `HEARTBEAT_CYCLES`: a supervised robot (robot.toml `on_missing`) beats faster so
    /// that a dead module is missed within a few cycles (docs/SERVICES.md §1). The
    /// stagger by module index is kept. Call right after `new`.
    pub fn set_heartbeat_cycles(&mut self, cycles: u8) {
        let n = cycles.clamp(1, HEARTBEAT_CYCLES as u8);
        self.heartbeat_cycles = n;
        self.pos.heartbeat_in = self.tables.module % n;
    }

    /// Makes this slave backup master number `rank` (1 = first) with the masks of the
    /// hyperperiod (the generated `MASTER_MASKS`, identical for every module of a robot).
    /// After `arbiter::takeover_cycles(rank)` = `SYNC_LOSS_CYCLES + 2 * rank` cycles
    /// without hearing a sync — counted from start-up too, so a backup takes over a bus
    /// whose master never started — it becomes master, continuing the cycle numbering so
    /// that the hyperperiod phase and the slaves' calendars stay valid (docs/PROTOCOL.md
    /// §5.6). Ignored on the master, with rank 0 or without masks.
    pub fn set_backup(&mut self, rank: u8, masks: &'t [u64]) {
        if !self.master && rank > 0 && !masks.is_empty() {
            self.backup = Some((rank, masks));
            self.arbiter = Arbiter::listening(Some(rank));
            self.arm_takeover(self.silent_since);
        }
    }

    /// The configured master restarting into a bus that may already run (a watchdog or
    /// software reset, not a power-up): listen first, defer to a running master's sync
    /// (becoming a backup of rank 0), take over only after `SYNC_LOSS_CYCLES` silent
    /// cycles. Call right after `new`. Ignored on a slave.
    pub fn listen_first(&mut self) {
        if !self.master {
            return;
        }
        self.master = false;
        self.arbiter = Arbiter::listening(Some(0));
        self.clock = SlotClock::slave(&self.tables.bus);
        self.next_boundary = Nanos::MAX;
        self.arm_takeover(self.silent_since);
    }

    /// Takeover deadline: `takeover_cycles(rank)` cycles after `from` (the last sync heard,
    /// or start-up); never for a plain slave.
    // Inline: every sync on a slave runs it (issue 10's sync budget), and a plain slave's
    // deadline is one store; the backup's product is out of line (`takeover_deadline`).
    #[inline(always)]
    fn arm_takeover(&mut self, from: Nanos) {
        self.silent_since = from;
        self.promote_at = match self.arbiter.takeover_after() {
            Some(n) => self.takeover_deadline(from, n),
            None => Nanos::MAX,
        };
    }

    #[inline(never)]
    fn takeover_deadline(&self, from: Nanos, cycles: u32) -> Nanos {
        from.saturating_add(u64::from(cycles).saturating_mul(self.tables.bus.cycle_ns()))
    }

    /// This module's view of the bus is stale (it could not act for a whole cycle, or it
    /// was bus-off): withdraw everything, forget the slot clock, listen before sending
    /// again (a master steps down: arbitration rule 1).
    fn stall(&mut self, now: Nanos, can: &mut impl Controller, host: &mut impl Host) {
        self.arbiter.stalled();
        self.master = false;
        self.clock = SlotClock::slave(&self.tables.bus);
        self.withdraw_all(can);
        self.arm_takeover(now);
        host.event(Event::SyncLost);
    }

    /// Stops the slot sequence and aborts every loaded frame (they were placed on a clock
    /// that is no longer trusted).
    fn withdraw_all(&mut self, can: &mut impl Controller) {
        self.next_boundary = Nanos::MAX;
        self.window_end = 0;
        for (i, mb) in self.mailboxes.iter_mut().enumerate() {
            match mb {
                Loaded::Free => {}
                Loaded::Window {
                    abort_requested, ..
                } => {
                    if !*abort_requested {
                        *abort_requested = true;
                        can.abort(Mailbox(i as u8));
                    }
                }
                _ => can.abort(Mailbox(i as u8)),
            }
        }
    }

    /// True while this module sends the sync frame (the configured master, or a backup
    /// that took over).
    pub fn is_master(&self) -> bool {
        self.master
    }

    /// Selects the SRT policy (default `Policy::OURS`).
    pub fn set_policy(&mut self, policy: Policy) {
        self.policy = policy;
    }

    /// Counters.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    /// True on the master, and on a slave while it follows the master's sync. A slave
    /// starts transmitting only once it knows both offset and rate (second sync): with
    /// the offset alone, a 5000 ppm clock would be 50 us off by the end of a 10 ms cycle.
    pub fn is_synced(&self) -> bool {
        self.master || (self.clock.is_rate_valid() && self.next_boundary != Nanos::MAX)
    }

    /// The slot clock (bus time of a local instant: `clock().to_bus(now)`).
    pub fn clock(&self) -> &SlotClock {
        &self.clock
    }

    /// Messages waiting in the SRT/NRT queue (not counting frames in mailboxes).
    pub fn queued(&self) -> usize {
        self.queue.len()
    }

    /// Does everything due at local time `now` (slot boundaries, window closes) and
    /// returns the local time at which it must be called next. O(slots per cycle) however
    /// late it comes: whole cycles in the past are skipped arithmetically (counted in
    /// `cycles_skipped`, docs/PROTOCOL.md §5.8), never walked slot by slot.
    pub fn poll(&mut self, now: Nanos, can: &mut impl Controller, host: &mut impl Host) -> Nanos {
        self.abort_overdue(now, can);
        // Time test first: one add and compare on the per-slot path.
        if now >= self.next_boundary.saturating_add(self.cycle_ns)
            && self.arbiter.rank().is_some()
            && self.is_synced()
        {
            // A master-capable module that missed a whole cycle (stalled, or its partition
            // healed) may have been replaced: it listens before sending (§5.6).
            self.stall(now, can, host);
        }
        if !self.master && !self.is_synced() {
            if now < self.promote_at || self.error.bus_off {
                return self.next_wakeup();
            }
            if now >= self.promote_at.saturating_add(self.cycle_ns) {
                // Called more than a cycle after its takeover time: this module was
                // stalled and its silence count is stale; it listens again (§5.6 rule 1).
                self.arbiter.stalled();
                self.arm_takeover(now);
                return self.next_wakeup();
            }
            self.promote(now, host);
        }
        let slot_ns = self.tables.bus.slot_ns;
        while self.next_boundary <= now {
            // A boundary whose successor has also passed was missed (handler too late):
            // skip it rather than transmit into someone else's slot.
            // A late slot-0 boundary skips whole past cycles in O(1) (`slot_boundary`), so
            // at most two cycles of boundaries are ever walked.
            let late = self.next_boundary.saturating_add(slot_ns) <= now;
            self.slot_boundary(now, late, can, host);
            if !self.is_synced() {
                // Sync lost: next is a backup's takeover, if any.
                return self.promote_at;
            }
        }
        self.next_wakeup()
    }

    /// The local time `poll` must run next (slot boundary or a window-close abort).
    pub fn next_wakeup(&self) -> Nanos {
        if !self.is_synced() {
            // Unsynced: nothing to do before the next sync, or a backup's takeover (not
            // while bus-off: recovery re-arms it).
            return if self.error.bus_off {
                Nanos::MAX
            } else {
                self.promote_at
            };
        }
        let mut next = self.next_boundary;
        if self.in_flight == 0 {
            // No window frame loaded: nothing to abort (the common case on the slot path).
            return next;
        }
        for mb in self.mailboxes.iter() {
            if let Loaded::Window {
                latest_start,
                abort_requested: false,
                ..
            } = *mb
            {
                next = next.min(latest_start);
            }
        }
        next
    }

    fn abort_overdue(&mut self, now: Nanos, can: &mut impl Controller) {
        if self.in_flight == 0 {
            return;
        }
        for (i, mb) in self.mailboxes.iter_mut().enumerate() {
            if let Loaded::Window {
                latest_start,
                abort_requested,
                ..
            } = mb
            {
                if !*abort_requested && *latest_start <= now {
                    *abort_requested = true;
                    can.abort(Mailbox(i as u8));
                }
            }
        }
    }

    /// Handles the boundary `self.next_boundary` and advances to the next one.
    fn slot_boundary(
        &mut self,
        now: Nanos,
        late: bool,
        can: &mut impl Controller,
        host: &mut impl Host,
    ) {
        let spc = self.tables.bus.slots_per_cycle;
        if self.pos.next_slot >= spc {
            self.next_cycle();
        }
        let slot = self.pos.next_slot;
        let hyper_slot = self.pos.cycle_in_hyper * spc as u32 + slot as u32;
        self.pos.next_slot = slot + 1;
        self.next_boundary = self.pos.boundary(slot + 1);
        self.window_end = 0;

        let own = self.cursor.take(self.tables.calendar, hyper_slot).copied();
        if slot == 0 {
            // A late cycle start may be whole cycles behind `now`: skip them (the landing
            // cycle's slot 0 is then handled on the next round of `poll`'s walk).
            if late && self.skip_missed_cycles(now, host) {
                return;
            }
            self.start_cycle(late, can, host);
            return;
        }
        if late {
            if let Some(entry) = own {
                Counters::bump(&mut self.counters.hrt_late);
                self.abandon_hrt(entry.tx, host);
            }
            return;
        }
        if let Some(entry) = own {
            self.load_hrt(entry.tx, entry.fragment, can, host);
            return;
        }
        if self.mask_cycle != self.pos.abs_cycle || self.cycle_mask & (1u64 << slot) != 0 {
            // Reserved by another module, or this cycle's mask is unknown (no sync yet):
            // stay silent.
            return;
        }
        if self.policy.refresh_laxity && self.in_flight > 0 {
            self.refresh_laxities(now, can);
        }
        let run = free_run(self.cycle_mask, slot, spc);
        self.window_end = self
            .pos
            .boundary(slot + run)
            .saturating_sub(self.tables.bus.guard_ns);
        self.refill(now, can, host);
    }

    /// Aborts waiting SRT frames whose laxity code has become more urgent (or whose
    /// deadline passed); `on_tx_done(Aborted)` re-queues them and the refill reloads
    /// them with a fresh code (or drops them as missed).
    fn refresh_laxities(&mut self, now: Nanos, can: &mut impl Controller) {
        let now_bus = self.bus_time(now);
        let encoding = self.tables.bus.laxity;
        for (i, mb) in self.mailboxes.iter_mut().enumerate() {
            if let Loaded::Window {
                item: Item::Topic { deadline, .. },
                key,
                abort_requested,
                laxity,
                ..
            } = mb
            {
                if *key == NRT_KEY || *abort_requested {
                    continue;
                }
                let fresh = encoding.encode(*deadline as SNanos - now_bus as SNanos);
                if fresh.is_none_or(|c| c < *laxity) {
                    *abort_requested = true;
                    can.abort(Mailbox(i as u8));
                }
            }
        }
    }

    /// Backup takeover: this module becomes master one slot from now. The cycle count
    /// continues from the last cycle it executed (so `abs_cycle mod hyperperiod` and the
    /// sync counter stay consistent with what slaves knew), on this module's own clock.
    fn promote(&mut self, now: Nanos, host: &mut impl Host) {
        let bus = self.tables.bus;
        let cycle = bus.cycle_ns().max(1);
        let silent = now.saturating_sub(self.silent_since) / cycle;
        let Some((_, masks)) = self.backup.filter(|_| {
            self.arbiter
                .silence(u32::try_from(silent).unwrap_or(u32::MAX))
                == Step::TakeOver
        }) else {
            // Not yet (a timer that fired early) or never (a plain slave).
            self.arm_takeover(self.silent_since);
            return;
        };
        let start_local = now.saturating_add(bus.slot_ns);
        let elapsed = start_local.saturating_sub(self.pos.start_local);
        let c0 = self.pos.abs_cycle + elapsed.div_ceil(cycle).max(1);
        self.master = true;
        self.tables.master_masks = masks;
        self.clock = SlotClock::master(&bus, start_local.saturating_sub(c0.saturating_mul(cycle)));
        self.enter_cycle(c0, 0, self.clock.cycle_start_bus(c0));
        self.pos.start_local = start_local;
        self.pos.slot_q16 = bus.slot_ns.max(1) << 16;
        self.pos.inv_q32 = 1 << 32;
        self.next_boundary = start_local;
        self.promote_at = Nanos::MAX;
        host.event(Event::Synced);
    }

    /// Called at a late slot-0 boundary of cycle `a` (not started yet). When `now` is at or
    /// past the start of cycle `a + 2` (a forward jump of the local clock, or a stall),
    /// moves the position to slot 0 of the cycle containing `now` in O(1): exactly where
    /// handling every boundary would have put it (each cycle advances the local map by
    /// the same `cycle_local`), minus the per-slot work. The cycles none of whose slots
    /// ran count in `cycles_skipped`; the HRT transfer in progress is abandoned (its slots
    /// passed). The landing cycle's passed boundaries are then handled (late) by `poll`: a
    /// slave past `SYNC_LOSS_CYCLES` without sync reports the loss there. Returns whether
    /// it moved. Within three cycles of `Nanos::MAX` the boundaries would saturate: the
    /// engine stops there (`stop_at_end_of_time`). Cold and out of line: it must not
    /// weigh on `poll`.
    #[cold]
    #[inline(never)]
    fn skip_missed_cycles(&mut self, now: Nanos, host: &mut impl Host) -> bool {
        let bus = &self.tables.bus;
        let next_start = self.pos.boundary(bus.slots_per_cycle);
        let cycle_local = next_start.saturating_sub(self.pos.start_local).max(1);
        if next_start.saturating_add(cycle_local) > now {
            return false; // less than a whole cycle to walk: walk it
        }
        // `now >= start_local + 2 cycles` here, and `ahead * cycle_local <= now - start_local`.
        // Cycles `a .. a + ahead` are skipped (`a` never started).
        let ahead = (now - self.pos.start_local) / cycle_local;
        let skipped = ahead;
        let abs = self.pos.abs_cycle.saturating_add(ahead);
        self.enter_cycle(abs, 0, self.clock.cycle_start_bus(abs));
        let p = &mut self.pos;
        p.start_local += ahead * cycle_local;
        // Keep the heartbeat stagger; a heartbeat due in a skipped cycle goes out next.
        let beats = self.heartbeat_cycles;
        let due_in = p.heartbeat_in % beats;
        let back = (skipped % u64::from(beats)) as u8;
        p.heartbeat_in = (due_in + beats - back) % beats;
        if skipped > u64::from(due_in) {
            self.heartbeat_pending = true;
        }
        self.next_boundary = p.start_local;
        self.window_end = 0;
        Counters::add(&mut self.counters.cycles_skipped, skipped);
        if let Some(x) = self.hrt {
            self.abandon_hrt(x.tx, host);
        }
        if (Nanos::MAX - self.pos.start_local) / 3 < cycle_local {
            self.stop_at_end_of_time();
        }
        true
    }

    /// Moves the position to absolute cycle `abs_cycle`, resuming at `next_slot`: the
    /// derived counters (hyperperiod phase, sync counter), its bus start `start_bus`
    /// (`clock.cycle_start_bus(abs_cycle)`, which a sync has at hand as the clock's
    /// anchor) and the calendar cursor. The caller sets the local map. One copy of these
    /// divisions for sync, takeover and skip.
    #[inline(never)]
    fn enter_cycle(&mut self, abs_cycle: u64, next_slot: u8, start_bus: Nanos) {
        let bus = &self.tables.bus;
        let p = &mut self.pos;
        p.abs_cycle = abs_cycle;
        p.cycle_in_hyper = mod_small(abs_cycle, bus.hyperperiod_cycles);
        p.counter = mod_small(abs_cycle, bus.cycle_counter_wrap);
        p.start_bus = start_bus;
        p.next_slot = next_slot;
        self.cursor = CalendarCursor::default();
    }

    /// Less than three cycles are left before `Nanos::MAX` (584 years of local time, so
    /// only reached by a clock jump): boundaries would saturate and never pass, so the
    /// engine stops for good: no boundaries, not synced (a master included), silent.
    fn stop_at_end_of_time(&mut self) {
        self.master = false;
        self.clock.unlock();
        self.backup = None;
        self.promote_at = Nanos::MAX;
        self.next_boundary = Nanos::MAX;
        self.window_end = 0;
    }

    /// Moves the position to slot 0 of the next cycle, extrapolating the local map.
    fn next_cycle(&mut self) {
        // Borrow, not copy: `BusConfig` is a dozen words and this runs every cycle.
        let bus = &self.tables.bus;
        let p = &mut self.pos;
        p.start_local = p.boundary(bus.slots_per_cycle);
        p.start_bus = p.start_bus.saturating_add(bus.cycle_ns());
        p.abs_cycle = p.abs_cycle.saturating_add(1);
        p.cycle_in_hyper += 1;
        if p.cycle_in_hyper >= bus.hyperperiod_cycles {
            p.cycle_in_hyper = 0;
        }
        p.counter += 1;
        if p.counter >= bus.cycle_counter_wrap {
            p.counter = 0;
        }
        p.next_slot = 0;
    }

    /// Bus time of local time `local`: from the cycle map when close to the current
    /// cycle (multiply and shift), else from the slot clock.
    fn bus_time(&self, local: Nanos) -> Nanos {
        match local.checked_sub(self.pos.start_local) {
            Some(d) if d < 1 << 30 => self
                .pos
                .start_bus
                .saturating_add((d * self.pos.inv_q32) >> 32),
            _ => self.clock.to_bus(local),
        }
    }

    fn start_cycle(&mut self, late: bool, can: &mut impl Controller, host: &mut impl Host) {
        if self.master {
            let idx = self.pos.cycle_in_hyper as usize;
            self.cycle_mask = self
                .tables
                .master_masks
                .get(idx)
                .copied()
                .unwrap_or(u64::MAX)
                | 1;
            self.mask_cycle = self.pos.abs_cycle;
            let cycle = self.pos.counter as u16;
            // A sync still waiting from an earlier cycle (the bus was held, e.g. stuck
            // dominant) is stale: sent now it would place this cycle's slots at the wrong
            // time, next to this cycle's own sync (docs/PROTOCOL.md §5.6).
            for (i, mb) in self.mailboxes.iter().enumerate() {
                if matches!(mb, Loaded::Sync) {
                    can.abort(Mailbox(i as u8));
                }
            }
            if !late {
                let frame = sync_frame(
                    Sync {
                        cycle,
                        mask: self.cycle_mask,
                    },
                    self.tables.bus.slots_per_cycle,
                );
                self.load_any(Loaded::Sync, &frame, can);
            }
        } else {
            // The mask of this cycle arrives with its sync frame (during slot 0).
            let abs_cycle = self.pos.abs_cycle;
            if abs_cycle > self.last_sync_cycle + 1 {
                Counters::bump(&mut self.counters.sync_missed);
            }
            if abs_cycle >= self.last_sync_cycle + SYNC_LOSS_CYCLES {
                // The slot clock can no longer be trusted: stop transmitting until the
                // next sync frame restarts the slot sequence.
                // Frames still waiting were placed on that clock: withdraw them. A
                // master-capable module's takeover is armed from the last sync it heard.
                self.withdraw_all(can);
                host.event(Event::SyncLost);
                return;
            }
        }
        host.event(Event::CycleStart);
        if self.pos.heartbeat_in == 0 {
            self.pos.heartbeat_in = self.heartbeat_cycles;
            self.heartbeat_pending = true;
        }
        self.pos.heartbeat_in -= 1;
    }

    fn load_any(&mut self, what: Loaded, frame: &Frame, can: &mut impl Controller) -> bool {
        for (i, mb) in self.mailboxes.iter_mut().enumerate() {
            if *mb == Loaded::Free {
                *mb = what;
                can.load(Mailbox(i as u8), frame);
                return true;
            }
        }
        false
    }

    /// Stops loading the current HRT transfer if it is of topic `tx`; reports it missed
    /// unless its last fragment's mailbox already owns the report. Out of line: only
    /// failure paths call it, and it inlines the host's dispatch.
    #[inline(never)]
    fn abandon_hrt(&mut self, tx: u8, host: &mut impl Host) {
        if let Some(x) = self.hrt.take() {
            if x.tx != tx {
                self.hrt = Some(x);
            } else if !x.last_loaded {
                host.tx_done(x.tx, Some(x.token), TxOutcome::DeadlineMissed);
            }
        }
    }

    fn load_hrt(&mut self, tx: u8, fragment: u8, can: &mut impl Controller, host: &mut impl Host) {
        let Some(topic) = self.tables.tx.get(tx as usize).copied() else {
            return;
        };
        let count = fragment_count(topic.size as usize);
        if fragment + 1 == count {
            // First fragment: sample the latest value and latch it for the whole transfer.
            // The previous transfer is done loading: missed if it never got its last
            // fragment loaded, else its last mailbox reports it when it completes.
            if let Some(stale) = self.hrt.take() {
                if !stale.last_loaded {
                    host.tx_done(stale.tx, Some(stale.token), TxOutcome::DeadlineMissed);
                }
            }
            match host.hrt_sample(tx) {
                Some(token) => {
                    self.hrt = Some(HrtTransfer {
                        tx,
                        token,
                        tid: next_tid(&mut self.tx_tid, tx),
                        seq: self.hrt_seq,
                        last_loaded: false,
                    });
                    self.hrt_seq = self.hrt_seq.wrapping_add(1);
                }
                None => {
                    Counters::bump(&mut self.counters.hrt_empty);
                    host.tx_done(tx, None, TxOutcome::NothingToSend);
                    return;
                }
            }
        }
        let Some(x) = self.hrt.as_mut().filter(|x| x.tx == tx) else {
            return;
        };
        let payload = host.payload(x.token);
        let (token, seq) = (x.token, x.seq);
        let mut data = [0u8; 8];
        let dlc = fragment_data(payload, fragment, &mut data);
        let field = fragment_field(count, x.tid, fragment);
        let Some(id) = CanId::new(LAXITY_HRT, topic.msg_id, field) else {
            return;
        };
        let Some(frame) = Frame::from_parts(id, dlc, data) else {
            return;
        };
        if !self.load_any(
            Loaded::Hrt {
                tx,
                token,
                fragment,
                seq,
                broken: false,
            },
            &frame,
            can,
        ) {
            Counters::bump(&mut self.counters.hrt_late);
            self.abandon_hrt(tx, host);
        } else if fragment == 0 {
            if let Some(x) = self.hrt.as_mut() {
                x.last_loaded = true;
            }
        }
    }

    /// Fills free mailboxes with window frames that can finish before the window ends.
    fn refill(&mut self, now: Nanos, can: &mut impl Controller, host: &mut impl Host) {
        if self.window_end <= now
            || (self.queue.is_empty()
                && !self.heartbeat_pending
                && (host.service_tx().is_none() || self.service_loaded()))
        {
            return;
        }
        let now_bus = self.bus_time(now);
        let remaining = self.window_end - now;
        while let Some(free) = self.mailboxes.iter().position(|m| *m == Loaded::Free) {
            if self.policy.keep_tdma_mailbox && self.in_flight >= MAILBOXES - 1 {
                break;
            }
            let Some((key, mut item)) = self.pick(now_bus, remaining, host) else {
                break;
            };
            let (frame, dlc) = match item {
                Item::Heartbeat => {
                    let hb = Heartbeat {
                        module: self.tables.module,
                        state: host.module_state(),
                        fingerprint: self.tables.bus.fingerprint,
                    };
                    match heartbeat_frame(hb) {
                        Some(f) => (f, f.dlc()),
                        None => continue,
                    }
                }
                Item::Service { .. } => match host.service_tx() {
                    Some(f) => (f, f.dlc()),
                    None => continue,
                },
                Item::Topic {
                    tx,
                    token,
                    fragment,
                    ref mut tid,
                    deadline,
                } => {
                    let Some(topic) = self.tables.tx.get(tx as usize) else {
                        continue;
                    };
                    let laxity = if key == NRT_KEY {
                        LAXITY_NRT
                    } else {
                        let lax = deadline as SNanos - now_bus as SNanos;
                        match self.tables.bus.laxity.encode(lax) {
                            Some(code) => code,
                            None => {
                                self.drop_missed(tx, token, host);
                                continue;
                            }
                        }
                    };
                    let payload = host.payload(token);
                    let mut data = [0u8; 8];
                    let dlc = fragment_data(payload, fragment, &mut data);
                    // The transfer takes its ID when its first fragment is first loaded,
                    // so two transfers of a topic loaded together get different IDs.
                    let tid = *tid.get_or_insert_with(|| next_tid(&mut self.tx_tid, tx));
                    let count = fragment_count(topic.size as usize);
                    let field = fragment_field(count, tid, fragment);
                    let Some(id) = CanId::new(laxity, topic.msg_id, field) else {
                        continue;
                    };
                    match Frame::from_parts(id, dlc, data) {
                        Some(f) => (f, dlc),
                        None => continue,
                    }
                }
            };
            let wc = self.wc(dlc);
            let latest_start = self.window_end.saturating_sub(wc);
            if let Some(mb) = self.mailboxes.get_mut(free) {
                *mb = Loaded::Window {
                    item,
                    key,
                    latest_start,
                    abort_requested: false,
                    laxity: frame.id().laxity(),
                };
            }
            self.in_flight += 1;
            can.load(Mailbox(free as u8), &frame);
        }
    }

    /// The next window item: the EDF head if it fits the remaining window time, else
    /// (policy permitting) the most urgent one that fits; drops hopeless messages.
    fn pick(
        &mut self,
        now_bus: Nanos,
        remaining: Nanos,
        host: &mut impl Host,
    ) -> Option<(u64, Item)> {
        let wc8 = self.wc(8);
        while let Some((key, head)) = self.queue.peek().map(|(k, i)| (k, *i)) {
            if let Item::Topic {
                tx,
                token,
                fragment,
                deadline,
                ..
            } = head
            {
                // Hopeless: even sent back to back from now, the remaining fragments
                // cannot all finish before the deadline.
                let need = (fragment as Nanos + 1) * wc8;
                if key != NRT_KEY
                    && (deadline < now_bus
                        || (self.policy.drop_hopeless && deadline - now_bus < need))
                {
                    self.queue.pop();
                    self.drop_missed(tx, token, host);
                    continue;
                }
            }
            if self.item_wc(&head) < remaining && !waits_for_topic(&head, &self.mailboxes) {
                return self.queue.pop();
            }
            break;
        }
        if self.policy.fit_window_end {
            let wc = self.wc_ns;
            let tables = self.tables;
            let mailboxes = &self.mailboxes;
            if let Some(found) = self.queue.pop_first_matching(|_, item| {
                item_dlc(item, &tables)
                    .and_then(|d| wc.get(d as usize))
                    .is_some_and(|w| *w < remaining)
                    && !waits_for_topic(item, mailboxes)
            }) {
                return Some(found);
            }
        }
        if self.heartbeat_pending && self.wc(5) < remaining {
            self.heartbeat_pending = false;
            return Some((NRT_KEY, Item::Heartbeat));
        }
        // The update channel last: below every message and the heartbeat, one frame in
        // a mailbox at a time (in order on the wire, docs/PROTOCOL.md §2.3).
        // (The host is asked first: a host without the channel answers `None` inline,
        // and the mailbox scan is skipped.)
        if let Some(f) = host.service_tx() {
            if self.service_loaded() {
                return None;
            }
            if !crate::service::sendable(&f) {
                host.service_sent();
            } else if self.wc(f.dlc()) < remaining {
                return Some((NRT_KEY, Item::Service { dlc: f.dlc() }));
            }
        }
        None
    }

    /// Whether an update-channel frame is in a mailbox.
    fn service_loaded(&self) -> bool {
        self.mailboxes.iter().any(|m| {
            matches!(
                m,
                Loaded::Window {
                    item: Item::Service { .. },
                    ..
                }
            )
        })
    }

    fn item_wc(&self, item: &Item) -> Nanos {
        item_dlc(item, &self.tables).map_or(Nanos::MAX, |d| self.wc(d))
    }

    /// Worst-case duration of a frame with `dlc` data bytes.
    fn wc(&self, dlc: u8) -> Nanos {
        self.wc_ns.get(dlc as usize).copied().unwrap_or(Nanos::MAX)
    }

    fn drop_missed(&mut self, tx: u8, token: Token, host: &mut impl Host) {
        Counters::bump(&mut self.counters.deadline_missed);
        host.tx_done(tx, Some(token), TxOutcome::DeadlineMissed);
    }

    /// A frame passed the filters; `sof` is its start-of-frame local timestamp.
    pub fn on_rx(
        &mut self,
        frame: &Frame,
        sof: Nanos,
        can: &mut impl Controller,
        host: &mut impl Host,
    ) {
        let id = frame.id();
        if id.is_sync() {
            // A bus-off controller receives nothing; a driver that still hands frames
            // over must not relock the module before its recovery.
            if !self.error.bus_off {
                self.on_sync(frame, sof, can, host);
            }
            return;
        }
        let msg = id.msg_id().0;
        if crate::service::is_service(id.msg_id()) {
            // The update channel: the protocol is the host's (docs/SERVICES.md §4).
            host.service_rx(frame, sof);
            return;
        }
        if (HEARTBEAT_BASE..FIRST_TOPIC_MSG_ID).contains(&msg) {
            match parse_heartbeat(frame) {
                Some(hb) if hb.fingerprint != self.tables.bus.fingerprint => {
                    host.event(Event::FingerprintMismatch {
                        module: hb.module,
                        fingerprint: hb.fingerprint,
                    })
                }
                Some(hb) => host.event(Event::Heartbeat {
                    module: hb.module,
                    state: hb.state,
                }),
                None => Counters::bump(&mut self.counters.rx_bad_heartbeat),
            }
            return;
        }
        let Ok(idx) = self
            .tables
            .rx
            .binary_search_by_key(&id.msg_id(), |t| t.msg_id)
        else {
            Counters::bump(&mut self.counters.rx_unknown_id);
            return;
        };
        let (Some(topic), Some(state)) = (self.tables.rx.get(idx), self.rx_state.get_mut(idx))
        else {
            Counters::bump(&mut self.counters.rx_unknown_id);
            return;
        };
        // Exactly this topic's `wire_len` bytes, not the rest of the arena
        // (`check_tables` rules out overlaps); a buffer outside the arena drops the frame.
        let start = topic.arena_offset as usize;
        let end = start + crate::fragment::wire_len(topic.size as usize);
        let Some(buf) = self.arena.get_mut(start..end) else {
            Counters::bump(&mut self.counters.rx_bad_size);
            return;
        };
        match state.step(buf, topic.size as usize, frame, sof) {
            RxStep::Pending => {}
            RxStep::Restarted => Counters::bump(&mut self.counters.rx_incomplete),
            RxStep::Complete(payload, first_sof) => {
                Counters::bump(&mut self.counters.rx_delivered);
                host.deliver(idx as u8, payload, first_sof);
            }
            RxStep::Dropped(why) => Counters::bump(match why {
                crate::fragment::RxDrop::BadDlc => &mut self.counters.rx_bad_dlc,
                crate::fragment::RxDrop::OutOfOrder => &mut self.counters.rx_out_of_order,
                crate::fragment::RxDrop::OtherTransfer => &mut self.counters.rx_other_transfer,
                crate::fragment::RxDrop::BadSize => &mut self.counters.rx_bad_size,
            }),
        }
        let _ = can;
    }

    fn on_sync(
        &mut self,
        frame: &Frame,
        sof: Nanos,
        can: &mut impl Controller,
        host: &mut impl Host,
    ) {
        let Some(sync) = self.sync_format.parse(frame) else {
            Counters::bump(&mut self.counters.rx_bad_sync);
            return;
        };
        if self.arbiter.foreign_sync() == Step::Yield {
            // Another master: step down at once and follow it; if it yielded too, the
            // ranked takeover elects one of us (§5.6).
            Counters::bump(&mut self.counters.master_yields);
            self.master = false;
            self.clock = SlotClock::slave(&self.tables.bus);
            self.withdraw_all(can);
            host.event(Event::SyncLost);
        }
        let was_synced = self.is_synced();
        // A master's sync (the configured one or a better-ranked backup) restarts the
        // takeover countdown.
        self.arm_takeover(sof);
        if !self.clock.on_sync(sof, sync.cycle) {
            return;
        }
        let slot_ns = self.tables.bus.slot_ns;
        // At the sync just handled the cycle map starts at the clock's anchor.
        let (abs_cycle, start_bus, start_local) = match self.clock.anchor_cycle(sof) {
            Some(c) => c,
            None => {
                let abs = self.clock.nearest_cycle(sof);
                let bus = self.clock.cycle_start_bus(abs);
                (abs, bus, self.clock.to_local(bus))
            }
        };
        self.last_sync_cycle = abs_cycle;
        self.cycle_mask = sync.mask;
        self.mask_cycle = abs_cycle;
        if !was_synced || abs_cycle != self.pos.abs_cycle {
            // (Re)start the slot sequence at slot 1 of this cycle: first lock, or the sync
            // is not for the cycle this node is executing (its clock ran slow, or a jump).
            self.enter_cycle(abs_cycle, 1, start_bus);
        }
        // Refresh the cycle map from the slot clock: offset from this SOF, slot length and
        // inverse from the rate factors (multiplies; no division when this sync follows
        // the last one by a cycle, `SlotClock::on_sync`).
        self.pos.start_bus = start_bus;
        self.pos.start_local = start_local;
        self.pos.slot_q16 = self.clock.local_q16(slot_ns).max(1 << 16);
        self.pos.inv_q32 = self.clock.bus_per_local_q32();
        self.next_boundary = self.pos.boundary(self.pos.next_slot);
        if !was_synced && self.is_synced() {
            host.event(Event::Synced);
        }
    }

    /// Mailbox `mailbox` finished with `result` at local time `now`.
    pub fn on_tx_done(
        &mut self,
        mailbox: Mailbox,
        result: TxResult,
        now: Nanos,
        can: &mut impl Controller,
        host: &mut impl Host,
    ) {
        let Some(slot) = self.mailboxes.get_mut(mailbox.0 as usize) else {
            return;
        };
        let what = core::mem::replace(slot, Loaded::Free);
        match result {
            TxResult::Sent => Counters::bump(&mut self.counters.tx_frames),
            TxResult::Aborted => Counters::bump(&mut self.counters.tx_aborted),
            TxResult::Failed => Counters::bump(&mut self.counters.tx_failed),
        }
        match what {
            Loaded::Free | Loaded::Sync => {}
            Loaded::Hrt {
                tx,
                token,
                fragment,
                seq,
                broken,
            } => {
                let current = self.hrt.filter(|x| x.seq == seq);
                if fragment == 0 {
                    // The last fragment's mailbox owns the report, whether or not the
                    // transfer is still the current one (a retransmission may end after
                    // the next transfer started, and the host may reuse the token).
                    if current.is_some() {
                        self.hrt = None;
                    }
                    let outcome = if result == TxResult::Sent && !broken {
                        TxOutcome::Sent
                    } else {
                        TxOutcome::DeadlineMissed
                    };
                    host.tx_done(tx, Some(token), outcome);
                } else if result != TxResult::Sent {
                    // An earlier fragment failed: receivers will drop the transfer.
                    for mb in self.mailboxes.iter_mut() {
                        if let Loaded::Hrt {
                            seq: s,
                            fragment: 0,
                            broken,
                            ..
                        } = mb
                        {
                            if *s == seq {
                                *broken = true;
                            }
                        }
                    }
                    if current.is_some() {
                        self.abandon_hrt(tx, host);
                    }
                }
            }
            Loaded::Window { item, key, .. } => {
                self.in_flight = self.in_flight.saturating_sub(1);
                match (item, result) {
                    (Item::Heartbeat, TxResult::Sent) => {}
                    (Item::Heartbeat, _) => self.heartbeat_pending = true,
                    // Not sent: offered again by the host at the next refill.
                    (Item::Service { .. }, TxResult::Sent) => host.service_sent(),
                    (Item::Service { .. }, _) => {}
                    (
                        Item::Topic {
                            tx,
                            token,
                            fragment: 0,
                            ..
                        },
                        TxResult::Sent,
                    ) => {
                        host.tx_done(tx, Some(token), TxOutcome::Sent);
                    }
                    (
                        Item::Topic {
                            tx,
                            token,
                            fragment,
                            tid,
                            deadline,
                        },
                        r,
                    ) => {
                        // Next fragment after a success; the same one again after an abort
                        // or a lost arbitration. Laxity is re-encoded when it is loaded.
                        let fragment = if r == TxResult::Sent {
                            fragment - 1
                        } else {
                            fragment
                        };
                        let next = Item::Topic {
                            tx,
                            token,
                            fragment,
                            tid,
                            deadline,
                        };
                        if self.queue.push(key, next).is_err() {
                            // Cannot happen: submit keeps room for every frame in flight.
                            self.drop_missed(tx, token, host);
                        }
                    }
                }
            }
        }
        self.refill(now, can, host);
    }

    /// Queues an SRT/NRT message of topic `tx` (deadline = now + topic deadline).
    pub fn submit(
        &mut self,
        now: Nanos,
        tx: u8,
        token: Token,
        can: &mut impl Controller,
        host: &mut impl Host,
    ) -> Result<(), SubmitError> {
        let topic = self
            .tables
            .tx
            .get(tx as usize)
            .ok_or(SubmitError::NotSubmittable)?;
        let payload = host.payload(token);
        if topic.class == Class::Hrt || payload.len() != topic.size as usize {
            return Err(SubmitError::NotSubmittable);
        }
        if self.queue.len() + self.in_flight >= Q {
            Counters::bump(&mut self.counters.queue_full);
            return Err(SubmitError::QueueFull);
        }
        let fragment = fragment_count(payload.len()).saturating_sub(1);
        let (key, deadline) = match topic.class {
            Class::Srt => {
                let d = self.bus_time(now).saturating_add(topic.deadline_ns);
                (d, d)
            }
            _ => (NRT_KEY, NRT_KEY),
        };
        self.queue
            .push(
                key,
                Item::Topic {
                    tx,
                    token,
                    fragment,
                    tid: None,
                    deadline,
                },
            )
            .map_err(|_| SubmitError::QueueFull)?;
        self.refill(now, can, host);
        Ok(())
    }

    /// The driver saw an RX FIFO overrun.
    pub fn on_rx_overrun(&mut self) {
        Counters::bump(&mut self.counters.rx_overrun);
    }

    /// The controller's fault-confinement state changed (docs/PROTOCOL.md §5.7), at local
    /// time `now`. Entering error-passive is counted (`error_passive`); the module keeps
    /// its slots. Entering bus-off is counted (`bus_off`) and stops the module: every
    /// mailbox is withdrawn, a master steps down, `Event::SyncLost` is reported, and
    /// nothing is sent — not even a takeover — until the driver reports the recovery;
    /// then the module rejoins like a slave (two syncs) or, master-capable, listens
    /// first (§5.6).
    pub fn on_error_state(
        &mut self,
        now: Nanos,
        state: ErrorState,
        can: &mut impl Controller,
        host: &mut impl Host,
    ) {
        let (was, is) = (self.error.level(), state.level());
        self.error = state;
        match (was, is) {
            (Level::Active, Level::Passive) => Counters::bump(&mut self.counters.error_passive),
            (Level::Active | Level::Passive, Level::BusOff) => {
                Counters::bump(&mut self.counters.bus_off);
                self.stall(now, can, host);
            }
            // Recovered: listen again from now.
            (Level::BusOff, _) => self.arm_takeover(now),
            _ => {}
        }
    }

    /// Last fault-confinement state reported by the driver (TEC, REC, bus-off); the
    /// entry counts are `counters().error_passive` and `counters().bus_off`.
    pub fn error_state(&self) -> ErrorState {
        self.error
    }
}

/// True for a transfer not started yet (no transfer ID) whose topic has a frame in a
/// mailbox: it must wait, or the two transfers' fragments would interleave on the wire
/// and receivers would drop both (docs/PROTOCOL.md §7.1). Scans the mailboxes only for
/// a transfer not started yet.
fn waits_for_topic(item: &Item, mailboxes: &[Loaded; MAILBOXES]) -> bool {
    let Item::Topic { tx, tid: None, .. } = *item else {
        return false;
    };
    mailboxes.iter().any(|m| match m {
        Loaded::Window {
            item: Item::Topic { tx: other, .. },
            ..
        } => *other == tx,
        _ => false,
    })
}

/// Takes the next transfer ID of topic `tx` (wrapping: the field keeps its low bits).
fn next_tid(tx_tid: &mut [u8; 256], tx: u8) -> u8 {
    match tx_tid.get_mut(usize::from(tx)) {
        Some(t) => {
            let id = *t;
            *t = t.wrapping_add(1);
            id
        }
        None => 0, // unreachable: 256 entries for a u8 index
    }
}

/// `x mod m` (`m` 0 read as 1): a 32-bit division (one instruction on the Cortex-M3)
/// while `x` fits in 32 bits, a 64-bit library call only after that.
fn mod_small(x: u64, m: u32) -> u32 {
    let m = m.max(1);
    match u32::try_from(x) {
        Ok(x) => x % m,
        Err(_) => (x % u64::from(m)) as u32,
    }
}

/// DLC of the next frame of a queued item.
fn item_dlc(item: &Item, tables: &NodeTables<'_>) -> Option<u8> {
    match *item {
        Item::Heartbeat => Some(5),
        Item::Service { dlc } => Some(dlc),
        Item::Topic { tx, fragment, .. } => {
            let size = tables.tx.get(tx as usize)?.size as usize;
            let wire = crate::fragment::wire_len(size);
            let count = fragment_count(size) as usize;
            let index = count.checked_sub(fragment as usize + 1)?;
            Some(wire.saturating_sub(index * 8).min(8) as u8)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::mod_small;

    #[test]
    fn mod_small_matches_u64_remainder_on_both_paths() {
        for x in [
            0,
            1,
            99,
            u64::from(u32::MAX),
            1 << 32,
            (1 << 40) + 7,
            u64::MAX,
        ] {
            for m in [1, 3, 10, 32_768, u32::MAX] {
                assert_eq!(u64::from(mod_small(x, m)), x % u64::from(m), "{x} mod {m}");
            }
        }
        assert_eq!(mod_small(7, 0), 0, "0 is read as 1");
    }
}
