//! Figures computed from what the wire carries (so every policy, including the baselines
//! that do not run the engine, is measured the same way): HRT periods, jitter, late and
//! missed instances; SRT latency and deadline misses; bus load per class.
//!
//! Streaming: a `Meter` is fed events and frames in time order while the run goes on and
//! keeps state bounded by the robot (pending messages, fixed histograms, bounded samples
//! for the plots), not by the length of the run.
use std::collections::VecDeque;

use rtcan_core::fragment::{counter_of, fragment_count};
use rtcan_core::timing::INTERMISSION_BITS;
use rtcan_core::{Class, MsgId, Nanos};

use crate::bus::WireFrame;
use crate::traffic::payload_seq;

/// What the metrics need to know about one transmitted topic.
#[derive(Clone, Debug, PartialEq)]
pub struct TopicInfo {
    /// Transmitting node.
    pub node: usize,
    /// Transmit topic index on that node.
    pub tx: u8,
    /// Message ID on the wire.
    pub msg_id: MsgId,
    /// Class.
    pub class: Class,
    /// Label grouping topics in the report (e.g. "S_A", or the topic name).
    pub label: String,
    /// Payload bytes.
    pub size: usize,
    /// SRT relative deadline, ns.
    pub deadline_ns: Nanos,
    /// HRT nominal period, ns.
    pub period_ns: Nanos,
}

pub use crate::histogram::{LatencyHist, Reservoir, RESERVOIR};

/// HRT figures of one message.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HrtStats {
    /// Label (with node).
    pub name: String,
    /// Frames seen.
    pub count: u64,
    /// Occurrences without a frame: gaps between frames, and silence at the start or
    /// end of the measured interval (a silent message has span / period misses).
    pub misses: u64,
    /// Mean period, ns.
    pub mean_period_ns: f64,
    /// Standard deviation of the period, ns.
    pub std_period_ns: f64,
    /// Smallest and largest (interval − nominal period), ns.
    pub jitter_min_ns: i64,
    /// See `jitter_min_ns`.
    pub jitter_max_ns: i64,
    /// A bounded sample of (interval − nominal) values, ns (for the histogram).
    pub jitter_ns: Vec<i64>,
    /// Instances delivered after their deadline (release + period); `None` when the
    /// releases are not known (payloads without sequence numbers).
    pub late: Option<u64>,
    /// Instances not delivered at all: released and never completed, or never released
    /// (silence, counted from the release times); `None` as for `late`.
    pub missed: Option<u64>,
    /// Worst observed response time (release → end of frame), ns, when known.
    pub max_response_ns: Option<Nanos>,
}

/// SRT figures of one class.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SrtStats {
    /// Class label.
    pub name: String,
    /// Events whose deadline fell inside the measured interval.
    pub count: u64,
    /// Of those, not delivered by their deadline (dropped, refused, late or lost).
    pub misses: u64,
    /// Latencies (event → end of last fragment) of delivered messages.
    pub latency: LatencyHist,
}

impl SrtStats {
    /// Miss ratio.
    pub fn miss_ratio(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            self.misses as f64 / self.count as f64
        }
    }
    /// Mean latency of delivered messages, ns.
    pub fn mean_ns(&self) -> f64 {
        self.latency.mean()
    }
    /// Latency percentile (0..=100), ns.
    pub fn percentile_ns(&self, p: f64) -> Nanos {
        self.latency.percentile(p)
    }
    /// Largest latency, ns.
    pub fn max_ns(&self) -> Nanos {
        self.latency.max
    }
    /// Records a delivered event's latency against `deadline_ns`.
    pub fn delivered(&mut self, lat: Nanos, deadline_ns: Nanos) {
        self.count += 1;
        self.latency.push(lat);
        if lat > deadline_ns {
            self.misses += 1;
        }
    }
    /// Records an event never delivered.
    pub fn lost(&mut self) {
        self.count += 1;
        self.misses += 1;
    }
}

/// Bus occupancy per class as a fraction of the measured interval.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Load {
    /// Sync frames.
    pub sync: f64,
    /// HRT frames.
    pub hrt: f64,
    /// SRT frames.
    pub srt: f64,
    /// NRT frames (heartbeats included).
    pub nrt: f64,
    /// Error frames.
    pub errors: f64,
}

/// Everything measured on one run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Figures {
    /// Per HRT message.
    pub hrt: Vec<HrtStats>,
    /// Per SRT class.
    pub srt: Vec<SrtStats>,
    /// Bus load.
    pub load: Load,
    /// Frames on the wire not attributed to any topic (sync and heartbeats excluded).
    pub unknown_frames: u64,
}

/// Measurement window: frames and events in `[from, to)`; SRT events count when their
/// deadline is before `to`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    /// Start, global ns.
    pub from: Nanos,
    /// End, global ns.
    pub to: Nanos,
}

/// How long after its deadline a message may still complete on the wire (a frame in
/// transmission or retransmission at the deadline); after that it is counted lost and
/// forgotten, which bounds the pending state.
pub const GRACE_NS: Nanos = 1_000_000_000;

/// Occurrences of period `p` that fit in a silence of length `gap` before the first
/// (after the last) frame: a frame up to half a period late still counts as present.
fn silent_periods(gap: Nanos, p: Nanos) -> u64 {
    ((gap as f64 / p.max(1) as f64) - 0.5).floor().max(0.0) as u64
}

/// Gap and jitter statistics of a periodic stream of times.
#[derive(Clone, Debug, Default, PartialEq)]
struct Periodic {
    first: Option<Nanos>,
    last: Option<Nanos>,
    count: u64,
    intervals: u64,
    sum: f64,
    sum_sq: f64,
    misses: u64,
    jmin: i64,
    jmax: i64,
    jitter: Reservoir<i64>,
}

impl Periodic {
    fn push(&mut self, t: Nanos, nominal: Nanos) {
        self.count += 1;
        if let Some(prev) = self.last {
            let iv = t.saturating_sub(prev) as i64;
            let k = ((iv as f64) / nominal.max(1) as f64).round().max(1.0) as i64;
            self.misses += (k - 1) as u64;
            let j = iv - k * nominal as i64;
            if self.intervals == 0 {
                (self.jmin, self.jmax) = (j, j);
            } else {
                self.jmin = self.jmin.min(j);
                self.jmax = self.jmax.max(j);
            }
            self.intervals += 1;
            self.sum += iv as f64;
            self.sum_sq += (iv as f64) * (iv as f64);
            self.jitter.push(j);
        } else {
            self.first = Some(t);
        }
        self.last = Some(t);
    }

    /// Misses including silence at both ends of `[from, to)`.
    fn misses(&self, from: Nanos, to: Nanos, p: Nanos) -> u64 {
        match (self.first, self.last) {
            (Some(f), Some(l)) => {
                self.misses
                    + silent_periods(f.saturating_sub(from), p)
                    + silent_periods(to.saturating_sub(l), p)
            }
            _ => to.saturating_sub(from) / p.max(1),
        }
    }
}

/// Per HRT topic.
#[derive(Clone, Debug, Default)]
struct HrtAcc {
    frames: Periodic,
    /// Releases with their deadline inside the window, for late/missed.
    releases: Periodic,
    /// Released, not completed: (seq, release time).
    pending: VecDeque<(u32, Nanos)>,
    on_time: u64,
    late: u64,
    lost: u64,
    max_response: Nanos,
    known: bool,
    current: Option<u32>,
}

/// Per SRT topic.
#[derive(Clone, Debug, Default)]
struct SrtAcc {
    /// Events not yet completed: (seq, time), in sequence order.
    pending: VecDeque<(u32, Nanos)>,
    /// Sequence number of the transfer whose first fragment was seen last.
    current: Option<u32>,
    class: usize,
}

/// Streaming measurement of one run.
pub struct Meter {
    topics: Vec<TopicInfo>,
    /// Topic index by node and transmit index.
    by_tx: Vec<Vec<Option<usize>>>,
    by_id: Vec<((usize, u16), usize)>,
    win: Window,
    ifs: Nanos,
    hrt: Vec<HrtAcc>,
    srt: Vec<SrtAcc>,
    classes: Vec<SrtStats>,
    load: Load,
    unknown_frames: u64,
}

impl Meter {
    /// A meter of `topics` over `win`; `bit_ns` is the bit time.
    pub fn new(topics: &[TopicInfo], win: Window, bit_ns: Nanos) -> Self {
        // (node, message ID) → topic index, looked up per frame: a sorted vector (binary
        // search, no hashing). On a duplicate key the last topic wins.
        let mut by_id: Vec<((usize, u16), usize)> = topics
            .iter()
            .enumerate()
            .map(|(i, t)| ((t.node, t.msg_id.0), i))
            .collect();
        by_id.sort_unstable_by_key(|&(k, i)| (k, std::cmp::Reverse(i)));
        by_id.dedup_by_key(|e| e.0);
        let mut classes: Vec<SrtStats> = Vec::new();
        let srt = topics
            .iter()
            .map(|t| {
                let class = if t.class == Class::Srt {
                    match classes.iter().position(|c| c.name == t.label) {
                        Some(i) => i,
                        None => {
                            classes.push(SrtStats {
                                name: t.label.clone(),
                                ..SrtStats::default()
                            });
                            classes.len() - 1
                        }
                    }
                } else {
                    0
                };
                SrtAcc {
                    class,
                    ..SrtAcc::default()
                }
            })
            .collect();
        let mut by_tx: Vec<Vec<Option<usize>>> = Vec::new();
        for (i, t) in topics.iter().enumerate() {
            if by_tx.len() <= t.node {
                by_tx.resize(t.node + 1, Vec::new());
            }
            if let Some(v) = by_tx.get_mut(t.node) {
                if v.len() <= usize::from(t.tx) {
                    v.resize(usize::from(t.tx) + 1, None);
                }
                if let Some(slot) = v.get_mut(usize::from(t.tx)) {
                    *slot = Some(i);
                }
            }
        }
        Meter {
            topics: topics.to_vec(),
            by_tx,
            by_id,
            win,
            ifs: Nanos::from(INTERMISSION_BITS) * bit_ns,
            hrt: vec![HrtAcc::default(); topics.len()],
            srt,
            classes,
            load: Load::default(),
            unknown_frames: 0,
        }
    }

    fn topic_of(&self, node: usize, msg: u16) -> Option<usize> {
        self.by_id
            .binary_search_by_key(&(node, msg), |e| e.0)
            .ok()
            .and_then(|k| self.by_id.get(k))
            .map(|e| e.1)
    }

    fn index(&self, node: usize, tx: u8) -> Option<usize> {
        self.by_tx
            .get(node)?
            .get(usize::from(tx))
            .copied()
            .flatten()
    }

    /// SRT event `seq` of (`node`, `tx`) at global time `at` (events of one topic in
    /// sequence order, before the frames that carry them).
    pub fn event(&mut self, node: usize, tx: u8, seq: u32, at: Nanos) {
        if let Some(a) = self.index(node, tx).and_then(|i| self.srt.get_mut(i)) {
            a.pending.push_back((seq, at));
        }
    }

    /// HRT sample `seq` of (`node`, `tx`) released at global time `at`.
    pub fn release(&mut self, node: usize, tx: u8, seq: u32, at: Nanos) {
        let Some(i) = self.index(node, tx) else {
            return;
        };
        let period = self.topics.get(i).map_or(0, |t| t.period_ns);
        let win = self.win;
        if let Some(a) = self.hrt.get_mut(i) {
            a.known = true;
            if at >= win.from && at + period < win.to {
                a.releases.push(at, period);
                a.pending.push_back((seq, at));
            }
        }
    }

    /// Forgets what can no longer complete by `now` (global): counted as lost.
    pub fn expire(&mut self, now: Nanos) {
        let win = self.win;
        for (i, t) in self.topics.iter().enumerate() {
            match t.class {
                Class::Hrt => {
                    let Some(a) = self.hrt.get_mut(i) else {
                        continue;
                    };
                    while a
                        .pending
                        .front()
                        .is_some_and(|&(_, at)| at + t.period_ns + GRACE_NS < now)
                    {
                        a.pending.pop_front();
                        a.lost += 1;
                    }
                }
                _ => {
                    let Some(a) = self.srt.get_mut(i) else {
                        continue;
                    };
                    while let Some(&(_, at)) = a.pending.front() {
                        if at + t.deadline_ns + GRACE_NS >= now {
                            break;
                        }
                        a.pending.pop_front();
                        if at >= win.from && at + t.deadline_ns < win.to {
                            if let Some(c) = self.classes.get_mut(a.class) {
                                c.lost();
                            }
                        }
                    }
                }
            }
        }
    }

    /// One frame that ended on the wire (or was destroyed, `!ok`).
    pub fn frame(&mut self, w: &WireFrame) {
        let win = self.win;
        let id = w.frame.id();
        let topic = self.topic_of(w.node, id.msg_id().0);
        if w.sof >= win.from && w.sof < win.to {
            let span = win.to.saturating_sub(win.from).max(1) as f64;
            let occ = (w.end - w.sof + self.ifs) as f64 / span;
            if !w.ok {
                self.load.errors += occ;
            } else if id.is_sync() {
                self.load.sync += occ;
            } else {
                // The topic's class when known (baselines put priorities in the top
                // bits), else the laxity field.
                let class = topic.and_then(|i| self.topics.get(i)).map(|t| t.class);
                match (class, id.laxity()) {
                    (Some(Class::Hrt), _) | (None, 0) => self.load.hrt += occ,
                    (Some(Class::Nrt), _) | (None, 63) => self.load.nrt += occ,
                    _ => self.load.srt += occ,
                }
            }
        }
        if !w.ok {
            return;
        }
        let Some(ti) = topic else {
            if !id.is_sync() && id.laxity() != 63 {
                self.unknown_frames += 1;
            }
            return;
        };
        let Some(t) = self.topics.get(ti) else { return };
        // The fragment field carries the transfer ID above the counter (PROTOCOL §7.1).
        let counter = counter_of(t.size, id.fragment());
        let last = counter + 1 == fragment_count(t.size);
        match t.class {
            Class::Hrt => {
                let period = t.period_ns;
                let Some(a) = self.hrt.get_mut(ti) else {
                    return;
                };
                // The first fragment sent (the highest) marks the period and carries the
                // sequence number; fragment 0 completes the instance.
                if last {
                    if w.sof >= win.from && w.sof < win.to {
                        a.frames.push(w.sof, period);
                    }
                    a.current = Some(payload_seq(w.frame.data()));
                }
                if counter == 0 && a.known {
                    let Some(seq) = a.current.take() else { return };
                    if let Ok(k) = a.pending.binary_search_by_key(&seq, |e| e.0) {
                        if let Some((_, at)) = a.pending.remove(k) {
                            let resp = w.end.saturating_sub(at);
                            a.max_response = a.max_response.max(resp);
                            if resp > period {
                                a.late += 1;
                            } else {
                                a.on_time += 1;
                            }
                        }
                    }
                }
            }
            _ => {
                let deadline = t.deadline_ns;
                let Some(a) = self.srt.get_mut(ti) else {
                    return;
                };
                // Fragments go out highest first: the first one carries the sequence
                // number, fragment 0 completes the transfer.
                if last {
                    a.current = Some(payload_seq(w.frame.data()));
                }
                if counter == 0 {
                    let Some(seq) = a.current.take() else { return };
                    let Ok(k) = a.pending.binary_search_by_key(&seq, |e| e.0) else {
                        return;
                    };
                    let Some((_, at)) = a.pending.remove(k) else {
                        return;
                    };
                    if at >= win.from && at + deadline < win.to {
                        if let Some(c) = self.classes.get_mut(a.class) {
                            c.delivered(w.end.saturating_sub(at), deadline);
                        }
                    }
                }
            }
        }
    }

    /// The figures; what is still pending counts as lost.
    pub fn finish(mut self) -> Figures {
        self.expire(Nanos::MAX);
        let win = self.win;
        let mut figs = Figures {
            load: self.load,
            unknown_frames: self.unknown_frames,
            ..Figures::default()
        };
        for (t, a) in self.topics.iter().zip(&self.hrt) {
            if t.class != Class::Hrt {
                continue;
            }
            let p = t.period_ns.max(1);
            let f = &a.frames;
            let mut st = HrtStats {
                name: format!("{}@n{}", t.label, t.node),
                count: f.count,
                misses: f.misses(win.from, win.to, p),
                jitter_min_ns: f.jmin,
                jitter_max_ns: f.jmax,
                jitter_ns: f.jitter.values.clone(),
                ..HrtStats::default()
            };
            if f.intervals > 0 {
                let n = f.intervals as f64;
                st.mean_period_ns = f.sum / n;
                st.std_period_ns = (f.sum_sq / n - st.mean_period_ns.powi(2)).max(0.0).sqrt();
            }
            if a.known {
                // Instances that should have been released but were not (silence), from
                // the release times over the part of the window deadlines fit in.
                let unreleased = a.releases.misses(win.from, win.to.saturating_sub(p), p);
                st.late = Some(a.late);
                st.missed = Some(a.lost + unreleased);
                st.max_response_ns = Some(a.max_response);
            }
            figs.hrt.push(st);
        }
        figs.srt = self.classes;
        figs
    }
}

/// The figures of a recorded run at once: `events[(node, tx)]` are SRT event times by
/// sequence number (a convenience over `Meter` for tests and small logs).
pub fn compute(
    wire: &[WireFrame],
    topics: &[TopicInfo],
    events: &std::collections::HashMap<(usize, u8), Vec<Nanos>>,
    win: Window,
    bit_ns: Nanos,
) -> Figures {
    let mut m = Meter::new(topics, win, bit_ns);
    let mut keys: Vec<&(usize, u8)> = events.keys().collect();
    keys.sort_unstable();
    for k in keys {
        for (seq, &at) in events.get(k).into_iter().flatten().enumerate() {
            m.event(k.0, k.1, seq as u32, at);
        }
    }
    for w in wire {
        m.frame(w);
    }
    m.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 9: a late-but-delivered frame was a "miss" (gap-based); by deadline it is
    /// late, and only an instance never delivered is missed.
    #[test]
    fn late_and_missed_are_told_apart_by_deadline() {
        use crate::traffic::fill_payload;
        use rtcan_core::{CanId, Frame};
        let ms = 1_000_000;
        let topic = TopicInfo {
            node: 0,
            tx: 0,
            msg_id: MsgId(0x140),
            class: Class::Hrt,
            label: "H".into(),
            size: 8,
            deadline_ns: 0,
            period_ns: ms,
        };
        let mut m = Meter::new(
            &[topic],
            Window {
                from: 0,
                to: 10 * ms,
            },
            1_000,
        );
        let frame = |seq: u32, end: Nanos| {
            let mut d = [0u8; 8];
            fill_payload(&mut d, seq, 0, 0);
            WireFrame {
                sof: end - 130_000,
                end,
                node: 0,
                frame: Frame::from_parts(CanId::new(0, MsgId(0x140), 0).unwrap(), 8, d).unwrap(),
                ok: true,
                partial: false,
            }
        };
        // Releases every ms from 0 to 8 ms (deadline inside the window); instance 3 is
        // delivered 0.8 ms after its deadline, instance 6 never.
        for k in 0..9u32 {
            m.release(0, 0, k, Nanos::from(k) * ms);
        }
        for k in 0..9u32 {
            let end = Nanos::from(k) * ms + 200_000;
            match k {
                3 => m.frame(&frame(k, end + ms + 600_000)),
                6 => {}
                _ => m.frame(&frame(k, end)),
            }
        }
        let f = m.finish();
        let h = f.hrt.first().unwrap();
        assert_eq!(h.late, Some(1));
        assert_eq!(h.missed, Some(1));
        assert_eq!(h.max_response_ns, Some(ms + 800_000));
        // The gap count sees instance 3 in the wrong period and 6 absent.
        assert!(h.misses >= 1);
    }

    #[test]
    fn silence_at_either_end_and_a_dead_bus_count_as_misses() {
        let mut p = Periodic::default();
        // Period 1 ms, window [0, 10 ms): frames only at 3..=6 ms.
        for k in 3..=6 {
            p.push(k * 1_000_000, 1_000_000);
        }
        // Missing: 1, 2 (start; 0 is at the very edge, half a period of tolerance) and
        // 7, 8, 9 (end).
        assert_eq!(p.misses(0, 10_000_000, 1_000_000), 5);
        let dead = Periodic::default();
        assert_eq!(dead.misses(0, 10_000_000, 1_000_000), 10);
        // A frame half a period late at the start is not a miss.
        let mut q = Periodic::default();
        q.push(1_400_000, 1_000_000);
        assert_eq!(q.misses(0, 2_000_000, 1_000_000), 0);
    }
}
