//! An ideal CAN bus for end-to-end tests of generated modules (after
//! rtcan-core/tests/common): bit-accurate frame durations, arbitration by identifier,
//! bxCAN-like mailboxes, every receiver applying its generated acceptance filters, and
//! each module's engine driving its generated `ModuleHost`. Clocks are ideal.
#![allow(
    dead_code,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing
)]

use rtcan::core::driver::{Controller, Mailbox, TxResult};
use rtcan::core::engine::Engine;
use rtcan::core::frame::Frame;
use rtcan::core::timing::{bits_to_ns, exact_bits};
use rtcan::core::Nanos;
use rtcan::pubsub::ModuleHost;

/// Mailboxes of one controller plus the aborts requested during an engine call.
#[derive(Default)]
pub struct TestCan {
    pub mailboxes: [Option<Frame>; 3],
    pub on_wire: Option<usize>,
    pub abort_requests: Vec<usize>,
}

impl Controller for TestCan {
    fn load(&mut self, mailbox: Mailbox, frame: &Frame) {
        let slot = &mut self.mailboxes[usize::from(mailbox.0)];
        assert!(slot.is_none(), "engine loaded a busy mailbox {mailbox:?}");
        *slot = Some(*frame);
    }
    fn abort(&mut self, mailbox: Mailbox) {
        self.abort_requests.push(usize::from(mailbox.0));
    }
}

/// One module on the bus: whatever its engine's const generics are.
pub trait Station {
    fn can(&mut self) -> &mut TestCan;
    fn filters(&self) -> &'static [(u32, u32)];
    fn poll(&mut self, now: Nanos);
    fn on_rx(&mut self, frame: &Frame, sof: Nanos);
    fn on_tx_done(&mut self, mailbox: usize, result: TxResult, now: Nanos);
    fn next_wakeup(&self) -> Nanos;
}

/// A generated module: its engine, its `ModuleHost` and its filters.
pub struct Module<const RX: usize, const A: usize, const Q: usize> {
    pub engine: Engine<'static, RX, A, Q>,
    pub host: ModuleHost<'static>,
    pub can: TestCan,
    pub filters: &'static [(u32, u32)],
}

impl<const RX: usize, const A: usize, const Q: usize> Module<RX, A, Q> {
    pub fn new(
        engine: Engine<'static, RX, A, Q>,
        host: ModuleHost<'static>,
        filters: &'static [(u32, u32)],
    ) -> Self {
        Module {
            engine,
            host,
            can: TestCan::default(),
            filters,
        }
    }
}

impl<const RX: usize, const A: usize, const Q: usize> Station for Module<RX, A, Q> {
    fn can(&mut self) -> &mut TestCan {
        &mut self.can
    }
    fn filters(&self) -> &'static [(u32, u32)] {
        self.filters
    }
    fn poll(&mut self, now: Nanos) {
        self.engine.poll(now, &mut self.can, &mut self.host);
        // Queued SRT/NRT messages go to the engine after every poll (no kick hook here).
        self.host.pump(&mut self.engine, now, &mut self.can);
    }
    fn on_rx(&mut self, frame: &Frame, sof: Nanos) {
        self.engine.on_rx(frame, sof, &mut self.can, &mut self.host);
    }
    fn on_tx_done(&mut self, mailbox: usize, result: TxResult, now: Nanos) {
        self.engine.on_tx_done(
            Mailbox(mailbox as u8),
            result,
            now,
            &mut self.can,
            &mut self.host,
        );
    }
    fn next_wakeup(&self) -> Nanos {
        self.engine.next_wakeup()
    }
}

/// A frame seen on the bus.
#[derive(Clone, Debug)]
pub struct WireFrame {
    pub node: usize,
    pub frame: Frame,
    pub sof: Nanos,
    pub end: Nanos,
}

pub struct Bus {
    pub nodes: Vec<Box<dyn Station>>,
    pub bitrate: u32,
    pub now: Nanos,
    pub log: Vec<WireFrame>,
    /// Frames a receiver's filters rejected: (node, identifier).
    pub filtered: Vec<(usize, u32)>,
    current: Option<WireFrame>,
}

impl Bus {
    pub fn new(bitrate: u32) -> Self {
        Bus {
            nodes: Vec::new(),
            bitrate,
            now: 0,
            log: Vec::new(),
            filtered: Vec::new(),
            current: None,
        }
    }

    pub fn add(&mut self, node: Box<dyn Station>) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    /// Resolves aborts requested during the last engine call of node `i`.
    fn settle(&mut self, i: usize) {
        let now = self.now;
        let n = &mut self.nodes[i];
        while let Some(mb) = n.can().abort_requests.pop() {
            if n.can().on_wire == Some(mb) || n.can().mailboxes[mb].is_none() {
                continue;
            }
            n.can().mailboxes[mb] = None;
            n.on_tx_done(mb, TxResult::Aborted, now);
        }
    }

    /// Runs until time `until`; `each` is called after every step (to publish, pump...).
    pub fn run(&mut self, until: Nanos) {
        loop {
            let mut next = until;
            for n in &self.nodes {
                next = next.min(n.next_wakeup());
            }
            if let Some(cur) = &self.current {
                next = next.min(cur.end);
            }
            self.now = next.max(self.now);
            if let Some(cur) = self.current.clone() {
                if cur.end <= self.now {
                    self.current = None;
                    for j in 0..self.nodes.len() {
                        if j == cur.node {
                            continue;
                        }
                        let raw = cur.frame.id().raw();
                        if rtcan::filters_pass(self.nodes[j].filters(), raw) {
                            self.nodes[j].on_rx(&cur.frame, cur.sof);
                            self.settle(j);
                        } else {
                            self.filtered.push((j, raw));
                        }
                    }
                    let now = self.now;
                    let n = &mut self.nodes[cur.node];
                    let mb = n.can().on_wire.take().expect("wire mailbox");
                    n.can().mailboxes[mb] = None;
                    n.on_tx_done(mb, TxResult::Sent, now);
                    self.settle(cur.node);
                    self.log.push(cur);
                    continue;
                }
            }
            let mut fired = false;
            for i in 0..self.nodes.len() {
                if self.nodes[i].next_wakeup() <= self.now {
                    let now = self.now;
                    self.nodes[i].poll(now);
                    self.settle(i);
                    fired = true;
                }
            }
            let mut started = false;
            if self.current.is_none() {
                let mut best: Option<(u32, usize, usize)> = None;
                for (i, n) in self.nodes.iter_mut().enumerate() {
                    for (m, f) in n.can().mailboxes.iter().enumerate() {
                        if let Some(f) = f {
                            if best.is_none_or(|b| f.id().raw() < b.0) {
                                best = Some((f.id().raw(), i, m));
                            }
                        }
                    }
                }
                if let Some((_, i, m)) = best {
                    let frame = self.nodes[i].can().mailboxes[m].expect("loaded");
                    let dur = bits_to_ns(exact_bits(&frame), self.bitrate);
                    self.nodes[i].can().on_wire = Some(m);
                    self.current = Some(WireFrame {
                        node: i,
                        frame,
                        sof: self.now,
                        end: self.now + dur,
                    });
                    started = true;
                }
            }
            let busy_past = self.current.as_ref().is_some_and(|c| c.end > until);
            if !fired && !started && self.now >= until && (self.current.is_none() || busy_past) {
                break;
            }
        }
    }
}
