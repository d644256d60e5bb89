//! The split architecture's protocol task around a real engine, on the host: frames
//! reach the controller only when the slot timer commits the prepared plan (at its
//! boundary, never during preparation), bus-off drops the plan and mutes the module
//! until recovery, the RX path's stamps and bad input.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use rtcan_board_common::protocol::{Direct, RxEvent, SlotCore, SlotTimerHw, Stamps, TxEvent};
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
    commit: Option<u64>,
    prepare: Option<u64>,
}

impl SlotTimerHw for Timer {
    fn now(&self) -> Nanos {
        self.now
    }
    fn ticks_of(at: Nanos) -> u64 {
        at.div_ceil(TICK)
    }
    fn arm_commit(&mut self, t: u64) -> bool {
        if t * TICK <= self.now {
            return false;
        }
        self.commit = Some(t);
        true
    }
    fn arm_prepare(&mut self, t: u64) {
        self.prepare = (t != u64::MAX).then_some(t);
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
    m.core.tx.writes.clear();
    m.core.tx.now = 4 * SLOT;
    m.core.timer.now = 4 * SLOT;
    m.core.tx.in_commit = true;
    assert!(!m.core.on_commit(), "a blocked plan is not applied");
    m.core.tx.in_commit = false;
    assert!(m.core.tx.writes.is_empty());
    m.proto.on_tx_event(
        &TxEvent::BusOff,
        &mut m.engine,
        &mut m.host,
        &mut Direct(&mut m.core),
    );
    assert!(!m.core.plan.is_armed(), "plan dropped");
    assert_eq!(
        m.core.tx.aborts.last(),
        Some(&0b111),
        "every mailbox aborted at once"
    );
    assert!(m.proto.is_muted());
    assert_eq!(m.engine.counters().bus_off, 1);
    // Two cycles in bus-off: nothing is written; the staged HRT frame was reported.
    m.core.tx.writes.clear();
    m.run();
    m.advance(SLOT + 20 * SLOT);
    assert!(m.core.tx.writes.is_empty(), "{:?}", m.core.tx.writes);
    assert!(m.proto.stats().muted_loads > 0);
    assert!(m.host.done.iter().any(|d| d.1 == TxOutcome::DeadlineMissed));
    // Recovery: the master transmits again from its next wake-up, on time.
    m.core.tx.bus_off = false;
    m.advance(SLOT + 40 * SLOT);
    assert!(!m.proto.is_muted());
    assert!(!m.core.tx.writes.is_empty());
    assert!(m
        .core
        .tx
        .writes
        .iter()
        .all(|w| w.3 && (w.0 - SLOT).is_multiple_of(SLOT)));
    assert!(m
        .core
        .tx
        .writes
        .iter()
        .any(|w| w.2.frame().unwrap().id().is_sync()));
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
    // The next sync re-synchronises: slot 3 of that cycle carries the HRT frame again.
    feed_sync(&mut m, 7);
    assert!(!m.proto.is_muted());
    m.advance(7 * CYCLE + 5 * SLOT);
    let w = hrt_writes(&m, 7);
    assert_eq!(w.len(), 1, "{:?}", m.core.tx.writes);
    assert!((3 * SLOT..3 * SLOT + 5_000).contains(&w[0]));
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
    // Recovered: transmits again, the plan unblocked.
    m.core.tx.bus_off = false;
    m.advance(SLOT + 30 * SLOT);
    assert!(!m.proto.is_muted());
    assert!(!m.core.plan.is_blocked());
    assert!(m
        .core
        .tx
        .writes
        .iter()
        .any(|w| w.3 && w.2.frame().unwrap().id().is_sync()));
}
