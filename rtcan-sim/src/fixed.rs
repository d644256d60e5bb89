//! Baseline (d): plain CAN with fixed priorities and no TDMA. Each node sends its HRT
//! topics from a free-running local timer and its SRT events as they come, with
//! identifiers ordered rate-monotonic for HRT (above everything) and
//! deadline-monotonic for SRT, messages fragmented as RTCAN does. A message still
//! queued at its deadline (HRT: the next period) is dropped. This is what the bus does
//! without temporal isolation; it shares no scheduling code with the engine.
//!
//! The driver is the one a competent CAN user writes for three mailboxes: the three
//! highest-priority frames are the ones loaded; when a frame of higher priority than a
//! loaded one is queued and no mailbox is free, the lowest-priority loaded mailbox is
//! aborted (a frame already on the wire completes) and reloaded later. Without this a
//! high-priority frame waits behind three low-priority ones (priority inversion), which
//! is a driver defect, not a property of fixed-priority CAN; with it the response
//! times obey the classical analysis (Davis, Burns, Bril, Lukkien 2007; `rta`).
use rtcan_core::driver::{Mailbox, Token, TxResult, MAILBOXES};
use rtcan_core::fragment::{fragment_count, fragment_data};
use rtcan_core::timing::worst_case_ns;
use rtcan_core::{CanId, Class, Controller, Frame, Host, Nanos};

use crate::bus::Module;
use crate::controller::SimController;
use crate::rta::Stream;
use crate::run::{Scenario, SimConfig};
use crate::tables::OwnedTables;
use crate::traffic::TrafficHost;

struct Msg {
    prio: u8,
    tx: u8,
    token: Token,
    next_fragment: u8,
    deadline: Nanos,
    loaded: Option<usize>,
}

impl Msg {
    /// Arbitration key of its next frame (lower wins): priority, message ID, fragment.
    fn key(&self, msg_id: u16) -> u32 {
        CanId::new(self.prio, rtcan_core::MsgId(msg_id), self.next_fragment)
            .map_or(u32::MAX, CanId::raw)
    }
}

/// Identifier priority of a topic (lower wins): HRT rate monotonic, 1 ms → 1, 10 ms →
/// 10, capped below every SRT priority (no period: 1); SRT deadline monotonic above 20;
/// NRT last.
pub fn priority(class: Class, hrt_period_ns: Option<Nanos>, deadline_ns: Nanos) -> u8 {
    match class {
        Class::Hrt => hrt_period_ns.map_or(1, |p| (p / 1_000_000).clamp(1, 20) as u8),
        Class::Srt => (21 + deadline_ns / 1_000_000).min(62) as u8,
        Class::Nrt => 63,
    }
}

/// The frame streams of `sc` under this baseline, for the response-time analysis
/// (`rta`): single-frame HRT topics with their worst-case frame time, minimum
/// inter-arrival (the period shortened by the largest clock drift) and release jitter
/// (timer interrupt, plus the abort report when a mailbox must be freed: two interrupt
/// latencies); every other frame as a possible blocker (8 data bytes). Returns the
/// streams and, per stream, the index in `sc.topics` of the HRT topic it analyses.
pub fn rta_streams(sc: &Scenario, cfg: &SimConfig) -> (Vec<Stream>, Vec<Option<usize>>) {
    let bitrate = sc.bus().map_or(1_000_000, |b| b.bitrate);
    let drift = 1.0 - cfg.drift_ppm.abs() * 1e-6;
    let mut streams = Vec::new();
    let mut which = Vec::new();
    for (i, t) in sc.topics.iter().enumerate() {
        let period = (t.class == Class::Hrt && t.period_ns > 0).then_some(t.period_ns);
        let prio = priority(t.class, period, t.deadline_ns);
        let single = fragment_count(t.size) == 1;
        let key = CanId::new(prio, t.msg_id, 0).map_or(u32::MAX, CanId::raw);
        let dlc = if single { t.size.min(8) as u8 } else { 8 };
        let (t_ns, j_ns, analysed) = match period {
            Some(p) if single => ((p as f64 * drift) as Nanos, 2 * cfg.irq_latency_ns, true),
            // Not analysed: they block (lower priority than every HRT frame) and never
            // interfere with an HRT frame.
            _ => (Nanos::MAX, 0, false),
        };
        streams.push(Stream {
            name: format!("{}@n{}", t.label, t.node),
            key,
            c_ns: worst_case_ns(dlc, bitrate),
            t_ns,
            j_ns,
        });
        which.push(analysed.then_some(i));
    }
    (streams, which)
}

/// A node of the fixed-priority baseline.
pub struct FixedNode<'t> {
    tables: &'t OwnedTables,
    /// Traffic generator (the same streams as the engine runs).
    pub host: TrafficHost,
    hrt_next: Vec<Option<(Nanos, Nanos)>>,
    queue: Vec<Msg>,
    mailboxes: [bool; MAILBOXES],
    /// Abort requested on the mailbox, result not yet reported.
    aborting: [bool; MAILBOXES],
    /// Messages dropped at their deadline, HRT and SRT.
    pub dropped: u64,
    /// Mailboxes aborted for a higher-priority frame.
    pub aborts: u64,
}

impl<'t> FixedNode<'t> {
    /// Node on `tables`; HRT periods (ns) per transmit topic and phases from the calendar.
    pub fn new(tables: &'t OwnedTables, host: TrafficHost, hrt_period_ns: &[Nanos]) -> Self {
        let slot = tables.bus.slot_ns;
        let hrt_next = tables
            .tx
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let period = hrt_period_ns.get(i).copied().unwrap_or(0);
                (t.class == Class::Hrt && period > 0).then(|| {
                    let phase = tables
                        .calendar
                        .iter()
                        .find(|e| usize::from(e.tx) == i)
                        .map_or(0, |e| u64::from(e.slot));
                    (slot + phase * slot, period)
                })
            })
            .collect();
        FixedNode {
            tables,
            host,
            hrt_next,
            queue: Vec::new(),
            mailboxes: [false; MAILBOXES],
            aborting: [false; MAILBOXES],
            dropped: 0,
            aborts: 0,
        }
    }

    fn prio(&self, tx: u8) -> u8 {
        let Some(t) = self.tables.tx.get(usize::from(tx)) else {
            return 63;
        };
        let period = self
            .hrt_next
            .get(usize::from(tx))
            .copied()
            .flatten()
            .map(|(_, p)| p);
        priority(t.class, period, t.deadline_ns)
    }

    fn enqueue(&mut self, tx: u8, token: Token, deadline: Nanos) {
        let payload = self.host.payload(token);
        let next_fragment = fragment_count(payload.len()).saturating_sub(1);
        let prio = self.prio(tx);
        self.queue.push(Msg {
            prio,
            tx,
            token,
            next_fragment,
            deadline,
            loaded: None,
        });
    }

    fn fill(&mut self, now: Nanos, can: &mut SimController) {
        // Drop what can no longer be on time and is not on its way.
        let mut i = 0;
        while i < self.queue.len() {
            let expired = self
                .queue
                .get(i)
                .is_some_and(|m| m.loaded.is_none() && m.deadline <= now);
            if expired {
                let m = self.queue.swap_remove(i);
                self.dropped += 1;
                self.host
                    .tx_done(m.tx, Some(m.token), rtcan_core::TxOutcome::DeadlineMissed);
            } else {
                i += 1;
            }
        }
        while let Some(free) = self.mailboxes.iter().position(|b| !b) {
            let best = self
                .queue
                .iter()
                .enumerate()
                .filter(|(_, m)| m.loaded.is_none())
                .min_by_key(|(_, m)| (m.prio, m.deadline))
                .map(|(i, _)| i);
            let Some(bi) = best else { break };
            let Some(m) = self.queue.get_mut(bi) else {
                break;
            };
            let Some(topic) = self.tables.tx.get(usize::from(m.tx)) else {
                break;
            };
            let mut data = [0u8; 8];
            let dlc = fragment_data(self.host.payload(m.token), m.next_fragment, &mut data);
            let (Some(id), true) = (CanId::new(m.prio, topic.msg_id, m.next_fragment), true) else {
                break;
            };
            let Some(frame) = Frame::from_parts(id, dlc, data) else {
                break;
            };
            m.loaded = Some(free);
            if let Some(b) = self.mailboxes.get_mut(free) {
                *b = true;
            }
            can.load(Mailbox(free as u8), &frame);
        }
        self.preempt(can);
    }

    fn msg_id(&self, tx: u8) -> u16 {
        self.tables
            .tx
            .get(usize::from(tx))
            .map_or(u16::MAX, |t| t.msg_id.0)
    }

    /// Every mailbox free and the best waiting frame still outranked by a loaded one:
    /// aborts the lowest-priority loaded mailbox (one abort at a time per waiting frame).
    fn preempt(&mut self, can: &mut SimController) {
        if self.mailboxes.iter().any(|b| !b) {
            return;
        }
        let pending_aborts = self.aborting.iter().filter(|a| **a).count();
        let mut waiting: Vec<u32> = self
            .queue
            .iter()
            .filter(|m| m.loaded.is_none())
            .map(|m| m.key(self.msg_id(m.tx)))
            .collect();
        waiting.sort_unstable();
        // Waiting frames that an abort already requested will make room for.
        for &best in waiting.iter().skip(pending_aborts) {
            let worst = self
                .queue
                .iter()
                .filter_map(|m| m.loaded.map(|mb| (m.key(self.msg_id(m.tx)), mb)))
                .filter(|&(_, mb)| !self.aborting.get(mb).copied().unwrap_or(true))
                .max();
            match worst {
                Some((key, mb)) if key > best => {
                    if let Some(a) = self.aborting.get_mut(mb) {
                        *a = true;
                    }
                    self.aborts += 1;
                    can.abort(Mailbox(mb as u8));
                }
                _ => break,
            }
        }
    }

    fn next(&self) -> Option<Nanos> {
        let h = self.hrt_next.iter().flatten().map(|(t, _)| *t).min();
        match (h, self.host.next_local()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

impl Module for FixedNode<'_> {
    fn start(&mut self, _now: Nanos, _can: &mut SimController) -> Option<Nanos> {
        self.next()
    }

    fn wake(&mut self, now: Nanos, can: &mut SimController) -> Option<Nanos> {
        for tx in 0..self.hrt_next.len() {
            let Some(Some((due, period))) = self.hrt_next.get(tx).copied() else {
                continue;
            };
            if due <= now {
                if let Some(slot) = self.hrt_next.get_mut(tx) {
                    *slot = Some((due + period, period));
                }
                // The sample is released now (stamped with its due time).
                self.host.now_local = due;
                if let Some(token) = self.host.hrt_sample(tx as u8) {
                    self.enqueue(tx as u8, token, due + period);
                }
            }
        }
        while let Some((tx, token)) = self.host.take_due(now) {
            let d = self
                .tables
                .tx
                .get(usize::from(tx))
                .map_or(0, |t| t.deadline_ns);
            self.enqueue(tx, token, now + d);
        }
        self.fill(now, can);
        self.next()
    }

    fn rx(
        &mut self,
        _f: &Frame,
        _sof: Nanos,
        _now: Nanos,
        _can: &mut SimController,
    ) -> Option<Nanos> {
        self.next()
    }

    fn tx_done(
        &mut self,
        mailbox: Mailbox,
        result: TxResult,
        now: Nanos,
        can: &mut SimController,
    ) -> Option<Nanos> {
        let mb = usize::from(mailbox.0);
        if let Some(b) = self.mailboxes.get_mut(mb) {
            *b = false;
        }
        if let Some(a) = self.aborting.get_mut(mb) {
            *a = false;
        }
        if let Some(i) = self.queue.iter().position(|m| m.loaded == Some(mb)) {
            let finished = match self.queue.get_mut(i) {
                Some(m) => {
                    m.loaded = None;
                    if result == TxResult::Sent {
                        if m.next_fragment == 0 {
                            true
                        } else {
                            m.next_fragment -= 1;
                            false
                        }
                    } else {
                        false
                    }
                }
                None => false,
            };
            if finished {
                let m = self.queue.swap_remove(i);
                self.host
                    .tx_done(m.tx, Some(m.token), rtcan_core::TxOutcome::Sent);
            }
        }
        self.fill(now, can);
        self.next()
    }

    fn rx_overrun(&mut self, _now: Nanos) {}
}
