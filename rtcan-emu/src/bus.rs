//! The emulated MCUs as nodes of the simulator's bus (`rtcan_sim::Bus`): each emulated
//! bxCAN is a node of that bus, driven from here (`rtcan_sim::bus::Activity`,
//! `set_offer`, `takes_frame`). rtcan-sim arbitrates, times every frame from its real
//! bits (`rtcan_core::timing::exact_bits`), destroys frames by bit errors or a bus held
//! dominant, keeps every controller's error counters (ISO 11898-1 fault confinement,
//! bus-off and its recovery) and applies its bus faults (`rtcan_sim::fault`); the
//! emulated bxCANs hold the mailboxes, filters and FIFOs the images program.
//!
//! Co-simulation: an emulated CPU must run instruction by instruction up to every bus
//! event and may raise a transmit request at any instruction. The loop below keeps
//! every MCU at the bus time of each decision:
//! - a frame on the wire: the MCUs run to its last-but-one EOF bit, where the receivers
//!   take it (bxCAN's RX interrupt, ISO 11898-1 §10.7), then to its end, where the
//!   transmitter's mailbox completes;
//! - at the first idle bit after the intermission every bxCAN's best pending mailbox is
//!   offered to the bus, which decides the arbitration one bit later;
//! - on an idle bus with nothing pending each MCU runs up to 40 bits ahead or to its first
//!   transmit request (TXRQ), and the frame starts on the bit after the earliest request.
//!   Running ahead is safe: 40 bits is less than the shortest frame, so no node can miss
//!   the end of a frame it should receive, and a node that ran past the start of a frame
//!   had no request by then.
use rtcan_core::confinement::ErrorState;
use rtcan_core::frame::Frame;
use rtcan_core::id::CanId;
use rtcan_core::Nanos;
use rtcan_sim::bus::{Activity, Module, NodeSetup};
use rtcan_sim::fault::{Fault, FaultKind};
use rtcan_sim::{Filter, SimController};

use crate::bxcan::RawFrame;
use crate::mcu::Mcu;

/// The rtcan-sim side of an emulated node: the bus's events reach the emulated bxCAN
/// through `Bus` (below), not through this module, which therefore does nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Port;

impl Module for Port {
    fn start(&mut self, _: Nanos, _: &mut SimController) -> Option<Nanos> {
        None
    }
    fn wake(&mut self, _: Nanos, _: &mut SimController) -> Option<Nanos> {
        None
    }
    fn rx(&mut self, _: &Frame, _: Nanos, _: Nanos, _: &mut SimController) -> Option<Nanos> {
        None
    }
    fn tx_done(
        &mut self,
        _: rtcan_core::driver::Mailbox,
        _: rtcan_core::driver::TxResult,
        _: Nanos,
        _: &mut SimController,
    ) -> Option<Nanos> {
        None
    }
    fn rx_overrun(&mut self, _: Nanos) {}
}

/// An extended data frame as rtcan-core's `Frame` (RTCAN uses nothing else).
pub fn raw_to_frame(f: &RawFrame) -> Option<Frame> {
    if !f.ide || f.rtr {
        return None;
    }
    Frame::from_parts(CanId::from_raw(f.id)?, f.dlc.min(8), f.data)
}

/// rtcan-core's `Frame` as a receiving bxCAN's FIFO registers hold it (only the DLC
/// bytes cross the wire: the others read 0).
pub fn frame_to_raw(f: &Frame) -> RawFrame {
    RawFrame {
        id: f.id().raw(),
        ide: true,
        rtr: false,
        dlc: f.dlc(),
        data: *f.raw_data(),
    }
}

/// Bits the MCUs may run ahead of an idle bus: less than the shortest frame (44 bits
/// with intermission), so no node can miss a frame end by running ahead.
const LOOK_AHEAD: u64 = 40;

/// The emulated MCUs on rtcan-sim's bus.
pub struct Bus {
    pub mcus: Vec<Mcu>,
    /// The simulator's bus, one node per MCU (same index).
    pub sim: rtcan_sim::Bus<Port>,
    /// Frames completed without error: (sender, frame, SOF bit).
    pub log: Vec<(usize, RawFrame, u64)>,
    /// Per `log` entry: when the sender's code requested it (TXRQ, ps) and, for a frame
    /// the slot-timer interrupt committed, the slot boundary (TIM2 match, ps).
    pub meta: Vec<(u64, Option<u64>)>,
    pub bit_ps: u64,
    bit_ns: Nanos,
    /// SOF of the frame whose start the bxCANs were told of, and of the frame whose
    /// receivers have taken it.
    started: Option<Nanos>,
    received: Option<Nanos>,
    /// Confinement state last given to each bxCAN, and each MCU's reset count then.
    given: Vec<(ErrorState, u32)>,
    /// Scheduled faults not yet applied, in time order.
    faults: Vec<Fault>,
    /// SRT publication stamps, read from the publishers' RAM at every start of frame.
    pub publications: Option<crate::publications::Publications>,
}

impl Bus {
    /// The MCUs on a bus with bit time `bit_ps` (1 Mbit/s: 1 000 000), error free.
    pub fn new(mcus: Vec<Mcu>, bit_ps: u64) -> Bus {
        let bit_ps = bit_ps.max(1_000);
        let bitrate = u32::try_from(1_000_000_000_000 / bit_ps).unwrap_or(u32::MAX);
        let mut sim = rtcan_sim::Bus::new(bitrate, 0.0, 0);
        for _ in &mcus {
            sim.add_node(
                Port,
                NodeSetup {
                    // The bxCAN's own filters and FIFOs take the frames (`takes_frame`).
                    filter: Filter::Rules(Vec::new()),
                    ..NodeSetup::default()
                },
            );
        }
        sim.run_until(0);
        let given = mcus
            .iter()
            .map(|m| (ErrorState::default(), m.st.resets))
            .collect();
        Bus {
            mcus,
            sim,
            log: Vec::new(),
            meta: Vec::new(),
            bit_ps,
            bit_ns: bit_ps / 1_000,
            started: None,
            received: None,
            given,
            faults: Vec::new(),
            publications: None,
        }
    }

    /// Schedules `f` (rtcan-sim's fault, `rtcan_sim::fault::parse`): a bus fault
    /// (`stuck`, `release`, `partition`, `rejoin`) or a module `reset`. The others need
    /// the module's software to cooperate (`stall`, `step`, `babble`) or its power held
    /// off (`dies`, `returns`), which the emulated MCU does not model: refused.
    pub fn schedule(&mut self, f: Fault) -> Result<(), String> {
        match f.kind {
            FaultKind::Stuck
            | FaultKind::Release
            | FaultKind::Partition
            | FaultKind::Rejoin
            | FaultKind::Reset => {}
            other => {
                return Err(format!(
                    "fault {other:?} is not modelled under emulation (stuck, release, partition, rejoin, reset are)"
                ))
            }
        }
        if f.module >= self.mcus.len() {
            return Err(format!("no module {}", f.module));
        }
        let at = self.faults.partition_point(|g| g.at <= f.at);
        self.faults.insert(at, f);
        Ok(())
    }

    /// Resets MCU `node` (power cycle or NRST) while the bus runs: the MCU and its
    /// controller back to power-on values. A frame it was sending completes on the wire
    /// (rtcan-sim's power-loss rule), but its mailbox is gone.
    pub fn reset_node(&mut self, node: usize) -> Result<(), String> {
        match self.mcus.get_mut(node) {
            Some(m) => m.reset().map_err(|e| format!("{e:?}"))?,
            None => return Err(format!("no node {node}")),
        }
        self.sync_confinement();
        Ok(())
    }

    /// Current bus time in bits.
    pub fn bit(&self) -> u64 {
        self.mcus.iter().map(|m| m.now()).min().unwrap_or(0) / self.bit_ps
    }

    fn ceil_bit(&self, t: Nanos) -> u64 {
        t.div_ceil(self.bit_ns.max(1))
    }

    /// The sim's TEC, REC and bus-off of every node into its bxCAN (and a controller
    /// reset into the sim's node, when the MCU was reset by itself: watchdog,
    /// SYSRESETREQ).
    fn sync_confinement(&mut self) {
        for (i, m) in self.mcus.iter_mut().enumerate() {
            let Some(given) = self.given.get_mut(i) else {
                continue;
            };
            if m.st.resets != given.1 {
                self.sim.reset_controller(i);
                given.1 = m.st.resets;
            }
            let Some(state) = self.sim.controller(i).map(|c| c.conf.state()) else {
                continue;
            };
            if !m.st.can.bus_confinement || state != given.0 {
                m.st.can.bus_confinement = true;
                m.st.can
                    .set_error_state(state.tec, state.rec, state.bus_off);
                given.0 = state;
            }
        }
    }

    /// Applies the faults due by bit `bit`; returns the bit of the next one.
    fn apply_faults(&mut self, bit: u64) -> Result<Option<u64>, String> {
        let t = bit * self.bit_ns;
        while let Some(f) = self.faults.first().copied() {
            if f.at > t {
                return Ok(Some(self.ceil_bit(f.at)));
            }
            self.faults.remove(0);
            if f.kind == FaultKind::Reset {
                self.reset_node(f.module)?;
            } else {
                rtcan_sim::fault::apply_bus(&mut self.sim, &f);
            }
            self.sync_confinement();
            self.notice_start();
            self.arbitration_point(t)?;
        }
        Ok(None)
    }

    /// On an idle bus with no pending request: runs every MCU up to `LOOK_AHEAD` bits or
    /// its first transmit request, and returns the bit at which the earliest request can
    /// start a frame (nodes that ran past it had no request by then: they do not contend,
    /// and nothing reaches them before that frame ends).
    fn look_ahead(&mut self, bit: u64, horizon: u64) -> Result<u64, String> {
        let horizon = (bit + LOOK_AHEAD).min(horizon);
        let mut first: Option<u64> = None;
        for m in &mut self.mcus {
            m.st.txrq_at = None;
            m.st.stop_on_txrq = true;
            let r = m.run_until(horizon * self.bit_ps);
            m.st.stop_on_txrq = false;
            r?;
            if let Some(t) = m.st.txrq_at {
                first = Some(first.map_or(t, |f| f.min(t)));
            }
        }
        Ok(match first {
            // SOF on the first bit boundary after the request.
            Some(t) => (t / self.bit_ps + 1).clamp(bit + 1, horizon),
            None => horizon,
        })
    }

    /// A frame the sim started since the last look: its transmitter's mailbox is on the
    /// wire (TTCM stamp at SOF), the other offers lost the arbitration (ALST) and are
    /// withdrawn until the next arbitration, where they are offered again.
    fn notice_start(&mut self) {
        let Activity::Busy(w) = self.sim.activity() else {
            return;
        };
        if self.started == Some(w.sof) {
            return;
        }
        self.started = Some(w.sof);
        let sof_bit = w.sof / self.bit_ns.max(1);
        if let Some(m) = self.mcus.get_mut(w.node) {
            m.st.can.tx_started(w.mailbox, sof_bit);
        }
        let losers: Vec<(usize, usize)> = self
            .sim
            .arbitration_offers()
            .iter()
            .filter(|o| o.1 != w.node)
            .map(|o| (o.1, o.2))
            .collect();
        for (n, mb) in losers {
            if let Some(m) = self.mcus.get_mut(n) {
                m.st.can.tx_lost(mb);
            }
            self.sim.set_offer(n, None);
        }
        if let Some(p) = self.publications.as_mut() {
            p.poll(&self.mcus);
        }
    }

    /// Every bxCAN's best pending mailbox to the bus (at an idle bit: the bus starts a
    /// frame and decides its arbitration one bit later).
    fn offer_all(&mut self) -> Result<(), String> {
        for (i, m) in self.mcus.iter().enumerate() {
            let offer = match m.st.can.tx_candidate() {
                Some((mb, raw)) => Some((
                    mb,
                    raw_to_frame(&raw).ok_or(format!(
                        "{}: mailbox {mb} holds a frame that is not an extended data frame (id {:#x}); the bus carries RTCAN frames only",
                        m.name, raw.id
                    ))?,
                )),
                None => None,
            };
            self.sim.set_offer(i, offer);
        }
        if let Activity::Arbitrating { sof } = self.sim.activity() {
            self.sim.run_until(sof + self.bit_ns);
            self.sync_confinement();
            self.notice_start();
        }
        Ok(())
    }

    /// The bus at bit `bit` (every MCU is there): receivers take the frame at its
    /// last-but-one EOF bit, the transmitter completes at its end, the sim's events up to
    /// `bit` run, and on an idle bus the pending mailboxes are offered.
    fn step_bus(&mut self, bit: u64) -> Result<(), String> {
        let t = bit * self.bit_ns;
        if let Activity::Busy(w) = self.sim.activity() {
            if self.received != Some(w.sof) && bit + 1 >= self.ceil_bit(w.end) {
                self.received = Some(w.sof);
                let raw = frame_to_raw(&w.frame);
                let sof_bit = w.sof / self.bit_ns.max(1);
                for (n, m) in self.mcus.iter_mut().enumerate() {
                    if self.sim.takes_frame(n) {
                        m.st.can.receive(&raw, sof_bit);
                    }
                }
            }
        }
        let seen = self.sim.wire.len();
        let was = self.sim.activity();
        self.sim.run_until(t);
        self.sync_confinement();
        if self.sim.wire.len() > seen {
            if let Activity::Busy(w) = was {
                self.frame_ended(&w, bit);
            }
        }
        self.notice_start();
        self.arbitration_point(t)
    }

    /// At global time `t` on a bus free to start a frame (idle after its intermission,
    /// or a start of frame the sim began by itself: a retransmission, a recovery, a
    /// release): offers every pending mailbox.
    fn arbitration_point(&mut self, t: Nanos) -> Result<(), String> {
        let idle_from = match self.sim.activity() {
            Activity::Idle { from } => Some(from),
            Activity::Arbitrating { sof } => Some(sof),
            Activity::Busy(_) => None,
        };
        if self.sim.stuck_node().is_none() && idle_from.is_some_and(|f| f <= t) {
            self.offer_all()?;
        }
        Ok(())
    }

    /// The frame `w` ended at bit `bit`: its transmitter's mailbox completes (sent, or a
    /// transmit error the bxCAN retries unless aborted or NART), and a good frame is
    /// logged. A transmitter reset meanwhile has no such mailbox any more.
    fn frame_ended(&mut self, w: &rtcan_sim::bus::OnWire, bit: u64) {
        let ok = self.sim.wire.last().is_some_and(|r| r.ok && r.sof == w.sof);
        if let Some(m) = self.mcus.get_mut(w.node) {
            if m.st.can.transmitting == Some(w.mailbox) {
                m.st.can.tx_finished(w.mailbox, ok, bit);
            }
        }
        if ok {
            self.log
                .push((w.node, frame_to_raw(&w.frame), w.sof / self.bit_ns.max(1)));
            let meta = self.mcus.get(w.node).map_or((0, None), |m| {
                let p = &m.st.probe;
                (
                    p.txrq_ps.get(w.mailbox).copied().unwrap_or(0),
                    p.boundary_ps.get(w.mailbox).copied().flatten(),
                )
            });
            self.meta.push(meta);
        }
    }

    /// Runs all MCUs and the bus to time `until` (ps).
    pub fn run_until(&mut self, until: u64) -> Result<(), String> {
        let end_bit = until / self.bit_ps;
        let mut bit = self.bit();
        while bit < end_bit {
            let mut limit = end_bit;
            if let Some(f) = self.apply_faults(bit)? {
                limit = limit.min(f.max(bit + 1));
            }
            // The sim's own next event (an idle-bus bus-off recovery, a retransmission).
            if let Some(t) = self.sim.next_event_at() {
                let b = self.ceil_bit(t);
                if b > bit {
                    limit = limit.min(b);
                }
            }
            let step_to = match self.sim.activity() {
                Activity::Busy(w) => {
                    let end = self.ceil_bit(w.end);
                    if self.received == Some(w.sof) {
                        end
                    } else {
                        end.saturating_sub(1)
                    }
                }
                Activity::Arbitrating { sof } => self.ceil_bit(sof),
                // Held dominant: nothing can start before the release.
                Activity::Idle { .. } if self.sim.stuck_node().is_some() => limit,
                Activity::Idle { from } if self.ceil_bit(from) > bit => self.ceil_bit(from),
                // Idle, and the offers at this bit started nothing.
                Activity::Idle { .. } => self.look_ahead(bit, limit)?,
            }
            .clamp(bit + 1, limit.max(bit + 1));
            for m in &mut self.mcus {
                m.run_until(step_to * self.bit_ps)?;
            }
            bit = step_to;
            self.step_bus(bit)?;
        }
        Ok(())
    }
}
