//! Bound (c): non-preemptive EDF with global knowledge over the free windows. One
//! omniscient scheduler sees every released SRT message of every node, knows the exact
//! length of each frame, and at every instant of a free window sends the next frame of
//! the earliest-deadline message that can still make its deadline and whose frame ends
//! before the window does (guard included). No arbitration, no interrupt latency, no
//! clock error, no heartbeats: it is an upper bound for any distributed policy on the
//! same windows, not something a CAN bus can do.
use rtcan_core::fragment::{fragment_count, fragment_data};
use rtcan_core::timing::{bits_to_ns, exact_bits, INTERMISSION_BITS};
use rtcan_core::{CanId, Class, Frame, Nanos};

use crate::bus::WireFrame;
use crate::run::Scenario;
use crate::slots::free_windows;
use crate::traffic::fill_payload;

struct Msg {
    node: usize,
    release: Nanos,
    deadline: Nanos,
    frames: Vec<(Frame, Nanos)>,
    next: usize,
}

/// Schedules the SRT `events` ((node, tx) → global times by sequence number) of `sc`
/// over its free windows until `end`; returns the frames as they would be on the wire.
/// Bus time is taken as global time shifted by one slot (the master's start).
pub fn schedule(
    sc: &Scenario,
    events: &std::collections::HashMap<(usize, u8), Vec<Nanos>>,
    end: Nanos,
) -> Vec<WireFrame> {
    let Some(bus) = sc.bus() else {
        return Vec::new();
    };
    let ifs = bits_to_ns(INTERMISSION_BITS, bus.bitrate);
    let mut msgs: Vec<Msg> = Vec::new();
    for t in sc.topics.iter().filter(|t| t.class == Class::Srt) {
        let Some(times) = events.get(&(t.node, t.tx)) else {
            continue;
        };
        for (seq, &at) in times.iter().enumerate() {
            let mut payload = vec![0u8; t.size];
            fill_payload(&mut payload, seq as u32, t.node as u8, t.tx);
            let n = fragment_count(t.size);
            let frames = (0..n)
                .rev()
                .filter_map(|c| {
                    let mut data = [0u8; 8];
                    let dlc = fragment_data(&payload, c, &mut data);
                    let f = Frame::from_parts(CanId::new(1, t.msg_id, c)?, dlc, data)?;
                    Some((f, bits_to_ns(exact_bits(&f), bus.bitrate) - ifs))
                })
                .collect();
            msgs.push(Msg {
                node: t.node,
                release: at,
                deadline: at + t.deadline_ns,
                frames,
                next: 0,
            });
        }
    }
    msgs.sort_by_key(|m| m.release);
    let windows = free_windows(&bus, sc.masks());
    let hyper = bus.cycle_ns() * sc.masks().len().max(1) as u64;
    let origin = bus.slot_ns;
    let mut out = Vec::new();
    let mut released = 0usize;
    let mut active: Vec<usize> = Vec::new();
    let mut base = 0u64;
    'outer: loop {
        for &(ws, wl) in &windows {
            let w_start = origin + base + ws;
            let w_end = (w_start + wl).saturating_sub(bus.guard_ns);
            if w_start >= end {
                break 'outer;
            }
            let mut t = w_start;
            loop {
                while msgs.get(released).is_some_and(|m| m.release <= t) {
                    active.push(released);
                    released += 1;
                }
                // Drop hopeless messages (remaining exact time cannot make the deadline).
                active.retain(|&i| {
                    msgs.get(i).is_some_and(|m| {
                        let rest: Nanos = m.frames.iter().skip(m.next).map(|f| f.1 + ifs).sum();
                        t + rest.saturating_sub(ifs) <= m.deadline
                    })
                });
                let pick = active
                    .iter()
                    .enumerate()
                    .filter(|(_, &i)| {
                        msgs.get(i)
                            .and_then(|m| m.frames.get(m.next))
                            .is_some_and(|f| t + f.1 <= w_end)
                    })
                    .min_by_key(|(_, &i)| msgs.get(i).map_or(Nanos::MAX, |m| m.deadline))
                    .map(|(k, &i)| (k, i));
                match pick {
                    Some((k, i)) => {
                        let Some(m) = msgs.get_mut(i) else { break };
                        let Some(&(frame, dur)) = m.frames.get(m.next) else {
                            break;
                        };
                        out.push(WireFrame {
                            sof: t,
                            end: t + dur,
                            node: m.node,
                            frame,
                            ok: true,
                        });
                        m.next += 1;
                        if m.next == m.frames.len() {
                            active.swap_remove(k);
                        }
                        t += dur + ifs;
                    }
                    None => {
                        let next_rel = msgs.get(released).map_or(Nanos::MAX, |m| m.release);
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
    out
}

/// Bus time the SRT events released in `[from, to)` need: exact frame lengths (stuffing
/// on the real bits, laxity code 1) plus intermissions, ns.
pub fn offered_ns(
    sc: &Scenario,
    events: &std::collections::HashMap<(usize, u8), Vec<Nanos>>,
    from: Nanos,
    to: Nanos,
) -> Nanos {
    let Some(bus) = sc.bus() else { return 0 };
    let mut total = 0;
    for t in sc.topics.iter().filter(|t| t.class == Class::Srt) {
        let Some(times) = events.get(&(t.node, t.tx)) else {
            continue;
        };
        for (seq, _) in times
            .iter()
            .enumerate()
            .filter(|(_, &at)| at >= from && at < to)
        {
            let mut payload = vec![0u8; t.size];
            fill_payload(&mut payload, seq as u32, t.node as u8, t.tx);
            for c in 0..fragment_count(t.size) {
                let mut data = [0u8; 8];
                let dlc = fragment_data(&payload, c, &mut data);
                if let Some(f) =
                    CanId::new(1, t.msg_id, c).and_then(|id| Frame::from_parts(id, dlc, data))
                {
                    total += bits_to_ns(exact_bits(&f), bus.bitrate);
                }
            }
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
