//! Figures computed from the wire log alone (so every policy, including the baselines
//! that do not run the engine, is measured the same way): HRT periods and jitter, SRT
//! latency and deadline misses, bus load per class, slot overlaps.
use std::collections::HashMap;

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

/// HRT figures of one message.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HrtStats {
    /// Label (with node).
    pub name: String,
    /// Frames seen.
    pub count: u64,
    /// Occurrences missing between consecutive frames.
    pub misses: u64,
    /// Mean period, ns.
    pub mean_period_ns: f64,
    /// Standard deviation of the period, ns.
    pub std_period_ns: f64,
    /// Smallest and largest (interval − nominal period), ns.
    pub jitter_min_ns: i64,
    /// See `jitter_min_ns`.
    pub jitter_max_ns: i64,
    /// Every (interval − nominal) sample, ns (for the histogram).
    pub jitter_ns: Vec<i64>,
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
    /// Latencies (event → end of last fragment) of delivered messages, ns, sorted.
    pub latencies_ns: Vec<Nanos>,
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
        if self.latencies_ns.is_empty() {
            0.0
        } else {
            self.latencies_ns.iter().sum::<Nanos>() as f64 / self.latencies_ns.len() as f64
        }
    }
    /// Latency percentile (0..=100), ns.
    pub fn percentile_ns(&self, p: f64) -> Nanos {
        let n = self.latencies_ns.len();
        if n == 0 {
            return 0;
        }
        let i = ((p / 100.0) * (n - 1) as f64).round() as usize;
        self.latencies_ns.get(i.min(n - 1)).copied().unwrap_or(0)
    }
    /// Largest latency, ns.
    pub fn max_ns(&self) -> Nanos {
        self.latencies_ns.last().copied().unwrap_or(0)
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

/// Computes the figures. `events[(node, tx)]` are the global event times by sequence
/// number; `bit_ns` the bit time.
pub fn compute(
    wire: &[WireFrame],
    topics: &[TopicInfo],
    events: &HashMap<(usize, u8), Vec<Nanos>>,
    win: Window,
    bit_ns: Nanos,
) -> Figures {
    // (node, message ID) → topic index, looked up twice per frame: a sorted vector
    // (binary search, no hashing). On a duplicate key the last topic wins.
    let mut by_id: Vec<((usize, u16), usize)> = topics
        .iter()
        .enumerate()
        .map(|(i, t)| ((t.node, t.msg_id.0), i))
        .collect();
    by_id.sort_unstable_by_key(|&(k, i)| (k, std::cmp::Reverse(i)));
    by_id.dedup_by_key(|e| e.0);
    let topic_of = |node: usize, msg: u16| {
        by_id
            .binary_search_by_key(&(node, msg), |e| e.0)
            .ok()
            .and_then(|k| by_id.get(k))
            .map(|e| e.1)
    };
    let mut figs = Figures::default();
    let span = win.to.saturating_sub(win.from).max(1) as f64;
    let ifs = Nanos::from(INTERMISSION_BITS) * bit_ns;
    // Per topic: HRT SOFs, SRT completion per sequence number.
    let mut sofs: Vec<Vec<Nanos>> = vec![Vec::new(); topics.len()];
    let mut current: Vec<Option<u32>> = vec![None; topics.len()];
    // Completion time by sequence number; only numbers of recorded events are ever
    // looked up, so the rest are not kept (dense vectors: no hashing per frame).
    let mut done: Vec<Vec<Option<Nanos>>> = topics
        .iter()
        .map(|t| vec![None; events.get(&(t.node, t.tx)).map_or(0, Vec::len)])
        .collect();
    for w in wire {
        let id = w.frame.id();
        // Looked up once per frame (load class and per-topic figures).
        let topic = topic_of(w.node, id.msg_id().0);
        if w.sof >= win.from && w.sof < win.to {
            let occ = (w.end - w.sof + ifs) as f64 / span;
            if !w.ok {
                figs.load.errors += occ;
            } else if id.is_sync() {
                figs.load.sync += occ;
            } else {
                // The topic's class when known (baselines put priorities in the top bits),
                // else the laxity field.
                let class = topic.and_then(|i| topics.get(i)).map(|t| t.class);
                match (class, id.laxity()) {
                    (Some(Class::Hrt), _) | (None, 0) => figs.load.hrt += occ,
                    (Some(Class::Nrt), _) | (None, 63) => figs.load.nrt += occ,
                    _ => figs.load.srt += occ,
                }
            }
        }
        if !w.ok {
            continue;
        }
        let Some(ti) = topic else {
            if !id.is_sync() && id.laxity() != 63 {
                figs.unknown_frames += 1;
            }
            continue;
        };
        let Some(t) = topics.get(ti) else { continue };
        // The fragment field also carries the transfer ID (docs/PROTOCOL.md §7.1).
        let counter = counter_of(t.size, id.fragment());
        match t.class {
            Class::Hrt => {
                if counter + 1 == fragment_count(t.size) && w.sof >= win.from && w.sof < win.to {
                    if let Some(v) = sofs.get_mut(ti) {
                        v.push(w.sof);
                    }
                }
            }
            _ => {
                let (Some(cur), Some(d)) = (current.get_mut(ti), done.get_mut(ti)) else {
                    continue;
                };
                if counter + 1 == fragment_count(t.size) {
                    *cur = Some(payload_seq(w.frame.data()));
                }
                if counter == 0 {
                    if let Some(slot) = cur
                        .take()
                        .and_then(|seq| d.get_mut(usize::try_from(seq).ok()?))
                    {
                        slot.get_or_insert(w.end);
                    }
                }
            }
        }
    }
    // HRT per message.
    for (ti, t) in topics
        .iter()
        .enumerate()
        .filter(|(_, t)| t.class == Class::Hrt)
    {
        let s = sofs.get(ti).map_or(&[][..], Vec::as_slice);
        let nominal = t.period_ns.max(1);
        let intervals: Vec<i64> = s
            .iter()
            .zip(s.iter().skip(1))
            .map(|(a, b)| (b - a) as i64)
            .collect();
        let mut st = HrtStats {
            name: format!("{}@n{}", t.label, t.node),
            count: s.len() as u64,
            ..HrtStats::default()
        };
        if !intervals.is_empty() {
            let n = intervals.len() as f64;
            st.mean_period_ns = intervals.iter().map(|&x| x as f64).sum::<f64>() / n;
            st.std_period_ns = (intervals
                .iter()
                .map(|&x| (x as f64 - st.mean_period_ns).powi(2))
                .sum::<f64>()
                / n)
                .sqrt();
            for &iv in &intervals {
                let k = ((iv as f64) / nominal as f64).round().max(1.0) as i64;
                st.misses += (k - 1) as u64;
                st.jitter_ns.push(iv - k * nominal as i64);
            }
            st.jitter_min_ns = st.jitter_ns.iter().copied().min().unwrap_or(0);
            st.jitter_max_ns = st.jitter_ns.iter().copied().max().unwrap_or(0);
        }
        figs.hrt.push(st);
    }
    // SRT per class label, in first-appearance order.
    let mut classes: Vec<SrtStats> = Vec::new();
    for (ti, t) in topics
        .iter()
        .enumerate()
        .filter(|(_, t)| t.class == Class::Srt)
    {
        let idx = match classes.iter().position(|c| c.name == t.label) {
            Some(i) => i,
            None => {
                classes.push(SrtStats {
                    name: t.label.clone(),
                    ..SrtStats::default()
                });
                classes.len() - 1
            }
        };
        let Some(c) = classes.get_mut(idx) else {
            continue;
        };
        let ev = events.get(&(t.node, t.tx)).map_or(&[][..], Vec::as_slice);
        let d = done.get(ti);
        for (seq, &at) in ev.iter().enumerate() {
            if at < win.from || at + t.deadline_ns >= win.to {
                continue;
            }
            c.count += 1;
            match d.and_then(|d| d.get(seq)).copied().flatten() {
                Some(end) => {
                    let lat = end.saturating_sub(at);
                    c.latencies_ns.push(lat);
                    if lat > t.deadline_ns {
                        c.misses += 1;
                    }
                }
                None => c.misses += 1,
            }
        }
    }
    for c in classes.iter_mut() {
        c.latencies_ns.sort_unstable();
    }
    figs.srt = classes;
    figs
}
