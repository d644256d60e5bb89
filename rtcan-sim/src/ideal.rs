//! Reference (c): non-preemptive EDF with global knowledge over the free windows. One
//! omniscient scheduler sees every released SRT message of every node, knows the exact
//! length of each frame, and at every instant of a free window sends the next frame of
//! the earliest-deadline message that can still make its deadline and whose frame ends
//! before the window does (guard included). No arbitration, no interrupt latency, no
//! clock error, no heartbeats.
//!
//! What it is not: an upper bound. Non-preemptive EDF is not optimal once messages are
//! dropped (it sends the earliest deadline first, even when that message makes a later,
//! larger set miss), and it is greedy within a window (it never idles to let a later
//! release with an earlier deadline go first). A distributed policy that fits frames to
//! window ends and drops hopeless messages early can, and at overload does, deliver
//! more on time (README, `rtcan sim --scenario rtcan-paper --sweep`). It is a
//! centralised reference with perfect information, not something a CAN bus can do.
use std::cmp::Reverse;
use std::collections::BinaryHeap;

use rtcan_core::fragment::{fragment_count, fragment_data};
use rtcan_core::timing::{bits_to_ns, exact_bits, INTERMISSION_BITS};
use rtcan_core::{CanId, Class, Frame, Nanos};

use crate::bus::WireFrame;
use crate::metrics::{Meter, TopicInfo};
use crate::run::Scenario;
use crate::slots::free_windows;
use crate::traffic::{fill_payload, EventStream};

struct Msg {
    node: usize,
    deadline: Nanos,
    frames: Vec<(Frame, Nanos)>,
    next: usize,
}

/// The frames of event `seq` of `t` with their durations (intermission excluded), in
/// the order they are sent, laxity code 1.
fn frames_of(t: &TopicInfo, seq: u32, bitrate: u32, ifs: Nanos) -> Vec<(Frame, Nanos)> {
    let mut payload = vec![0u8; t.size];
    fill_payload(&mut payload, seq, t.node as u8, t.tx);
    (0..fragment_count(t.size))
        .rev()
        .filter_map(|c| {
            let mut data = [0u8; 8];
            let dlc = fragment_data(&payload, c, &mut data);
            let f = Frame::from_parts(CanId::new(1, t.msg_id, c)?, dlc, data)?;
            Some((f, bits_to_ns(exact_bits(&f), bitrate) - ifs))
        })
        .collect()
}

/// Every SRT event of `sc` with `seed`, merged in release order (ties in topic order),
/// as (release, topic index, sequence number).
struct Releases {
    streams: Vec<(usize, EventStream)>,
    heap: BinaryHeap<Reverse<(Nanos, usize, usize)>>,
}

impl Releases {
    fn new(sc: &Scenario, seed: u64) -> Self {
        let mut streams = Vec::new();
        for (ti, t) in sc.topics.iter().enumerate() {
            if t.class != Class::Srt {
                continue;
            }
            let gen = sc
                .gens
                .get(t.node)
                .and_then(|g| g.iter().find(|g| g.tx == t.tx));
            if let Some(g) = gen {
                streams.push((ti, EventStream::new(*g, seed, t.node as u8)));
            }
        }
        let heap = streams
            .iter()
            .enumerate()
            .map(|(k, (ti, s))| Reverse((s.peek(), *ti, k)))
            .collect();
        Releases { streams, heap }
    }

    fn peek(&self) -> Nanos {
        self.heap.peek().map_or(Nanos::MAX, |r| r.0 .0)
    }

    fn pop(&mut self) -> Option<(Nanos, usize, u32)> {
        let Reverse((at, ti, k)) = self.heap.pop()?;
        let (_, s) = self.streams.get_mut(k)?;
        let (seq, t) = s.next()?;
        debug_assert_eq!(t, at);
        if s.peek() != Nanos::MAX {
            self.heap.push(Reverse((s.peek(), ti, k)));
        }
        Some((at, ti, seq))
    }
}

/// Schedules the SRT events of `sc` (regenerated from its generators with `seed`) over
/// its free windows until `end`, feeding the meter the events and the frames as they
/// would be on the wire, and `sink` each frame. Bus time is taken as global time
/// shifted by one slot (the master's start). Memory: the messages released and not
/// finished, bounded by rates and deadlines.
pub fn schedule(
    sc: &Scenario,
    seed: u64,
    end: Nanos,
    meter: &mut Meter,
    mut sink: impl FnMut(&WireFrame),
) {
    let Some(bus) = sc.bus() else {
        return;
    };
    let ifs = bits_to_ns(INTERMISSION_BITS, bus.bitrate);
    let mut rel = Releases::new(sc, seed);
    let windows = free_windows(&bus, sc.masks());
    let hyper = bus.cycle_ns() * sc.masks().len().max(1) as u64;
    let origin = bus.slot_ns;
    let mut active: Vec<Msg> = Vec::new();
    let mut base = 0u64;
    'outer: loop {
        for &(ws, wl) in &windows {
            let w_start = origin + base + ws;
            let w_end = (w_start + wl).saturating_sub(bus.guard_ns);
            if w_start >= end {
                break 'outer;
            }
            meter.expire(w_start);
            let mut t = w_start;
            loop {
                while rel.peek() <= t {
                    let Some((at, ti, seq)) = rel.pop() else {
                        break;
                    };
                    let Some(tp) = sc.topics.get(ti) else {
                        continue;
                    };
                    meter.event(tp.node, tp.tx, seq, at);
                    active.push(Msg {
                        node: tp.node,
                        deadline: at + tp.deadline_ns,
                        frames: frames_of(tp, seq, bus.bitrate, ifs),
                        next: 0,
                    });
                }
                // Drop hopeless messages (remaining exact time cannot make the deadline).
                active.retain(|m| {
                    let rest: Nanos = m.frames.iter().skip(m.next).map(|f| f.1 + ifs).sum();
                    t + rest.saturating_sub(ifs) <= m.deadline
                });
                let pick = active
                    .iter()
                    .enumerate()
                    .filter(|(_, m)| m.frames.get(m.next).is_some_and(|f| t + f.1 <= w_end))
                    .min_by_key(|(_, m)| m.deadline)
                    .map(|(k, _)| k);
                match pick {
                    Some(k) => {
                        let Some(m) = active.get_mut(k) else { break };
                        let Some(&(frame, dur)) = m.frames.get(m.next) else {
                            break;
                        };
                        let w = WireFrame {
                            sof: t,
                            end: t + dur,
                            node: m.node,
                            frame,
                            ok: true,
                            partial: false,
                        };
                        meter.frame(&w);
                        sink(&w);
                        m.next += 1;
                        if m.next == m.frames.len() {
                            active.swap_remove(k);
                        }
                        t += dur + ifs;
                    }
                    None => {
                        let next_rel = rel.peek();
                        if next_rel < w_end {
                            t = t.max(next_rel);
                        } else {
                            break;
                        }
                    }
                }
                if t >= w_end {
                    break;
                }
            }
        }
        base += hyper;
    }
}

/// Bus time the SRT events (regenerated with `seed`) released in `[from, to)` need:
/// exact frame lengths (stuffing on the real bits, laxity code 1) plus intermissions, ns.
pub fn offered_ns(sc: &Scenario, seed: u64, from: Nanos, to: Nanos) -> Nanos {
    let Some(bus) = sc.bus() else { return 0 };
    let ifs = bits_to_ns(INTERMISSION_BITS, bus.bitrate);
    let mut rel = Releases::new(sc, seed);
    let mut total = 0;
    while rel.peek() < to {
        let Some((at, ti, seq)) = rel.pop() else {
            break;
        };
        let Some(t) = sc.topics.get(ti) else { continue };
        if at >= from {
            total += frames_of(t, seq, bus.bitrate, ifs)
                .iter()
                .map(|f| f.1 + ifs)
                .sum::<Nanos>();
        }
    }
    total
}

/// Free-window time per hyperperiod usable by SRT (each window minus the guard), ns,
/// and the hyperperiod, ns.
pub fn window_capacity(sc: &Scenario) -> (Nanos, Nanos) {
    let Some(bus) = sc.bus() else { return (0, 1) };
    let usable = free_windows(&bus, sc.masks())
        .iter()
        .map(|&(_, l)| l.saturating_sub(bus.guard_ns))
        .sum();
    (usable, bus.cycle_ns() * sc.masks().len().max(1) as u64)
}
