//! The discrete-event CAN bus: global time in ns, arbitration, frame timing from the real
//! bits, receive FIFOs, interrupt latency, bit errors.
//!
//! Events are kept where they belong rather than in one priority queue: the bus's own
//! next event (at most one), one armed timer per node, and per node a FIFO of interrupts.
//! Every event carries (time, scheduling sequence number); the next one is the smallest
//! over these places, so events at the same time run in the order they were scheduled.
//!
//! What is modelled, and how:
//! - A node that has a pending frame when the bus is idle starts a start-of-frame; every
//!   node whose mailbox is loaded within that first bit time joins the arbitration (a
//!   node loading later sees the SOF and waits). Lowest raw identifier wins; each
//!   controller offers only its own best mailbox. Losers retry when the bus is next idle
//!   (with NART they fail at once).
//! - Duration = `rtcan_core::timing::exact_bits` (stuffing on the actual ID, DLC, data
//!   and CRC-15), EOF included; receivers and the transmitter see the frame complete at
//!   the end of EOF, the bus takes new SOFs after the 3-bit intermission.
//! - Bit errors (optional, `bit_error_rate` per bit): the frame is hit at a uniformly
//!   drawn bit after the SOF; an error flag (6 bits) and delimiter (8 bits) follow, then
//!   the intermission. Receivers drop the frame, the transmitter retransmits (or fails
//!   with NART; or ends aborted if an abort was requested meanwhile). Every controller
//!   keeps ISO 11898-1 error counters (`confinement.rs`): error-passive, bus-off (no
//!   transmission, no reception) and recovery after 128 runs of 11 recessive bits,
//!   counted at each start of frame; level changes reach the module as
//!   `Module::error_state`; on an idle bus the recovery completes after exactly
//!   1408 recessive bit times (an `IdleRecover` bus event).
//! - Errors seen by some receivers only (optional, `set_eof_error_rate`): a receiver
//!   that alone sees an error in the last-but-one bit of EOF rejects the frame and sends
//!   an error flag in the last bit, which the other receivers ignore (they already
//!   accepted it) and the transmitter takes as an error: it retransmits, and those
//!   receivers get the frame twice (inconsistent duplication; omission if the
//!   transmitter fails before the retransmission). `WireFrame::partial`.
//! - Faults on the bus (`fault.rs`, applied by the scenario at their times): a node
//!   holding the bus dominant (`set_stuck`), a node cut off on its stub
//!   (`set_partitioned`), a node whose interrupts are masked (`stall`: its FIFOs
//!   overrun), a node whose clock jumps (`step_clock`), and per node a bus guardian
//!   (`set_guardian`, `guardian.rs`).
//! - Receive and transmit interrupts, and timer wake-ups, run `irq_latency_ns` after the
//!   hardware event. Start-of-frame timestamps are taken by hardware, without latency,
//!   in the receiver's local clock.
use std::collections::VecDeque;

use rtcan_core::driver::{Mailbox, TxResult};
use rtcan_core::timing::{bits_to_ns, exact_bits, INTERMISSION_BITS};
use rtcan_core::{Frame, Nanos};

use crate::clock::NodeClock;
use crate::controller::{Filter, SimController, RX_FIFO_DEPTH};
use crate::cpu::{Cpu, CpuModel, Effect};
use crate::rng::Rng;

mod external;
pub use external::{Activity, OnWire};

/// Error flag plus error delimiter, in bits.
pub const ERROR_FRAME_BITS: u32 = 6 + 8;

/// What a simulated module does with the driver events of its controller. Every
/// callback gets the local time and returns the local time of the next timer wake-up
/// it wants (`None`: no timer armed). A module is typically an `rtcan_core::Engine`
/// plus a `Host`.
pub trait Module {
    /// Power-on.
    fn start(&mut self, now: Nanos, can: &mut SimController) -> Option<Nanos>;
    /// The timer fired.
    fn wake(&mut self, now: Nanos, can: &mut SimController) -> Option<Nanos>;
    /// The receive interrupt read `frame` from a FIFO; `sof` is its hardware timestamp.
    fn rx(
        &mut self,
        frame: &Frame,
        sof: Nanos,
        now: Nanos,
        can: &mut SimController,
    ) -> Option<Nanos>;
    /// The transmit interrupt reported `mailbox` done.
    fn tx_done(
        &mut self,
        mailbox: Mailbox,
        result: TxResult,
        now: Nanos,
        can: &mut SimController,
    ) -> Option<Nanos>;
    /// A receive FIFO overran.
    fn rx_overrun(&mut self, now: Nanos);
    /// The controller's fault-confinement level changed (error-active, error-passive,
    /// bus-off, recovered: bxCAN's status-change interrupt); `state` has the counters.
    /// `None` keeps the armed timer (modules without fault handling need do nothing).
    fn error_state(
        &mut self,
        _now: Nanos,
        _state: rtcan_core::confinement::ErrorState,
        _can: &mut SimController,
    ) -> Option<Nanos> {
        None
    }
}

/// Physical parameters of one node.
#[derive(Clone, Debug)]
pub struct NodeSetup {
    /// Local clock.
    pub clock: NodeClock,
    /// Interrupt latency (RX, TX and timer), ns.
    pub irq_latency_ns: Nanos,
    /// No automatic retransmission.
    pub nart: bool,
    /// Acceptance filters.
    pub filter: Filter,
    /// Modelled CPU (`None`: handlers take no time beyond `irq_latency_ns`). With a
    /// model, interrupts and tasks run on it (`cpu.rs`) and take the time their cost
    /// table says; set `irq_latency_ns` to 0 then, the model has the exception entry.
    pub cpu: Option<CpuModel>,
}

impl Default for NodeSetup {
    fn default() -> Self {
        NodeSetup {
            clock: NodeClock::default(),
            irq_latency_ns: 0,
            nart: false,
            filter: Filter::AcceptAll,
            cpu: None,
        }
    }
}

/// One frame as it happened on the wire (global times).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WireFrame {
    /// Start of frame.
    pub sof: Nanos,
    /// End of EOF (or of the error delimiter).
    pub end: Nanos,
    /// Transmitting node.
    pub node: usize,
    /// The frame.
    pub frame: Frame,
    /// False when destroyed by an error frame (or retransmitted after a per-receiver
    /// error in the last bit of EOF, see `partial`).
    pub ok: bool,
    /// Accepted by some receivers but rejected by others after an error in the
    /// last-but-one bit of EOF; the transmitter retransmits it (`ok` is false).
    pub partial: bool,
}

/// Bus-wide counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BusStats {
    /// Frames completed.
    pub frames_ok: u64,
    /// Frames destroyed by a bit error.
    pub error_frames: u64,
    /// Arbitrations between several controllers.
    pub contended: u64,
    /// Two controllers sent the same identifier at once (a design error on a real bus).
    pub id_collisions: u64,
    /// Time the bus was not idle (frames, error frames, intermissions), ns.
    pub busy_ns: Nanos,
    /// Frames some receivers accepted and others rejected (error in the last-but-one
    /// bit of EOF), then retransmitted.
    pub eof_errors: u64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Ev {
    Wake {
        node: usize,
    },
    ArbDecide,
    FrameEnd,
    RxIrq {
        node: usize,
        fifo: usize,
    },
    TxIrq {
        node: usize,
        mb: u8,
        result: u8,
    },
    /// The node's modelled CPU finishes a step or takes SysTick.
    Cpu {
        node: usize,
    },
    /// A fault-confinement level change of the node's controller (`confinement.rs`).
    ErrIrq {
        node: usize,
    },
    /// On an idle bus a bus-off controller may have completed its recovery.
    IdleRecover,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Free from the given time on (the intermission of the last frame ends there).
    Idle {
        from: Nanos,
    },
    Arbitrating {
        sof: Nanos,
    },
    Busy {
        node: usize,
        mb: usize,
        sof: Nanos,
        frame: Frame,
        ok: bool,
        /// Receivers (bit per node) that saw an error in the last-but-one bit of EOF.
        rejects: u64,
    },
}

/// A scheduled event: global time in the high 64 bits, then the sequence number of its
/// scheduling, so that one integer comparison orders events by time and those at the
/// same time in the order they were scheduled. The low `PLACE_BITS` are zero; in
/// `Bus::keys` they hold the index of the place, so that the next event and where it is
/// come out of one branch-free minimum.
type Key = u128;

/// Low bits of a key left for the place index (places: the bus and up to 4095 nodes).
const PLACE_BITS: u32 = 12;
const PLACE_MASK: Key = (1 << PLACE_BITS) - 1;

/// Key of an empty event place (after every real key: sequence numbers never reach it).
const NONE: Key = u128::MAX;

fn key(t: Nanos, seq: u64) -> Key {
    // 2^52 events (decades of simulated time at millions of events per second) before
    // the sequence number would run into the time bits.
    debug_assert!(seq < 1 << (64 - PLACE_BITS));
    (u128::from(t) << 64) | (u128::from(seq) << PLACE_BITS)
}

fn key_time(k: Key) -> Nanos {
    (k >> 64) as Nanos
}

struct Node<M> {
    module: M,
    can: SimController,
    setup: NodeSetup,
    /// The armed timer wake-up (at most one: re-arming replaces it, so no stale entries
    /// are ever scheduled or popped).
    wake: Option<Key>,
    /// Pending interrupts, in (time, sequence) order: every interrupt is scheduled at
    /// the current time plus this node's fixed latency, so appending keeps it sorted.
    irqs: VecDeque<(Key, Ev)>,
    /// Last requested local wake-up and its global time (the inverse clock is costly).
    last_req: Option<(Nanos, Nanos)>,
    /// The modelled CPU and the key of its next event.
    cpu: Option<(Cpu, Key)>,
    /// Interrupts are masked until this global time (`stall`).
    stalled_until: Nanos,
    /// Cut off from the bus (`set_partitioned`).
    partitioned: bool,
    /// Its bus guardian, if it has one.
    guardian: Option<crate::guardian::Guardian>,
}

/// The simulated bus with its nodes.
pub struct Bus<M: Module> {
    bitrate: u32,
    bit_error_rate: f64,
    nodes: Vec<Node<M>>,
    /// The bus's own next event (arbitration decision or frame end): at most one is
    /// ever outstanding, the state machine moves Idle → Arbitrating → Busy → Idle.
    bus_ev: Option<(Key, Ev)>,
    /// Keys packed for the scan that finds the next event, each with its own index in
    /// the low `PLACE_BITS`: index 0 the bus event, `1 + i` the earlier of node i's
    /// wake-up and first interrupt; `NONE` when empty. Mirrors `bus_ev`, `Node::wake`
    /// and `Node::irqs`.
    keys: Vec<Key>,
    seq: u64,
    state: State,
    now: Nanos,
    rng: Rng,
    started: bool,
    /// Completed and destroyed frames, in order, when `record_wire` is set.
    pub wire: Vec<WireFrame>,
    /// Keep `wire` (off for long sweeps that only need counters).
    pub record_wire: bool,
    /// Counters.
    pub stats: BusStats,
    offers: Vec<(u32, usize, usize)>,
    irqs: Vec<(Nanos, Ev)>,
    /// Recessive bits before the start of frame being arbitrated (trailing bits of the
    /// last frame and idle time): what bus-off controllers count towards recovery.
    recessive_run: u64,
    /// The node whose transceiver holds the bus dominant (`set_stuck`).
    stuck: Option<usize>,
    /// Per receiver and frame, probability of an error it alone sees in the last-but-one
    /// bit of EOF.
    eof_error_rate: f64,
}

/// The node may start a frame: not bus-off, not cut off, not stopped by its guardian.
fn transmits<M>(n: &Node<M>) -> bool {
    !n.can.conf.is_bus_off()
        && !n.partitioned
        && n.guardian.as_ref().is_none_or(|g| !g.is_tripped())
}

fn result_code(r: TxResult) -> u8 {
    match r {
        TxResult::Sent => 0,
        TxResult::Aborted => 1,
        TxResult::Failed => 2,
    }
}

fn code_result(c: u8) -> TxResult {
    match c {
        0 => TxResult::Sent,
        1 => TxResult::Aborted,
        _ => TxResult::Failed,
    }
}

impl<M: Module> Bus<M> {
    /// A bus at `bitrate` bit/s; `bit_error_rate` per bit (0 = error free); `seed` for
    /// the error draws.
    pub fn new(bitrate: u32, bit_error_rate: f64, seed: u64) -> Self {
        Bus {
            bitrate: bitrate.max(1),
            bit_error_rate,
            nodes: Vec::new(),
            bus_ev: None,
            keys: vec![NONE],
            seq: 0,
            state: State::Idle { from: 0 },
            now: 0,
            rng: Rng::new(seed, 0xB05),
            started: false,
            wire: Vec::new(),
            record_wire: true,
            stats: BusStats::default(),
            offers: Vec::new(),
            irqs: Vec::new(),
            recessive_run: 0,
            stuck: None,
            eof_error_rate: 0.0,
        }
    }

    /// Per receiver and frame, the probability that this receiver alone sees an error in
    /// the last-but-one bit of EOF (0 = never; the bit error rate is a good value).
    pub fn set_eof_error_rate(&mut self, p: f64) {
        self.eof_error_rate = p;
    }

    /// Gives node `i` a bus guardian (`guardian.rs`).
    pub fn set_guardian(&mut self, i: usize, g: crate::guardian::Guardian) {
        if let Some(node) = self.nodes.get_mut(i) {
            node.guardian = Some(g);
        }
    }

    /// Node `i`'s bus guardian.
    pub fn guardian(&self, i: usize) -> Option<&crate::guardian::Guardian> {
        self.nodes.get(i).and_then(|n| n.guardian.as_ref())
    }

    /// Node `i`'s transceiver holds the bus dominant from now (`on`), or lets it go. While
    /// it does, no frame starts and the frame on the wire is destroyed; every controller
    /// sees dominant bits after its error flag: REC +8 per 8 bits (error-passive at
    /// once on the scale of a cycle), the transmitter of that frame TEC +8 per 8 bits
    /// (bus-off). Released, the bus is idle (recessive) from now.
    pub fn set_stuck(&mut self, i: usize, on: bool) {
        if !on {
            if self.stuck == Some(i) {
                self.stuck = None;
                if let State::Idle { from } = self.state {
                    self.state = State::Idle {
                        from: from.max(self.now),
                    };
                }
                self.maybe_start_arbitration();
            }
            return;
        }
        self.stuck = Some(i);
        let tx = match &mut self.state {
            State::Busy { node, ok, .. } => {
                *ok = false;
                Some(*node)
            }
            _ => None,
        };
        let now = self.now;
        for n in 0..self.nodes.len() {
            let Some(node) = self.nodes.get_mut(n) else {
                continue;
            };
            let level = node.can.conf.level();
            node.can.conf.stuck_dominant(tx == Some(n));
            if node.can.conf.level() != level {
                let t = now + node.setup.irq_latency_ns;
                self.push_irq(n, t, Ev::ErrIrq { node: n });
            }
        }
    }

    /// Node `i` is cut off from the bus (`on`) or joins it again. Cut off, it neither
    /// receives nor takes part in arbitration; alone on its stub its frames would get
    /// no acknowledgement: TEC rises to error-passive and stays there (ISO 11898-1: an
    /// error-passive transmitter does not count acknowledgement errors).
    pub fn set_partitioned(&mut self, i: usize, on: bool) {
        let now = self.now;
        let Some(node) = self.nodes.get_mut(i) else {
            return;
        };
        node.partitioned = on;
        if on {
            let level = node.can.conf.level();
            node.can.conf.unacknowledged();
            if node.can.conf.level() != level {
                let t = now + node.setup.irq_latency_ns;
                self.push_irq(i, t, Ev::ErrIrq { node: i });
            }
        } else {
            self.maybe_start_arbitration();
        }
    }

    /// Node `i`'s interrupts (timer, receive, transmit, status) are masked until global
    /// time `until`: they run then. Frames keep arriving in its FIFOs, which overrun.
    pub fn stall(&mut self, i: usize, until: Nanos) {
        if let Some(node) = self.nodes.get_mut(i) {
            node.stalled_until = node.stalled_until.max(until);
        }
    }

    /// Node `i`'s local clock jumps by `delta_ns` now (its offset changes; an offset
    /// cannot go below zero, so a backward step larger than the offset is cut short).
    /// Its armed timer fires at the same local time, now at another global time.
    /// Returns the new clock.
    pub fn step_clock(&mut self, i: usize, delta_ns: i64) -> Option<NodeClock> {
        let now = self.now;
        let node = self.nodes.get_mut(i)?;
        let c = &mut node.setup.clock;
        c.offset_ns = if delta_ns >= 0 {
            c.offset_ns.saturating_add(delta_ns.unsigned_abs())
        } else {
            c.offset_ns.saturating_sub(delta_ns.unsigned_abs())
        };
        let clock = node.setup.clock;
        let lat = node.setup.irq_latency_ns;
        let rearm = match (node.wake, node.last_req) {
            (Some(_), Some((l, _))) => {
                let g = clock.global_at(l);
                node.last_req = Some((l, g));
                Some(g.saturating_add(lat).max(now))
            }
            _ => {
                node.last_req = None;
                None
            }
        };
        if let Some(t) = rearm {
            let k = key(t, self.next_seq());
            self.set_wake(i, Some(k));
        }
        Some(clock)
    }

    /// Changes the bit error rate from now on (a campaign's noise burst).
    pub fn set_bit_error_rate(&mut self, ber: f64) {
        self.bit_error_rate = ber;
    }

    /// Attaches a node; returns its index.
    pub fn add_node(&mut self, module: M, setup: NodeSetup) -> usize {
        let can = SimController::new(setup.nart, setup.filter.clone());
        let cpu = setup.cpu.clone().map(|m| (Cpu::new(m), NONE));
        self.nodes.push(Node {
            module,
            can,
            setup,
            wake: None,
            irqs: VecDeque::new(),
            last_req: None,
            cpu,
            stalled_until: 0,
            partitioned: false,
            guardian: None,
        });
        // Place 1 + i of node i fits the key's PLACE_BITS for any real bus: module indices
        // are 8-bit.
        self.keys.push(NONE);
        let n = self.nodes.len() - 1;
        self.cpu_reschedule(n);
        n
    }

    /// The CPU report of the run so far (empty without models); `name(i)` names node i.
    pub fn cpu_report(&self, name: impl Fn(usize) -> String) -> crate::cpu::CpuReport {
        let mut r = crate::cpu::CpuReport::default();
        for (i, n) in self.nodes.iter().enumerate() {
            if let Some((cpu, _)) = &n.cpu {
                r.design = cpu.model().design.name().to_string();
                r.cpi = cpu.model().table.cpi;
                r.cost = cpu.model().cost.name();
                r.clock_hz = cpu.model().table.clock_hz;
                r.modules.push(cpu.summary(&name(i), self.now));
            }
        }
        r
    }

    /// The modelled CPU of node `i` (`None` without a model).
    pub fn cpu(&self, i: usize) -> Option<&Cpu> {
        self.nodes
            .get(i)
            .and_then(|n| n.cpu.as_ref())
            .map(|(c, _)| c)
    }

    /// Current global time.
    pub fn now(&self) -> Nanos {
        self.now
    }

    /// Bit time in ns (rounded up).
    pub fn bit_ns(&self) -> Nanos {
        bits_to_ns(1, self.bitrate)
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True without nodes.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Module of node `i`.
    pub fn module(&self, i: usize) -> Option<&M> {
        self.nodes.get(i).map(|n| &n.module)
    }

    /// Module of node `i`, mutably.
    pub fn module_mut(&mut self, i: usize) -> Option<&mut M> {
        self.nodes.get_mut(i).map(|n| &mut n.module)
    }

    /// Controller of node `i`.
    pub fn controller(&self, i: usize) -> Option<&SimController> {
        self.nodes.get(i).map(|n| &n.can)
    }

    /// Clock of node `i`.
    pub fn clock(&self, i: usize) -> Option<NodeClock> {
        self.nodes.get(i).map(|n| n.setup.clock)
    }

    /// Runs an arbitrary action on node `i` at the current time, as if from its own
    /// code (e.g. a test loading a mailbox), with the usual bookkeeping afterwards.
    pub fn with_node(
        &mut self,
        i: usize,
        f: impl FnOnce(&mut M, Nanos, &mut SimController) -> Option<Nanos>,
    ) {
        self.callback(i, f);
    }

    fn next_seq(&mut self) -> u64 {
        self.seq += 1;
        self.seq
    }

    /// Schedules an interrupt of node `n` (RX or TX) at `t`.
    fn push_irq(&mut self, n: usize, t: Nanos, ev: Ev) {
        let seq = self.next_seq();
        if let Some(node) = self.nodes.get_mut(n) {
            // Appending keeps the order (fixed latency), except for interrupts a stall
            // deferred: those go in their place.
            let k = key(t, seq);
            let at = node
                .irqs
                .iter()
                .rposition(|&(b, _)| b <= k)
                .map_or(0, |p| p + 1);
            node.irqs.insert(at, (k, ev));
        }
        self.refresh_key(n);
    }

    /// Recomputes node `n`'s entry of `keys`.
    fn refresh_key(&mut self, n: usize) {
        if let (Some(node), Some(k)) = (self.nodes.get(n), self.keys.get_mut(1 + n)) {
            let irq = node.irqs.front().map_or(NONE, |&(k, _)| k);
            let cpu = node.cpu.as_ref().map_or(NONE, |&(_, k)| k);
            // NONE | place = NONE: an empty place stays empty.
            *k = node.wake.unwrap_or(NONE).min(irq).min(cpu) | (1 + n) as Key;
        }
    }

    /// Schedules the bus's arbitration decision or frame end at `t`.
    fn push_bus(&mut self, t: Nanos, ev: Ev) {
        let seq = self.next_seq();
        debug_assert!(self.bus_ev.is_none());
        self.bus_ev = Some((key(t, seq), ev));
        if let Some(k) = self.keys.first_mut() {
            *k = key(t, seq); // place 0
        }
    }

    fn set_wake(&mut self, n: usize, wake: Option<Key>) {
        if let Some(node) = self.nodes.get_mut(n) {
            node.wake = wake;
        }
        self.refresh_key(n);
    }

    /// The earliest scheduled event and the index of its place in `keys`: a branch-free
    /// minimum over the bus slot and one entry per node (a handful of nodes: cheaper
    /// than a heap).
    fn next_event(&self) -> Option<(Key, usize)> {
        let m = self.keys.iter().fold(NONE, |a, &k| a.min(k));
        (m != NONE).then_some((m & !PLACE_MASK, (m & PLACE_MASK) as usize))
    }

    /// Removes the event with key `k` that `next_event` found at place `j`.
    fn take_event(&mut self, k: Key, j: usize) -> Option<Ev> {
        let Some(n) = j.checked_sub(1) else {
            if let Some(k) = self.keys.first_mut() {
                *k = NONE;
            }
            return self.bus_ev.take().map(|(_, ev)| ev);
        };
        let node = self.nodes.get_mut(n)?;
        let ev = if node.wake == Some(k) {
            node.wake = None;
            Some(Ev::Wake { node: n })
        } else if let Some((_, ck)) = node.cpu.as_mut().filter(|(_, ck)| *ck == k) {
            *ck = NONE;
            Some(Ev::Cpu { node: n })
        } else {
            node.irqs.pop_front().map(|(_, ev)| ev)
        };
        self.refresh_key(n);
        ev
    }

    fn callback(
        &mut self,
        i: usize,
        f: impl FnOnce(&mut M, Nanos, &mut SimController) -> Option<Nanos>,
    ) {
        let now = self.now;
        let Some(node) = self.nodes.get_mut(i) else {
            return;
        };
        node.can.now = now;
        let local = node.setup.clock.local(now);
        let next = f(&mut node.module, local, &mut node.can);
        let lat = node.setup.irq_latency_ns;
        let wake_at = next.map(|l| {
            let g = match node.last_req {
                Some((req, g)) if req == l => g,
                _ => {
                    let g = node.setup.clock.global_at(l);
                    node.last_req = Some((l, g));
                    g
                }
            };
            g.saturating_add(lat).max(now)
        });
        // Re-arm only when the deadline moved: an unchanged wake-up keeps its place
        // (sequence number) among events at the same time.
        let rearm = wake_at != node.wake.map(key_time);
        // Synchronous completions (aborts) are rare: skip the buffer handling without.
        let mut reports = if node.can.reports.is_empty() {
            None
        } else {
            Some(std::mem::take(&mut node.can.reports))
        };
        if rearm {
            let armed = wake_at.map(|t| key(t, self.next_seq()));
            self.set_wake(i, armed);
        }
        if let Some(reports) = reports.as_mut() {
            for (mb, r) in reports.drain(..) {
                self.push_irq(
                    i,
                    now + lat,
                    Ev::TxIrq {
                        node: i,
                        mb: mb.0,
                        result: result_code(r),
                    },
                );
            }
        }
        // Hand the (emptied) buffer back, so that it is allocated once.
        if let (Some(reports), Some(node)) = (reports, self.nodes.get_mut(i)) {
            node.can.reports = reports;
        }
        self.maybe_start_arbitration();
    }

    fn maybe_start_arbitration(&mut self) {
        if self.stuck.is_some() {
            // A dominant bus never becomes idle: nothing starts, nothing recovers.
            return;
        }
        if let State::Idle { from } = self.state {
            // A bus-off, cut-off or guarded-off controller's loaded mailboxes start nothing.
            if self
                .nodes
                .iter()
                .any(|n| n.can.has_pending() && transmits(n))
            {
                // A pending idle-recovery check gives way: the start of frame counts
                // the recessive run for every bus-off controller.
                if matches!(self.bus_ev, Some((_, Ev::IdleRecover))) {
                    self.bus_ev = None;
                    if let Some(k) = self.keys.first_mut() {
                        *k = NONE;
                    }
                }
                // Pending frames wait for the intermission to end, then start together.
                let sof = from.max(self.now);
                let idle = (sof - from) / self.bit_ns().max(1);
                self.recessive_run = crate::confinement::TRAILING_RECESSIVE_BITS + idle;
                self.state = State::Arbitrating { sof };
                let t = sof + self.bit_ns();
                self.push_bus(t, Ev::ArbDecide);
            } else if self.bus_ev.is_none() {
                // An idle bus still recovers bus-off controllers: wake up when the first
                // has seen its 128 runs of 11 recessive bits.
                let left = self
                    .nodes
                    .iter()
                    .filter(|n| n.can.conf.is_bus_off())
                    .map(|n| n.can.conf.recovery_bits_left())
                    .min();
                if let Some(left) = left {
                    let more = left.saturating_sub(crate::confinement::TRAILING_RECESSIVE_BITS);
                    let bits = u32::try_from(more).unwrap_or(u32::MAX);
                    let t = self
                        .now
                        .max(from.saturating_add(bits_to_ns(bits, self.bitrate)));
                    self.push_bus(t, Ev::IdleRecover);
                }
            }
        }
    }

    /// The bus stayed idle until now: bus-off controllers whose recovery completed
    /// within this recessive run recover (the others count the run at the next start of
    /// frame, or at the next check).
    fn idle_recover(&mut self) {
        let State::Idle { from } = self.state else {
            return;
        };
        if self.stuck.is_some() {
            return;
        }
        let idle = self.now.saturating_sub(from) / self.bit_ns().max(1);
        let run = crate::confinement::TRAILING_RECESSIVE_BITS + idle;
        for n in 0..self.nodes.len() {
            let Some(node) = self.nodes.get_mut(n) else {
                continue;
            };
            if node.can.conf.is_bus_off()
                && node.can.conf.recovery_bits_left() <= run
                && node.can.conf.recessive(run)
            {
                let t = self.now + node.setup.irq_latency_ns;
                self.push_irq(n, t, Ev::ErrIrq { node: n });
            }
        }
        self.maybe_start_arbitration();
    }

    fn start(&mut self) {
        self.started = true;
        for i in 0..self.nodes.len() {
            self.callback(i, |m, now, can| m.start(now, can));
        }
    }

    /// Runs every event up to and including global time `until`.
    pub fn run_until(&mut self, until: Nanos) {
        if !self.started {
            self.start();
        }
        while let Some((k, j)) = self.next_event() {
            let t = key_time(k);
            if t > until {
                break;
            }
            let Some(ev) = self.take_event(k, j) else {
                break;
            };
            self.now = t;
            self.handle(ev);
        }
        self.now = self.now.max(until);
    }

    fn handle(&mut self, ev: Ev) {
        let now = self.now;
        // A stalled node (interrupts masked) takes its interrupts when the stall ends.
        if let Some(n) = match ev {
            Ev::Wake { node }
            | Ev::RxIrq { node, .. }
            | Ev::TxIrq { node, .. }
            | Ev::ErrIrq { node } => Some(node),
            _ => None,
        } {
            let until = self.nodes.get(n).map_or(0, |x| x.stalled_until);
            if now < until {
                if let Ev::Wake { .. } = ev {
                    let k = key(until, self.next_seq());
                    self.set_wake(n, Some(k));
                } else {
                    self.push_irq(n, until, ev);
                }
                return;
            }
        }
        // With a modelled CPU, interrupts become jobs on it; their effects come back as
        // `Ev::Cpu` when the modelled execution reaches them.
        if let Some(n) = match ev {
            Ev::Wake { node } | Ev::RxIrq { node, .. } | Ev::TxIrq { node, .. } => Some(node),
            _ => None,
        } {
            if let Some(node) = self.nodes.get_mut(n) {
                if let Some((cpu, _)) = node.cpu.as_mut() {
                    match ev {
                        Ev::Wake { .. } => cpu.timer(now),
                        Ev::RxIrq { fifo, .. } => {
                            if let Some(p) = node.can.rx_irq_pending.get_mut(fifo) {
                                *p = false;
                            }
                            cpu.rx_irq(now, fifo);
                        }
                        Ev::TxIrq { mb, result, .. } => {
                            cpu.tx_irq(now, Mailbox(mb), code_result(result));
                        }
                        _ => {}
                    }
                    self.cpu_reschedule(n);
                    return;
                }
            }
        }
        match ev {
            // Taken from the node, so whatever the module asks next is a new deadline.
            Ev::Wake { node } => self.callback(node, |m, now, can| m.wake(now, can)),
            Ev::ArbDecide => self.arbitrate(),
            Ev::FrameEnd => self.frame_end(),
            Ev::RxIrq { node, fifo } => self.rx_irq(node, fifo),
            Ev::TxIrq { node, mb, result } => {
                self.callback(node, |m, now, can| {
                    m.tx_done(Mailbox(mb), code_result(result), now, can)
                });
            }
            Ev::Cpu { node } => self.cpu_step(node),
            // The status-change interrupt is not costed by the CPU model: it is rare
            // (level changes only) and runs directly.
            Ev::ErrIrq { node } => self.error_irq(node),
            Ev::IdleRecover => self.idle_recover(),
        }
    }

    /// Re-keys node `n`'s CPU event after its state changed.
    fn cpu_reschedule(&mut self, n: usize) {
        let Some(t) = self
            .nodes
            .get(n)
            .and_then(|node| node.cpu.as_ref())
            .map(|(c, _)| c.next_event())
        else {
            return;
        };
        let current = self
            .nodes
            .get(n)
            .and_then(|node| node.cpu.as_ref())
            .map(|&(_, k)| k);
        // Keep the place (sequence number) of an unchanged event.
        if current.is_some_and(|k| k != NONE && key_time(k) == t) {
            return;
        }
        let k = key(t.max(self.now), self.next_seq());
        if let Some((_, ck)) = self.nodes.get_mut(n).and_then(|node| node.cpu.as_mut()) {
            *ck = k;
        }
        self.refresh_key(n);
    }

    /// Node `n`'s CPU reached its next event: executes the effect on the module.
    fn cpu_step(&mut self, n: usize) {
        let now = self.now;
        let effect = match self.nodes.get_mut(n).and_then(|node| node.cpu.as_mut()) {
            Some((cpu, _)) => cpu.advance(now),
            None => return,
        };
        let loads = self.nodes.get(n).map_or(0, |node| node.can.stats.loads);
        match effect {
            Effect::None | Effect::Spawn { .. } => {}
            Effect::Wake => {
                self.callback(n, |m, now, can| m.wake(now, can));
            }
            Effect::PopRx { fifo } => {
                if let Some(node) = self.nodes.get_mut(n) {
                    let popped = node.can.fifos.get_mut(fifo).and_then(VecDeque::pop_front);
                    let more = node.can.fifo_len(fifo) > 0;
                    if let Some((cpu, _)) = node.cpu.as_mut() {
                        if let Some((frame, sof)) = popped {
                            cpu.rx_read(now, frame, sof, frame.id().is_sync());
                        }
                        if more {
                            // The interrupt stays requested while the FIFO holds frames.
                            cpu.rx_irq(now, fifo);
                        }
                    }
                }
            }
            Effect::Rx { frame, sof } => {
                self.callback(n, |m, now, can| m.rx(&frame, sof, now, can));
            }
            Effect::TxDone { mailbox, result } => {
                self.callback(n, |m, now, can| m.tx_done(mailbox, result, now, can));
            }
        }
        if let Some(node) = self.nodes.get_mut(n) {
            // A TDMA frame (HRT fragment or sync: laxity 0) loaded by this effect is the
            // TXRQ the slot boundary's latency is about; window frames are not.
            let loaded = node.can.stats.loads > loads
                && node
                    .can
                    .mailboxes
                    .iter()
                    .flatten()
                    .any(|p| p.loaded_at == now && p.frame.id().laxity() == 0);
            if let Some((cpu, _)) = node.cpu.as_mut() {
                if loaded {
                    cpu.loaded(now);
                }
                if effect == Effect::Wake {
                    cpu.wake_done();
                }
            }
        }
        if let Some((cpu, _)) = self.nodes.get_mut(n).and_then(|node| node.cpu.as_mut()) {
            cpu.retire(now);
        }
        self.cpu_reschedule(n);
    }

    fn arbitrate(&mut self) {
        let State::Arbitrating { sof } = self.state else {
            return;
        };
        if self.stuck.is_some() {
            self.state = State::Idle { from: self.now };
            return;
        }
        let now = self.now;
        // Reused buffer: this runs once per frame and must not allocate.
        let mut offers = std::mem::take(&mut self.offers);
        offers.clear();
        // A bus-off or cut-off controller does not transmit; a guardian may stop it.
        offers.extend(self.nodes.iter_mut().enumerate().filter_map(|(n, node)| {
            transmits(node).then_some(())?;
            let (mb, p) = node.can.best_pending()?;
            if let Some(g) = node.guardian.as_mut() {
                g.admit(now, p.frame.id()).then_some(())?;
            }
            Some((p.frame.id().raw(), n, mb))
        }));
        // The start of frame ended the recessive run: a controller that recovers with it
        // joins only the next arbitration.
        self.count_recessive();
        let Some(&(win_id, win_node, win_mb)) = offers.iter().min() else {
            // Everything was aborted during the SOF bit.
            self.state = State::Idle { from: self.now };
            self.offers = offers;
            return;
        };
        if offers.len() > 1 {
            self.stats.contended += 1;
        }
        if offers.iter().filter(|o| o.0 == win_id).count() > 1 {
            self.stats.id_collisions += 1;
        }
        let lat_now = self.now;
        for &(_, n, mb) in offers.iter().filter(|o| o.1 != win_node) {
            let Some(node) = self.nodes.get_mut(n) else {
                continue;
            };
            if node.can.nart {
                node.can.take_mailbox(mb);
                node.can.stats.tx_failed += 1;
                let t = lat_now + node.setup.irq_latency_ns;
                self.push_irq(
                    n,
                    t,
                    Ev::TxIrq {
                        node: n,
                        mb: mb as u8,
                        result: result_code(TxResult::Failed),
                    },
                );
            }
        }
        self.offers = offers;
        let Some(node) = self.nodes.get_mut(win_node) else {
            return;
        };
        let Some(p) = node.can.mailbox(win_mb) else {
            return;
        };
        if let Some(g) = node.guardian.as_mut() {
            g.sent();
        }
        node.can.on_wire = Some(win_mb);
        if let Some(t) = node.can.tx_sof.get_mut(win_mb) {
            *t = sof;
        }
        let bits = exact_bits(&p.frame);
        let body = bits - INTERMISSION_BITS;
        let mut ok = true;
        let mut end_bits = body;
        if self.bit_error_rate > 0.0 {
            let p_err = 1.0 - (1.0 - self.bit_error_rate).powi(body as i32);
            if self.rng.unit() < p_err {
                ok = false;
                let k = self.rng.range(1, u64::from(body - 1)) as u32;
                end_bits = k + ERROR_FRAME_BITS;
            }
        }
        let mut rejects = 0u64;
        if ok && self.eof_error_rate > 0.0 {
            for (n, node) in self.nodes.iter().enumerate() {
                if n != win_node
                    && n < 64
                    && !node.partitioned
                    && !node.can.conf.is_bus_off()
                    && self.rng.unit() < self.eof_error_rate
                {
                    rejects |= 1 << n;
                }
            }
            if rejects != 0 {
                // The error flag starts in the last bit of EOF.
                end_bits = body - 1 + ERROR_FRAME_BITS;
            }
        }
        self.state = State::Busy {
            node: win_node,
            mb: win_mb,
            sof,
            frame: p.frame,
            ok,
            rejects,
        };
        let t = sof + bits_to_ns(end_bits, self.bitrate);
        self.push_bus(t, Ev::FrameEnd);
    }

    fn frame_end(&mut self) {
        let State::Busy {
            node: tx,
            mb,
            sof,
            frame,
            ok: rx_ok,
            rejects,
        } = self.state
        else {
            return;
        };
        // Receivers outside `rejects` accept a frame that is good up to the last-but-one
        // bit of EOF; the transmitter needs the whole EOF.
        let ok = rx_ok && rejects == 0;
        let now = self.now;
        let ifs = bits_to_ns(INTERMISSION_BITS, self.bitrate);
        self.stats.busy_ns += now - sof + ifs;
        if self.record_wire {
            self.wire.push(WireFrame {
                sof,
                end: now,
                node: tx,
                frame,
                ok,
                partial: rx_ok && !ok,
            });
        }
        let mut irqs = std::mem::take(&mut self.irqs);
        irqs.clear();
        if let Some(node) = self.nodes.get_mut(tx) {
            node.can.on_wire = None;
            let lat = now + node.setup.irq_latency_ns;
            let aborting = node.can.abort_requested.get(mb).copied().unwrap_or(false);
            let level = node.can.conf.level();
            if ok {
                node.can.conf.tx_ok();
            } else {
                node.can.conf.tx_error();
            }
            if node.can.conf.level() != level {
                irqs.push((lat, Ev::ErrIrq { node: tx }));
            }
            let result = if ok {
                node.can.stats.tx_ok += 1;
                Some(TxResult::Sent)
            } else if node.can.nart {
                node.can.stats.tx_failed += 1;
                Some(TxResult::Failed)
            } else if aborting {
                node.can.stats.aborted += 1;
                Some(TxResult::Aborted)
            } else {
                None // automatic retransmission
            };
            if let Some(r) = result {
                node.can.take_mailbox(mb);
                irqs.push((
                    lat,
                    Ev::TxIrq {
                        node: tx,
                        mb: mb as u8,
                        result: result_code(r),
                    },
                ));
            }
        }
        // Every receiver on the bus counts the frame, whatever its filters.
        for (n, node) in self.nodes.iter_mut().enumerate().filter(|(n, _)| *n != tx) {
            if node.partitioned {
                continue;
            }
            let level = node.can.conf.level();
            if rx_ok && rejects & (1u64 << n.min(63)) == 0 {
                node.can.conf.rx_ok();
            } else {
                node.can.conf.rx_error();
            }
            if node.can.conf.level() != level {
                irqs.push((now + node.setup.irq_latency_ns, Ev::ErrIrq { node: n }));
            }
        }
        if !ok && rx_ok {
            self.stats.eof_errors += 1;
        }
        if rx_ok {
            if ok {
                self.stats.frames_ok += 1;
            }
            let mut overruns = Vec::new();
            for (n, node) in self.nodes.iter_mut().enumerate().filter(|(n, _)| *n != tx) {
                if node.can.conf.is_bus_off()
                    || node.partitioned
                    || (n < 64 && rejects & (1u64 << n) != 0)
                {
                    continue;
                }
                let Some(fifo) = node.can.filter.fifo_for(frame.id().raw()) else {
                    continue;
                };
                let (Some(q), Some(pending)) = (
                    node.can.fifos.get_mut(fifo),
                    node.can.rx_irq_pending.get_mut(fifo),
                ) else {
                    continue;
                };
                if q.len() >= RX_FIFO_DEPTH {
                    if let Some(c) = node.can.stats.rx_overrun.get_mut(fifo) {
                        *c += 1;
                    }
                    overruns.push(n);
                    continue;
                }
                q.push_back((frame, node.setup.clock.local(sof)));
                node.can.stats.rx_frames += 1;
                if !*pending {
                    *pending = true;
                    irqs.push((now + node.setup.irq_latency_ns, Ev::RxIrq { node: n, fifo }));
                }
            }
            for n in overruns {
                if let Some(node) = self.nodes.get_mut(n) {
                    let local = node.setup.clock.local(now);
                    node.module.rx_overrun(local);
                }
            }
        } else {
            self.stats.error_frames += 1;
        }
        for &(t, ev) in &irqs {
            let n = match ev {
                Ev::RxIrq { node, .. } | Ev::TxIrq { node, .. } | Ev::ErrIrq { node } => node,
                _ => continue,
            };
            self.push_irq(n, t, ev);
        }
        self.irqs = irqs;
        self.state = State::Idle { from: now + ifs };
        self.maybe_start_arbitration();
    }

    /// Bus-off controllers count the recessive run that preceded this start of frame;
    /// those that recover report it.
    fn count_recessive(&mut self) {
        let run = self.recessive_run;
        for n in 0..self.nodes.len() {
            let Some(node) = self.nodes.get_mut(n) else {
                continue;
            };
            if node.can.conf.recessive(run) {
                let t = self.now + node.setup.irq_latency_ns;
                self.push_irq(n, t, Ev::ErrIrq { node: n });
            }
        }
    }

    /// Reports the controller's fault-confinement state to the module.
    fn error_irq(&mut self, n: usize) {
        let Some(node) = self.nodes.get(n) else {
            return;
        };
        let state = node.can.conf.state();
        // A module without fault handling keeps its timer.
        let keep = node.wake.and(node.last_req.map(|r| r.0));
        self.callback(n, |m, now, can| m.error_state(now, state, can).or(keep));
    }

    fn rx_irq(&mut self, n: usize, fifo: usize) {
        if let Some(p) = self
            .nodes
            .get_mut(n)
            .and_then(|node| node.can.rx_irq_pending.get_mut(fifo))
        {
            *p = false;
        }
        // The driver's ISR reads until the FIFO is empty (frames arriving meanwhile too).
        while let Some((frame, sof)) = self
            .nodes
            .get_mut(n)
            .and_then(|node| node.can.fifos.get_mut(fifo))
            .and_then(|q| q.pop_front())
        {
            self.callback(n, |m, now, can| m.rx(&frame, sof, now, can));
        }
    }
}
