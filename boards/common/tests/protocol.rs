//! The split architecture's protocol task around a real engine, on the host: frames
//! reach the controller only when the slot timer commits the prepared plan (at its
//! boundary, never during preparation), bus-off drops the plan and mutes the module
//! until recovery, the RX path's stamps and bad input.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use rtcan_board_common::protocol::{
    Alarm, AlarmSetting, Direct, RxEvent, SlotCore, SlotTimerHw, Stamps, TxEvent,
};
use rtcan_board_common::{Protocol, SlotPlan, TxImage, TxPort};
use rtcan_core::driver::{Event, Host, Mailbox, Token, TxOutcome, TxResult};
use rtcan_core::engine::Engine;
use rtcan_core::frame::Frame;
use rtcan_core::id::{CanId, Class, MsgId};
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::tables::{BusConfig, CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_core::time::Nanos;
use rtcan_core::timing::{worst_case_bits, INTERMISSION_BITS};

const SLOT: Nanos = 200_000;
const TICK: Nanos = 125;
const LEAD: Nanos = SLOT / 2;
const HRT_ID: MsgId = MsgId(0x0144);
const RX_ID: MsgId = MsgId(0x0150);

const BUS: BusConfig = BusConfig {
    bitrate: 1_000_000,
    slots_per_cycle: 10,
    slot_ns: SLOT,
    hyperperiod_cycles: 1,
    cycle_counter_wrap: 1 << 15,
    laxity: LaxityEncoding::Linear {
        unit_ns: SLOT as u32,
    },
    guard_ns: 10_000,
    fingerprint: 0x1234_5678,
};
const TX: [TxTopic; 1] = [TxTopic {
    msg_id: HRT_ID,
    class: Class::Hrt,
    size: 4,
    deadline_ns: 0,
}];
const CAL: [CalEntry; 1] = [CalEntry {
    slot: 3,
    tx: 0,
    fragment: 0,
}];
const RX: [RxTopic; 1] = [RxTopic {
    msg_id: RX_ID,
    size: 4,
    arena_offset: 0,
}];
// Slot 0 (sync) and slot 3 reserved.
const MASKS: [u64; 1] = [0b1001];

fn master_tables() -> NodeTables<'static> {
    NodeTables {
        bus: BUS,
        module: 0,
        tx: &TX,
        rx: &RX,
        calendar: &CAL,
        master_masks: &MASKS,
    }
}

struct Timer {
    now: Nanos,
    /// Tick of the commit compare's match (`advance` runs the slot timer then).
    commit: Option<u64>,
    prepare: Option<u64>,
    /// Alarms raised in software (armed when due, or rescued after a lost match).
    raised: u32,
    /// The protocol task is preempted right after arming the commit compare: the clock
    /// jumps to this time then (its next reading sees it).
    jump_at_commit_arm: Option<Nanos>,
}

impl Timer {
    /// A raised alarm fires at the current time (rounded up to the next tick).
    fn raise(&mut self, alarm: Alarm) {
        self.raised += 1;
        let at = Some(self.now.div_ceil(TICK));
        match alarm {
            Alarm::Commit => self.commit = at,
            Alarm::Prepare => self.prepare = at,
        }
    }
}

impl SlotTimerHw for Timer {
    fn ticks(&self) -> u64 {
        self.now / TICK
    }
    fn ns_of(ticks: u64) -> Nanos {
        ticks * TICK
    }
    fn ticks_of(at: Nanos) -> u64 {
        at.div_ceil(TICK)
    }
    fn arm(&mut self, alarm: Alarm, setting: AlarmSetting) {
        let at = match setting {
            AlarmSetting::Off => None,
            AlarmSetting::Due => return self.raise(alarm),
            AlarmSetting::Compare { at_ticks, .. } | AlarmSetting::Later { at_ticks } => {
                Some(at_ticks)
            }
        };
        match alarm {
            Alarm::Commit => {
                self.commit = at;
                if let Some(j) = self.jump_at_commit_arm.take() {
                    self.now = j;
                }
            }
            Alarm::Prepare => self.prepare = at,
        }
    }
    fn rescue(&mut self, alarm: Alarm) {
        // The model's compare never misses, but a match at or before the current time
        // that `advance` has not run yet is what the hardware would have lost: raise it.
        let armed = match alarm {
            Alarm::Commit => self.commit,
            Alarm::Prepare => self.prepare,
        };
        if armed.is_some_and(|t| t * TICK <= self.now) {
            self.raise(alarm);
        }
    }
}

#[derive(Default)]
struct Port {
    /// (local time, mailbox, image, written by the slot timer's commit)
    writes: Vec<(Nanos, usize, TxImage, bool)>,
    aborts: Vec<u8>,
    bus_off: bool,
    now: Nanos,
    in_commit: bool,
}

impl TxPort for Port {
    fn write(&mut self, mailbox: usize, image: &TxImage) {
        self.writes
            .push((self.now, mailbox, *image, self.in_commit));
    }
    fn abort(&mut self, mask: u8) {
        self.aborts.push(mask);
    }
    fn is_bus_off(&self) -> bool {
        self.bus_off
    }
}

#[derive(Default)]
struct TestHost {
    done: Vec<(u8, TxOutcome)>,
    delivered: Vec<(u8, Vec<u8>, Nanos)>,
}

impl Host for TestHost {
    fn hrt_sample(&mut self, _tx: u8) -> Option<Token> {
        Some(Token(0))
    }
    fn payload(&self, _token: Token) -> &[u8] {
        &[1, 2, 3, 4]
    }
    fn tx_done(&mut self, tx: u8, _token: Option<Token>, outcome: TxOutcome) {
        self.done.push((tx, outcome));
    }
    fn deliver(&mut self, rx: u8, payload: &[u8], sof: Nanos) {
        self.delivered.push((rx, payload.to_vec(), sof));
    }
    fn event(&mut self, _event: Event) {}
}

type Core = SlotCore<Timer, Port>;

struct Module {
    engine: Engine<'static, 1, 16, 4>,
    host: TestHost,
    proto: Protocol,
    core: Core,
}

impl Module {
    fn new(tables: NodeTables<'static>, stamps: Stamps) -> Self {
        Module {
            engine: Engine::new(tables, 0),
            host: TestHost::default(),
            proto: Protocol::new(1_000, 200, LEAD).with_stamps(stamps),
            core: SlotCore {
                timer: Timer {
                    now: 0,
                    commit: None,
                    prepare: None,
                    raised: 0,
                    jump_at_commit_arm: None,
                },
                plan: SlotPlan::new(),
                tx: Port::default(),
            },
        }
    }

    fn set_now(&mut self, t: Nanos) {
        self.core.timer.now = t;
        self.core.tx.now = t;
    }

    /// The time the test timer reads (it may have jumped in a critical section).
    fn sync_port_time(&mut self) {
        self.core.tx.now = self.core.timer.now;
    }

    fn run(&mut self) {
        self.proto.run(
            &mut self.engine,
            &mut self.host,
            &mut Direct(&mut self.core),
            &mut |_, _, _, _| {},
        );
    }

    /// Runs the slot timer and the protocol task up to local time `until`.
    fn advance(&mut self, until: Nanos) {
        loop {
            let t = &self.core.timer;
            let next = t
                .commit
                .unwrap_or(u64::MAX)
                .min(t.prepare.unwrap_or(u64::MAX))
                .saturating_mul(TICK);
            if next > until {
                self.set_now(until);
                return;
            }
            self.set_now(next);
            if self.core.timer.commit.is_some_and(|c| c * TICK <= next) {
                self.core.timer.commit = None;
                self.core.tx.in_commit = true;
                // After a bus-off dropped the plan the alarm may find nothing: no-op.
                self.core.on_commit();
                self.core.tx.in_commit = false;
            }
            if self.core.timer.prepare.is_some_and(|p| p * TICK <= next) {
                self.core.timer.prepare = None;
            }
            self.run();
        }
    }

    fn complete_all(&mut self) {
        let written: Vec<usize> = self.core.tx.writes.iter().map(|w| w.1).collect();
        for m in written {
            let ev = TxEvent::Done(Mailbox(m as u8), TxResult::Sent);
            self.proto.on_tx_event(
                &ev,
                &mut self.engine,
                &mut self.host,
                &mut Direct(&mut self.core),
            );
        }
        self.core.tx.writes.clear();
    }
}

#[test]
fn sync_and_hrt_reach_the_controller_only_at_their_boundaries() {
    let mut m = Module::new(master_tables(), Stamps::Ttcm);
    m.run();
    // Cycle 0 starts one slot after start-up: the prepare alarm is half a slot before.
    assert_eq!(m.core.timer.prepare, Some((SLOT - LEAD) / TICK));
    assert!(m.core.timer.commit.is_none());
    m.advance(SLOT - LEAD);
    assert!(m.core.plan.is_armed(), "prepared half a slot ahead");
    assert_eq!(m.core.timer.commit, Some(SLOT / TICK));
    assert!(
        m.core.tx.writes.is_empty(),
        "nothing reaches the controller early"
    );
    m.advance(SLOT);
    assert_eq!(m.core.tx.writes.len(), 1);
    let (at, _, img, by_commit) = m.core.tx.writes[0];
    assert_eq!(at, SLOT);
    assert!(by_commit);
    assert!(img.frame().unwrap().id().is_sync());
    m.complete_all();
    // Slots 1 and 2 are free: the heartbeat goes out in that window, committed at the
    // slot-1 boundary.
    m.advance(4 * SLOT - 1);
    assert_eq!(m.core.tx.writes.len(), 1);
    let (at, _, img, by_commit) = m.core.tx.writes[0];
    assert_eq!((at, by_commit), (2 * SLOT, true));
    assert_ne!(img.frame().unwrap().id().msg_id(), HRT_ID);
    m.complete_all();
    // Slot 3 (boundary at 4 slots from start): this module's HRT frame, at its boundary.
    m.advance(4 * SLOT);
    assert_eq!(m.core.tx.writes.len(), 1);
    let (at, _, img, by_commit) = m.core.tx.writes[0];
    assert_eq!((at, by_commit), (4 * SLOT, true));
    let f = img.frame().unwrap();
    assert_eq!(f.id().msg_id(), HRT_ID);
    assert_eq!(&f.data()[..4], &[1, 2, 3, 4]);
    m.complete_all();
    assert_eq!(m.host.done, vec![(0, TxOutcome::Sent)]);
    // Ten more cycles: one sync and one HRT frame per cycle, at their boundaries, all
    // from commits (heartbeats in the free slots besides).
    let (mut syncs, mut hrts) = (0, 0);
    for c in 1..=10 {
        m.advance(SLOT + c * 10 * SLOT + 4 * SLOT);
        let start = SLOT + c * 10 * SLOT;
        for &(at, _, img, by_commit) in &m.core.tx.writes {
            assert!(by_commit, "a write outside a commit");
            let id = img.frame().unwrap().id();
            if id.is_sync() {
                assert_eq!(at, start);
                syncs += 1;
            } else if id.msg_id() == HRT_ID {
                assert_eq!(at, start + 3 * SLOT);
                hrts += 1;
            }
        }
        m.complete_all();
    }
    assert_eq!((syncs, hrts), (10, 10));
    assert_eq!(m.proto.stats().late_prepares, 0);
}

#[test]
fn a_late_protocol_task_runs_the_boundary_directly_and_counts_it() {
    let mut m = Module::new(master_tables(), Stamps::Ttcm);
    // The protocol task first runs after the first boundary has passed.
    m.set_now(SLOT + 3_000);
    m.run();
    assert_eq!(m.proto.stats().late_prepares, 1);
    // Less than a slot late: the engine still sends the sync, loaded directly.
    assert_eq!(m.core.tx.writes.len(), 1);
    let (at, _, img, by_commit) = m.core.tx.writes[0];
    assert_eq!((at, by_commit), (SLOT + 3_000, false));
    assert!(img.frame().unwrap().id().is_sync());
    // The next boundary (slot 1, at 2 slots) is prepared normally: alarm half a slot ahead.
    assert!(!m.core.plan.is_armed());
    assert_eq!(m.core.timer.prepare, Some((2 * SLOT - LEAD) / TICK));
}

/// The protocol task is preempted between publishing the plan (with the commit compare)
/// and its next clock reading, for `preempted_ns`: past the boundary, the compare's match
/// may have been lost; the task raises it, and the slot timer (not the task) commits
/// the plan, once. Short of the boundary, nothing is raised.
#[test]
fn a_boundary_passed_while_arming_is_raised_and_committed_by_the_slot_timer() {
    for (preempted_ns, raised) in [(LEAD - 125, 0), (LEAD, 1), (LEAD + 7_000, 1)] {
        let mut m = Module::new(master_tables(), Stamps::Ttcm);
        m.run();
        m.advance(SLOT - LEAD - 1);
        m.set_now(SLOT - LEAD);
        m.core.timer.prepare = None;
        m.core.timer.jump_at_commit_arm = Some(SLOT - LEAD + preempted_ns);
        m.run();
        m.sync_port_time();
        assert!(m.core.plan.is_published(), "{preempted_ns}");
        assert_eq!(m.core.timer.raised, raised, "{preempted_ns}");
        assert!(
            m.core.tx.writes.is_empty(),
            "the task never writes the plan"
        );
        let fire_at = SLOT.max(SLOT - LEAD + preempted_ns);
        assert_eq!(m.core.timer.commit, Some(fire_at.div_ceil(TICK)));
        m.advance(fire_at);
        assert_eq!(m.core.tx.writes.len(), 1, "{preempted_ns}");
        let (at, _, img, by_commit) = m.core.tx.writes[0];
        assert_eq!((at, by_commit), (fire_at, true));
        assert!(img.frame().unwrap().id().is_sync());
        assert!(!m.core.plan.is_armed());
        assert_eq!(m.proto.stats().late_prepares, 0);
    }
}

#[test]
fn bus_off_drops_the_plan_and_mutes_until_recovery() {
    let mut m = Module::new(master_tables(), Stamps::Ttcm);
    m.run();
    m.advance(SLOT);
    m.complete_all();
    // Slot 3's plan (the HRT frame) is prepared, then the controller goes bus-off.
    m.advance(4 * SLOT - LEAD);
    assert!(m.core.plan.is_armed());
    m.core.tx.bus_off = true;
    // The status-change interrupt (priority 3) blocks the plan at once; the slot timer
    // fires before the protocol task (priority 2) has handled the bus-off: the HRT frame
    // prepared before the bus-off must not be loaded (it would go out after recovery).
    m.core.plan.block();
    // The heartbeat, loaded in the free window at the slot-1 boundary, is still pending.
    let pending: Vec<usize> = m.core.tx.writes.iter().map(|w| w.1).collect();
    assert_eq!(pending.len(), 1);
    m.core.tx.writes.clear();
    m.core.tx.now = 4 * SLOT;
    m.core.timer.now = 4 * SLOT;
    m.core.tx.in_commit = true;
    assert!(!m.core.on_commit(), "a blocked plan is not applied");
    m.core.tx.in_commit = false;
    assert!(m.core.tx.writes.is_empty());
    m.core.tx.aborts.clear();
    m.proto.on_tx_event(
        &TxEvent::BusOff,
        &mut m.engine,
        &mut m.host,
        &mut Direct(&mut m.core),
    );
    assert!(!m.core.plan.is_armed(), "plan dropped");
    // One write aborts all three mailboxes; the engine's own withdrawal (one abort per
    // mailbox it had loaded) does not touch the hardware again.
    assert_eq!(
        m.core.tx.aborts,
        vec![0b111],
        "every mailbox aborted at once"
    );
    // The hardware completes the aborted heartbeat's mailbox (TX interrupt, no TXOK).
    for mb in pending {
        let ev = TxEvent::Done(Mailbox(mb as u8), TxResult::Aborted);
        m.proto
            .on_tx_event(&ev, &mut m.engine, &mut m.host, &mut Direct(&mut m.core));
    }
    assert!(m.proto.is_muted());
    assert_eq!(m.engine.counters().bus_off, 1);
    // Two cycles in bus-off: nothing is written; the staged HRT frame was reported.
    m.core.tx.writes.clear();
    m.run();
    m.advance(SLOT + 20 * SLOT);
    assert!(m.core.tx.writes.is_empty(), "{:?}", m.core.tx.writes);
    // The engine stepped down and withdrew (§5.7): it loads nothing the gate must hold.
    assert_eq!(m.proto.stats().muted_loads, 0);
    assert!(m.host.done.iter().any(|d| d.1 == TxOutcome::DeadlineMissed));
    // Recovery, noticed when the protocol task next runs (bxCAN raises no interrupt when
    // BOFF clears; the app's periodic kick runs the task). The master stepped down at
    // bus-off (§5.7): it listens for its takeover time, 4 cycles at rank 0 (§5.6), and
    // transmits nothing meanwhile.
    m.core.tx.bus_off = false;
    let recovered = SLOT + 20 * SLOT;
    m.run();
    assert!(m.proto.is_muted());
    assert!(!m.engine.is_master());
    let takeover = recovered + 4 * CYCLE;
    m.advance(takeover - 1);
    assert!(m.core.tx.writes.is_empty(), "{:?}", m.core.tx.writes);
    assert!(m.proto.is_muted());
    // No sync heard: it takes over, its first cycle a slot later, prepared ahead.
    m.advance(takeover + SLOT - 1);
    assert!(m.engine.is_master());
    assert!(!m.proto.is_muted());
    assert!(m.core.plan.is_armed());
    assert!(m.core.tx.writes.is_empty());
    // Three cycles, every frame completing within its slot: sync and HRT frame at their
    // boundaries, all from commits.
    let start = takeover + SLOT;
    let mut written = Vec::new();
    for k in 0..30 {
        m.advance(start + k * SLOT + SLOT / 2);
        written.extend(m.core.tx.writes.iter().copied());
        m.complete_all();
    }
    assert!(written.iter().all(|w| w.3), "all by commit");
    let at = |id: fn(&Frame) -> bool| -> Vec<Nanos> {
        written
            .iter()
            .filter(|w| id(&w.2.frame().unwrap()))
            .map(|w| w.0 - start)
            .collect()
    };
    assert_eq!(at(|f| f.id().is_sync()), vec![0, CYCLE, 2 * CYCLE]);
    assert_eq!(
        at(|f| f.id().msg_id() == HRT_ID),
        vec![3 * SLOT, CYCLE + 3 * SLOT, 2 * CYCLE + 3 * SLOT]
    );
    assert_eq!(m.proto.stats().late_prepares, 0);
}

fn regs_of(frame: &Frame, time16: u16) -> TxImage {
    let mut img = TxImage::of(frame);
    img.tir &= !1; // RIR has no TXRQ
    img.tdtr |= u32::from(time16) << 16;
    img
}

#[test]
fn rx_stamps_bad_frames_and_overruns() {
    for stamps in [Stamps::Ttcm, Stamps::RxTime] {
        let mut m = Module::new(master_tables(), stamps);
        // A single-frame message (≤ 8 bytes: no CRC fragment).
        let f = Frame::new(CanId::new(3, RX_ID, 0).unwrap(), &[9, 8, 7, 6]).unwrap();
        let now = 5_000_000;
        let ev = RxEvent::frame(regs_of(&f, 1_000), now);
        let mut core = Direct(&mut m.core);
        m.proto
            .on_rx_event(&ev, &mut m.engine, &mut m.host, &mut core);
        assert_eq!(m.host.delivered.len(), 1, "{stamps:?}");
        let (rx, payload, sof) = m.host.delivered[0].clone();
        assert_eq!((rx, payload), (0, vec![9, 8, 7, 6]));
        let expect = match stamps {
            // First frame: SOF = now minus the unstuffed length to the valid point.
            Stamps::Ttcm => now - 63_000 - 4 * 8_000,
            Stamps::RxTime => now - (worst_case_bits(4) - INTERMISSION_BITS - 1) as Nanos * 1_000,
        };
        assert_eq!(sof, expect, "{stamps:?}");
        // A standard-ID frame is not RTCAN: dropped and counted, nothing delivered.
        let foreign = TxImage {
            tir: 0x123 << 21,
            ..regs_of(&f, 1_100)
        };
        m.proto.on_rx_event(
            &RxEvent::frame(foreign, now + 100_000),
            &mut m.engine,
            &mut m.host,
            &mut core,
        );
        assert_eq!(m.proto.stats().rx_foreign, 1);
        // An overrun marker reaches the engine's counter.
        m.proto
            .on_rx_event(&RxEvent::OVERRUN, &mut m.engine, &mut m.host, &mut core);
        assert_eq!(m.engine.counters().rx_overrun, 1);
        assert_eq!(m.host.delivered.len(), 1);
    }
}

fn slave_tables() -> NodeTables<'static> {
    NodeTables {
        bus: BUS,
        module: 1,
        tx: &TX,
        rx: &[],
        calendar: &CAL,
        master_masks: &[],
    }
}

/// Cycle length of `BUS`.
const CYCLE: Nanos = 10 * SLOT;

/// The master's sync frame of cycle `c`, SOF at bus (= local) time `c * CYCLE`, handled
/// by the slave's protocol task right after it became valid.
fn feed_sync(m: &mut Module, c: u64) {
    let frame = rtcan_core::sync::sync_frame(
        rtcan_core::sync::Sync {
            cycle: c as u16,
            mask: 0b1001,
        },
        10,
    );
    let sof = c * CYCLE;
    let now = sof + (rtcan_board_common::sof::valid_bits_min(frame.dlc()) as Nanos + 2) * 1_000;
    m.advance(now);
    let ev = RxEvent::frame(regs_of(&frame, (sof / 1_000) as u16), now);
    m.proto
        .on_rx_event(&ev, &mut m.engine, &mut m.host, &mut Direct(&mut m.core));
    m.run();
}

/// HRT frames written in cycle `c` (and when, relative to the cycle's SOF).
fn hrt_writes(m: &Module, c: u64) -> Vec<Nanos> {
    m.core
        .tx
        .writes
        .iter()
        .filter(|w| w.2.frame().unwrap().id().msg_id() == HRT_ID)
        .map(|w| w.0 - c * CYCLE)
        .collect()
}

#[test]
fn a_slave_transmits_again_only_after_a_sync_following_bus_off() {
    let mut m = Module::new(slave_tables(), Stamps::Ttcm);
    m.run();
    assert_eq!(
        m.core.timer.prepare, None,
        "unsynced slave: nothing to wake for"
    );
    // Lock (offset, then rate) on two syncs, then its HRT frame goes out in slot 3 of
    // every cycle, committed at the boundary the sync placed (within the SOF estimate's
    // error: the sync frame's stuff bits).
    for c in 1..=4 {
        feed_sync(&mut m, c);
        m.advance(c * CYCLE + 5 * SLOT);
        if c >= 3 {
            let w = hrt_writes(&m, c);
            assert_eq!(w.len(), 1, "cycle {c}: {w:?}");
            assert!(
                (3 * SLOT..3 * SLOT + 5_000).contains(&w[0]),
                "cycle {c}: at {}",
                w[0]
            );
            assert!(m.core.tx.writes.iter().all(|w| w.3), "all by commit");
        }
        m.complete_all();
    }
    // Bus-off in cycle 5 before slot 3, recovered right away: no HRT frame until a sync
    // frame has been received again.
    feed_sync(&mut m, 5);
    m.core.tx.bus_off = true;
    m.proto.on_tx_event(
        &TxEvent::BusOff,
        &mut m.engine,
        &mut m.host,
        &mut Direct(&mut m.core),
    );
    m.core.tx.bus_off = false;
    m.core.tx.writes.clear();
    m.run();
    // Cycle 5 and 6 without a sync reaching the slave (the master's sync lost).
    m.advance(7 * CYCLE - SLOT);
    assert!(m.proto.is_muted());
    assert!(hrt_writes(&m, 5).is_empty(), "{:?}", m.core.tx.writes);
    assert!(
        m.core.tx.writes.is_empty(),
        "nothing at all before the re-sync"
    );
    // Its slot clock was forgotten at bus-off (§5.7): it relocks like a starting slave,
    // offset on the first sync and rate on the second, and transmits only then.
    feed_sync(&mut m, 7);
    assert!(m.proto.is_muted());
    m.advance(8 * CYCLE - SLOT);
    assert!(m.core.tx.writes.is_empty(), "{:?}", m.core.tx.writes);
    feed_sync(&mut m, 8);
    assert!(!m.proto.is_muted());
    m.advance(8 * CYCLE + 5 * SLOT);
    let w = hrt_writes(&m, 8);
    assert_eq!(w.len(), 1, "{:?}", m.core.tx.writes);
    assert!((3 * SLOT..3 * SLOT + 5_000).contains(&w[0]));
    assert!(m.core.tx.writes.iter().all(|w| w.3), "all by commit");
}

#[test]
fn a_blocked_plan_without_its_bus_off_event_is_handled_as_bus_off() {
    let mut m = Module::new(master_tables(), Stamps::Ttcm);
    m.run();
    m.advance(SLOT - LEAD);
    assert!(m.core.plan.is_armed());
    // The status-change interrupt blocked the plan; its queued event was lost.
    m.core.tx.bus_off = true;
    m.core.plan.block();
    m.run();
    assert!(m.proto.is_muted());
    assert_eq!(m.engine.counters().bus_off, 1);
    assert!(!m.core.plan.is_armed(), "the blocked plan was dropped");
    // Recovered (noticed at the next run): the plan is unblocked at the takeover, after
    // the master listened for 4 cycles (§5.6, §5.7), and its sync goes out by commit.
    let recovered = 3 * SLOT;
    m.advance(recovered);
    assert!(m.proto.is_muted());
    assert!(m.core.plan.is_blocked());
    assert!(m.core.tx.writes.is_empty());
    m.core.tx.bus_off = false;
    m.run();
    assert!(m.proto.is_muted());
    assert!(m.core.plan.is_blocked());
    m.advance(recovered + 4 * CYCLE + 2 * SLOT);
    assert!(!m.proto.is_muted());
    assert!(!m.core.plan.is_blocked());
    let syncs: Vec<(Nanos, bool)> = m
        .core
        .tx
        .writes
        .iter()
        .filter(|w| w.2.frame().unwrap().id().is_sync())
        .map(|w| (w.0, w.3))
        .collect();
    assert_eq!(syncs, vec![(recovered + 4 * CYCLE + SLOT, true)]);
}
