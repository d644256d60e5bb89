//! A discrete-event software CAN bus: bus time advances from event to event (frame
//! ends, engine wake-ups); when the bus is idle the lowest identifier among all loaded
//! mailboxes wins arbitration, occupies the bus for its exact length (real stuff bits,
//! `timing::exact_bits`) and is then received, with its SOF time, by every other node
//! whose acceptance filters pass it.
//! Each node has its own local clock (`local = bus + offset`), so slaves must really
//! synchronise on the master's sync frame.
use crate::meter::{Kind, Meter};
use crate::soft_can::SoftCan;
use rtcan_core::driver::{Host, Mailbox, Token, TxResult};
use rtcan_core::engine::{Engine, SubmitError};
use rtcan_core::frame::Frame;
use rtcan_core::time::Nanos;
use rtcan_core::timing::{bits_to_ns, exact_bits};
use rtcan_pubsub::ModuleHost;

/// One node as the bus sees it.
pub trait Node {
    /// Its controller.
    fn can(&mut self) -> &mut SoftCan;
    /// Local time at bus time `bus`.
    fn local(&self, bus: Nanos) -> Nanos;
    /// Bus time of the node's next wake-up (`Nanos::MAX`: none).
    fn next_wake_bus(&self) -> Nanos;
    /// Slot timer fired at bus time `bus`.
    fn poll(&mut self, bus: Nanos, meter: &mut dyn Meter);
    /// A frame arrived whose SOF was at bus time `sof`.
    fn rx(&mut self, frame: &Frame, sof: Nanos, now: Nanos, meter: &mut dyn Meter);
    /// A mailbox completed at bus time `now`.
    fn tx_done(&mut self, mailbox: Mailbox, result: TxResult, now: Nanos, meter: &mut dyn Meter);
}

/// What a host does after the engine ran its slot timer: an R2P `ModuleHost` hands the
/// messages its topics queued to the engine (`ModuleHost::pump`; the generated code's
/// `kick` hook is not used on this bus); a host that submits directly does nothing.
pub trait Pump: Host {
    /// Submits what is queued above the engine; returns how many were submitted.
    fn pump<const RX: usize, const A: usize, const Q: usize>(
        &mut self,
        _engine: &mut Engine<'_, RX, A, Q>,
        _now: Nanos,
        _can: &mut SoftCan,
    ) -> usize {
        0
    }
}

impl Pump for ModuleHost<'_> {
    fn pump<const RX: usize, const A: usize, const Q: usize>(
        &mut self,
        engine: &mut Engine<'_, RX, A, Q>,
        now: Nanos,
        can: &mut SoftCan,
    ) -> usize {
        ModuleHost::pump(self, engine, now, can)
    }
}

/// An engine, its host and controller, and a local clock offset from bus time.
pub struct Station<'t, H: Pump, const RX: usize, const A: usize, const Q: usize> {
    /// The engine.
    pub engine: Engine<'t, RX, A, Q>,
    /// The host above it.
    pub host: H,
    /// The controller below it.
    pub can: SoftCan,
    /// Local clock = bus time + offset.
    pub offset: Nanos,
    next: Nanos,
}

impl<'t, H: Pump, const RX: usize, const A: usize, const Q: usize> Station<'t, H, RX, A, Q> {
    /// A station whose engine starts at bus time `bus_now`.
    pub fn new(engine: Engine<'t, RX, A, Q>, host: H, offset: Nanos) -> Self {
        Station {
            engine,
            host,
            can: SoftCan::new(),
            offset,
            next: 0,
        }
    }
    /// The same station behind acceptance filters (a module's generated `FILTERS`).
    pub fn filtered(mut self, filters: &'static [(u32, u32)]) -> Self {
        self.can = SoftCan::with_filters(filters);
        self
    }
    /// Submits an SRT/NRT message at bus time `bus`.
    pub fn submit(&mut self, bus: Nanos, tx: u8, token: Token) -> Result<(), SubmitError> {
        let now = bus + self.offset;
        let r = self
            .engine
            .submit(now, tx, token, &mut self.can, &mut self.host);
        self.next = self.engine.next_wakeup();
        r
    }
    /// Hands what the host queued (published SRT/NRT messages) to the engine at bus
    /// time `bus`; returns how many were submitted.
    pub fn pump(&mut self, bus: Nanos) -> usize {
        let now = bus + self.offset;
        let n = self.host.pump(&mut self.engine, now, &mut self.can);
        self.next = self.engine.next_wakeup();
        n
    }
}

impl<H: Pump, const RX: usize, const A: usize, const Q: usize> Node for Station<'_, H, RX, A, Q> {
    fn can(&mut self) -> &mut SoftCan {
        &mut self.can
    }
    fn local(&self, bus: Nanos) -> Nanos {
        bus + self.offset
    }
    fn next_wake_bus(&self) -> Nanos {
        self.next.saturating_sub(self.offset)
    }
    fn poll(&mut self, bus: Nanos, meter: &mut dyn Meter) {
        let now = bus + self.offset;
        let (e, c, h) = (&mut self.engine, &mut self.can, &mut self.host);
        let mut next = 0;
        meter.measure(Kind::Poll, &mut || next = e.poll(now, c, h));
        // Not metered: the middleware's work, not the engine's slot-boundary handling.
        if h.pump(e, now, c) > 0 {
            next = e.next_wakeup();
        }
        // Guard against a wake-up that is not in the future (would stall the bus loop).
        self.next = next.max(now + 1);
    }
    fn rx(&mut self, frame: &Frame, sof: Nanos, now: Nanos, meter: &mut dyn Meter) {
        let (sof, _now) = (sof + self.offset, now + self.offset);
        let (e, c, h) = (&mut self.engine, &mut self.can, &mut self.host);
        meter.measure(Kind::Rx, &mut || e.on_rx(frame, sof, c, h));
        self.next = self.engine.next_wakeup();
    }
    fn tx_done(&mut self, mailbox: Mailbox, result: TxResult, now: Nanos, meter: &mut dyn Meter) {
        let now = now + self.offset;
        let (e, c, h) = (&mut self.engine, &mut self.can, &mut self.host);
        meter.measure(Kind::TxDone, &mut || {
            e.on_tx_done(mailbox, result, now, c, h)
        });
        self.next = self.engine.next_wakeup();
    }
}

/// Bus statistics.
#[derive(Clone, Copy, Debug, Default)]
pub struct BusStats {
    /// Frames transmitted.
    pub frames: u32,
    /// Bus time spent transmitting, ns.
    pub busy_ns: Nanos,
}

/// The bus: time and the frame on the wire.
pub struct SoftBus {
    bitrate: u32,
    /// Bus time now, ns.
    pub now: Nanos,
    /// (node, mailbox, frame, sof, end)
    wire: Option<(usize, Frame, Nanos, Nanos)>,
    /// Statistics.
    pub stats: BusStats,
}

impl SoftBus {
    /// Idle bus at time 0.
    pub const fn new(bitrate: u32) -> Self {
        SoftBus {
            bitrate,
            now: 0,
            wire: None,
            stats: BusStats {
                frames: 0,
                busy_ns: 0,
            },
        }
    }

    /// Runs every node until bus time `until`.
    pub fn run_until(&mut self, nodes: &mut [&mut dyn Node], until: Nanos, meter: &mut dyn Meter) {
        loop {
            let t = self.now;
            // 1. End of the frame on the wire: receivers, then the sender's completion.
            if let Some((sender, frame, sof, end)) = self.wire {
                if end <= t {
                    self.wire = None;
                    for (i, n) in nodes.iter_mut().enumerate() {
                        if i != sender && n.can().accepts(frame.id().raw()) {
                            n.rx(&frame, sof, t, meter);
                        }
                    }
                    if let Some(n) = nodes.get_mut(sender) {
                        n.can().finish();
                    }
                }
            }
            // 2. Completions (sent, aborted) and due wake-ups.
            for n in nodes.iter_mut() {
                while let Some((m, r)) = n.can().take_completion() {
                    n.tx_done(m, r, t, meter);
                }
                if n.next_wake_bus() <= t {
                    n.poll(t, meter);
                    while let Some((m, r)) = n.can().take_completion() {
                        n.tx_done(m, r, t, meter);
                    }
                }
            }
            // 3. Arbitration on an idle bus: lowest identifier wins.
            if self.wire.is_none() {
                let mut best: Option<(usize, usize, Frame)> = None;
                for (i, n) in nodes.iter_mut().enumerate() {
                    if let Some((m, f)) = n.can().best() {
                        if best.is_none_or(|(_, _, b)| f.id().raw() < b.id().raw()) {
                            best = Some((i, m, f));
                        }
                    }
                }
                if let Some((i, m, f)) = best {
                    if let Some(n) = nodes.get_mut(i) {
                        n.can().start(m);
                    }
                    let len = bits_to_ns(exact_bits(&f), self.bitrate);
                    self.wire = Some((i, f, t, t + len));
                    self.stats.frames += 1;
                    self.stats.busy_ns += len;
                }
            }
            // 4. Next event.
            let mut next = self.wire.map_or(Nanos::MAX, |w| w.3);
            for n in nodes.iter_mut() {
                next = next.min(n.next_wake_bus());
            }
            if next > until {
                self.now = until;
                return;
            }
            self.now = next.max(t + 1);
        }
    }
}
