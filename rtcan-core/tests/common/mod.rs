//! A minimal ideal CAN bus for engine tests: bit-accurate frame durations, arbitration
//! by identifier, per-node clocks with offset and drift, bxCAN-like mailboxes.
//! (The full simulator with FIFOs, latency and errors is rtcan-sim.)
#![allow(dead_code)]

use rtcan_core::driver::{Controller, Event, Host, Mailbox, Token, TxOutcome, TxResult};
use rtcan_core::engine::Engine;
use rtcan_core::frame::Frame;
use rtcan_core::id::CanId;

/// Which identifiers a `Bus::destroy` entry hits.
pub type IdMatch = fn(CanId) -> bool;
use rtcan_core::tables::NodeTables;
use rtcan_core::timing::{bits_to_ns, exact_bits};
use rtcan_core::Nanos;

/// Controller of one node: mailbox contents plus requests made during an engine call.
#[derive(Default)]
pub struct TestCan {
    pub mailboxes: [Option<Frame>; 3],
    pub on_wire: Option<usize>,
    pub abort_requests: Vec<usize>,
}

impl Controller for TestCan {
    fn load(&mut self, mailbox: Mailbox, frame: &Frame) {
        let slot = &mut self.mailboxes[mailbox.0 as usize];
        assert!(slot.is_none(), "engine loaded a busy mailbox {mailbox:?}");
        *slot = Some(*frame);
    }
    fn abort(&mut self, mailbox: Mailbox) {
        self.abort_requests.push(mailbox.0 as usize);
    }
}

/// Host with messages in a Vec; records everything.
#[derive(Default)]
pub struct TestHost {
    pub messages: Vec<Vec<u8>>,
    /// HRT: payload returned by hrt_sample for each tx index (None = nothing to send).
    pub hrt: Vec<Option<Vec<u8>>>,
    pub delivered: Vec<(u8, Vec<u8>, Nanos)>,
    pub done: Vec<(u8, Option<Token>, TxOutcome)>,
    pub events: Vec<Event>,
    pub fingerprint_state: u8,
    /// HRT: hand out the same token for every sample of a topic (as a pool that reuses
    /// the block the engine just released), overwriting its payload.
    pub reuse_hrt_tokens: bool,
    pub hrt_tokens: Vec<Option<Token>>,
    /// Update-channel frames to send (front first) and the ones received.
    pub service_out: std::collections::VecDeque<Frame>,
    pub service_in: Vec<Frame>,
}

impl TestHost {
    pub fn add(&mut self, payload: &[u8]) -> Token {
        self.messages.push(payload.to_vec());
        Token((self.messages.len() - 1) as u16)
    }
}

impl Host for TestHost {
    fn hrt_sample(&mut self, tx: u8) -> Option<Token> {
        let p = self.hrt.get(tx as usize).cloned().flatten()?;
        if !self.reuse_hrt_tokens {
            return Some(self.add(&p));
        }
        let tx = tx as usize;
        if self.hrt_tokens.len() <= tx {
            self.hrt_tokens.resize(tx + 1, None);
        }
        match self.hrt_tokens[tx] {
            Some(t) => {
                self.messages[t.0 as usize] = p;
                Some(t)
            }
            None => {
                let t = self.add(&p);
                self.hrt_tokens[tx] = Some(t);
                Some(t)
            }
        }
    }
    fn payload(&self, token: Token) -> &[u8] {
        &self.messages[token.0 as usize]
    }
    fn tx_done(&mut self, tx: u8, token: Option<Token>, outcome: TxOutcome) {
        self.done.push((tx, token, outcome));
    }
    fn deliver(&mut self, rx: u8, payload: &[u8], sof: Nanos) {
        self.delivered.push((rx, payload.to_vec(), sof));
    }
    fn event(&mut self, event: Event) {
        self.events.push(event);
    }
    fn service_rx(&mut self, frame: &Frame, _sof: Nanos) {
        self.service_in.push(*frame);
    }
    fn service_tx(&mut self) -> Option<Frame> {
        self.service_out.front().copied()
    }
    fn service_sent(&mut self) {
        self.service_out.pop_front();
    }
}

pub type TestEngine = Engine<'static, 16, 512, 16>;

pub struct Node {
    pub engine: TestEngine,
    pub can: TestCan,
    pub host: TestHost,
    /// local = global * (1 + ppm/1e6) + offset
    pub ppm: f64,
    pub offset: f64,
    pub wake: Nanos,
    pub alive: bool,
}

impl Node {
    pub fn local(&self, global: Nanos) -> Nanos {
        (global as f64 * (1.0 + self.ppm * 1e-6) + self.offset).round() as Nanos
    }
    pub fn global(&self, local: Nanos) -> Nanos {
        if local == Nanos::MAX {
            return Nanos::MAX;
        }
        ((local as f64 - self.offset) / (1.0 + self.ppm * 1e-6)).ceil() as Nanos
    }
}

/// One transmitted frame as seen on the bus (global time).
#[derive(Clone, Debug)]
pub struct WireFrame {
    pub node: usize,
    pub frame: Frame,
    pub sof: Nanos,
    pub end: Nanos,
}

/// Bit times an error frame and the intermission after it occupy the bus.
pub const ERROR_FRAME_BITS: u64 = 20;

pub struct Bus {
    pub nodes: Vec<Node>,
    pub bitrate: u32,
    pub now: Nanos,
    pub log: Vec<WireFrame>,
    /// Transmissions to destroy with an error frame: the first one whose identifier
    /// `.1` accepts, starting at or after global time `.0`. Receivers drop it; the
    /// transmitter's mailbox stays loaded and retransmits (automatic retransmission, as on
    /// bxCAN). A predicate, not a raw ID: fragment fields carry transfer IDs (§7.1).
    pub destroy: Vec<(Nanos, IdMatch)>,
    /// Transmissions destroyed so far (the frames, as they were on the wire).
    pub destroyed: Vec<WireFrame>,
    current: Option<WireFrame>,
    /// No arbitration before this time (end of an error frame).
    idle_at: Nanos,
}

impl Bus {
    pub fn new(bitrate: u32) -> Self {
        Bus {
            nodes: Vec::new(),
            bitrate,
            now: 0,
            log: Vec::new(),
            destroy: Vec::new(),
            destroyed: Vec::new(),
            current: None,
            idle_at: 0,
        }
    }

    pub fn add(&mut self, tables: NodeTables<'static>, ppm: f64, offset: f64) -> usize {
        let mut node = Node {
            engine: TestEngine::new(tables, 0),
            can: TestCan::default(),
            host: TestHost::default(),
            ppm,
            offset,
            wake: 0,
            alive: true,
        };
        node.engine = TestEngine::new(tables, node.local(0));
        node.wake = node.global(node.engine.next_wakeup());
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    /// Resolves abort requests made during the last engine call of node `i`.
    fn settle(&mut self, i: usize) {
        loop {
            let n = &mut self.nodes[i];
            let Some(mb) = n.can.abort_requests.pop() else {
                break;
            };
            if n.can.on_wire == Some(mb) || n.can.mailboxes[mb].is_none() {
                continue; // on the wire: it completes; empty: nothing to do
            }
            n.can.mailboxes[mb] = None;
            let local = n.local(self.now);
            n.engine.on_tx_done(
                Mailbox(mb as u8),
                TxResult::Aborted,
                local,
                &mut n.can,
                &mut n.host,
            );
        }
        let n = &mut self.nodes[i];
        n.wake = n.global(n.engine.next_wakeup());
    }

    /// Runs until global time `until`.
    pub fn run(&mut self, until: Nanos) {
        let mut spins = 0u32;
        loop {
            let mut next = until;
            for n in &self.nodes {
                if n.alive {
                    next = next.min(n.wake);
                }
            }
            if let Some(cur) = &self.current {
                next = next.min(cur.end);
            }
            if self.idle_at > self.now {
                next = next.min(self.idle_at);
            }
            let before = self.now;
            self.now = next.max(self.now);
            spins = if self.now == before { spins + 1 } else { 0 };
            assert!(spins < 10_000, "no progress at t={}", self.now);
            // 1. End of transmission.
            if let Some(cur) = self.current.clone() {
                if cur.end <= self.now {
                    self.current = None;
                    let hit = self
                        .destroy
                        .iter()
                        .position(|&(t, hit)| cur.sof >= t && hit(cur.frame.id()));
                    if let Some(k) = hit {
                        self.destroy.remove(k);
                        self.nodes[cur.node].can.on_wire = None;
                        self.idle_at = cur.end + bits_to_ns(ERROR_FRAME_BITS as u32, self.bitrate);
                        self.destroyed.push(cur);
                        continue;
                    }
                    for j in 0..self.nodes.len() {
                        if j == cur.node || !self.nodes[j].alive {
                            continue;
                        }
                        let n = &mut self.nodes[j];
                        let sof = n.local(cur.sof);
                        n.engine.on_rx(&cur.frame, sof, &mut n.can, &mut n.host);
                        self.settle(j);
                    }
                    let n = &mut self.nodes[cur.node];
                    let mb = n.can.on_wire.take().expect("wire mailbox");
                    n.can.mailboxes[mb] = None;
                    let local = n.local(self.now);
                    n.engine.on_tx_done(
                        Mailbox(mb as u8),
                        TxResult::Sent,
                        local,
                        &mut n.can,
                        &mut n.host,
                    );
                    self.settle(cur.node);
                    self.log.push(cur);
                    // On to timers and arbitration at this same instant: a pending frame
                    // starts as soon as the bus is idle, not at the next timer event.
                }
            }
            // 2. Node timers.
            let mut fired = false;
            for i in 0..self.nodes.len() {
                if self.nodes[i].alive && self.nodes[i].wake <= self.now {
                    let n = &mut self.nodes[i];
                    let local = n.local(self.now);
                    n.engine.poll(local, &mut n.can, &mut n.host);
                    self.settle(i);
                    fired = true;
                }
            }
            // 3. Arbitration when idle: the lowest identifier among all mailboxes wins.
            let mut started = false;
            if self.current.is_none() && self.now >= self.idle_at {
                let mut best: Option<(u32, usize, usize)> = None;
                for (i, n) in self.nodes.iter().enumerate() {
                    if !n.alive {
                        continue;
                    }
                    for (m, f) in n.can.mailboxes.iter().enumerate() {
                        if let Some(f) = f {
                            if best.is_none_or(|b| f.id().raw() < b.0) {
                                best = Some((f.id().raw(), i, m));
                            }
                        }
                    }
                }
                if let Some((_, i, m)) = best {
                    let frame = self.nodes[i].can.mailboxes[m].expect("loaded");
                    let dur = bits_to_ns(exact_bits(&frame), self.bitrate);
                    self.nodes[i].can.on_wire = Some(m);
                    self.current = Some(WireFrame {
                        node: i,
                        frame,
                        sof: self.now,
                        end: self.now + dur,
                    });
                    started = true;
                }
            }
            if !fired && !started && self.current.is_none() && self.now >= until {
                break;
            }
            if !fired
                && !started
                && self.now >= until
                && self.current.as_ref().is_some_and(|c| c.end > until)
            {
                break;
            }
        }
    }

    /// Submits an SRT/NRT message on node `i` at the current time.
    pub fn submit(
        &mut self,
        i: usize,
        tx: u8,
        payload: &[u8],
    ) -> Result<(), rtcan_core::engine::SubmitError> {
        let now = self.now;
        let n = &mut self.nodes[i];
        let token = n.host.add(payload);
        let local = n.local(now);
        let r = n.engine.submit(local, tx, token, &mut n.can, &mut n.host);
        self.settle(i);
        r
    }
}
