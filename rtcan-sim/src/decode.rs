//! candump log → topic-level messages. Reassembly uses the engine's own
//! `rtcan_core::fragment::RxState` (no second implementation); topics come from a
//! `Catalog` built from a robot's plan or from a built-in scenario.
use std::collections::HashMap;
use std::fmt::Write as _;

use rtcan_core::fragment::{wire_len, RxState, RxStep};
use rtcan_core::heartbeat::parse_heartbeat;
use rtcan_core::sync::parse_sync;
use rtcan_core::{Class, Nanos};

use crate::candump::Entry;

/// Field types are the model's (`rtcan_model::Prim`): one definition of the payload layout.
pub use rtcan_model::Prim;

/// A field value as text (little-endian on the wire, docs/PROTOCOL.md).
fn render_prim(prim: Prim, b: &[u8]) -> String {
    let mut a = [0u8; 8];
    for (d, s) in a.iter_mut().zip(b) {
        *d = *s;
    }
    let u = u64::from_le_bytes(a);
    match prim {
        Prim::U8 | Prim::U16 | Prim::U32 | Prim::U64 => u.to_string(),
        Prim::I8 => (u as u8 as i8).to_string(),
        Prim::I16 => (u as u16 as i16).to_string(),
        Prim::I32 => (u as u32 as i32).to_string(),
        Prim::I64 => (u as i64).to_string(),
        Prim::F32 => f32::from_bits(u as u32).to_string(),
        Prim::F64 => f64::from_bits(u).to_string(),
        Prim::Bool => (u != 0).to_string(),
    }
}

/// One payload field.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FieldDesc {
    /// Name.
    pub name: String,
    /// Element type.
    pub prim: Prim,
    /// `Some(n)` for arrays.
    pub len: Option<u16>,
    /// Byte offset.
    pub offset: usize,
}

/// One topic as the decoder knows it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TopicDesc {
    /// Message ID.
    pub msg_id: u16,
    /// Name.
    pub name: String,
    /// Class.
    pub class: Class,
    /// Payload bytes.
    pub size: u16,
    /// Fields.
    pub fields: Vec<FieldDesc>,
}

/// What the decoder knows about a bus.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Catalog {
    /// Slots per cycle (to parse sync frames).
    pub slots_per_cycle: u8,
    /// Topics.
    pub topics: Vec<TopicDesc>,
}

/// One decoded record.
#[derive(Clone, Debug, PartialEq)]
pub enum Decoded {
    /// A complete message; `time_ns` is the first fragment's timestamp.
    Message {
        time_ns: Nanos,
        topic: usize,
        payload: Vec<u8>,
        fragments: u8,
    },
    /// A sync frame.
    Sync {
        time_ns: Nanos,
        cycle: u16,
        mask: u64,
    },
    /// A heartbeat.
    Heartbeat {
        time_ns: Nanos,
        module: u8,
        state: u8,
        fingerprint: u32,
    },
    /// A frame that belongs to no known topic, or was dropped by reassembly.
    Unattributed {
        time_ns: Nanos,
        raw_id: u32,
        why: String,
    },
}

/// Decodes `entries` with `cat`.
pub fn decode(entries: &[Entry], cat: &Catalog) -> Vec<Decoded> {
    let by_id: HashMap<u16, usize> = cat
        .topics
        .iter()
        .enumerate()
        .map(|(i, t)| (t.msg_id, i))
        .collect();
    let mut state: Vec<RxState> = vec![RxState::default(); cat.topics.len()];
    let mut bufs: Vec<Vec<u8>> = cat
        .topics
        .iter()
        .map(|t| vec![0u8; wire_len(usize::from(t.size))])
        .collect();
    let mut frags: Vec<u8> = vec![0; cat.topics.len()];
    let mut out = Vec::new();
    for e in entries {
        let id = e.frame.id();
        let t = e.time_ns;
        if e.standard {
            out.push(Decoded::Unattributed {
                time_ns: t,
                raw_id: id.raw(),
                why: "standard identifier".into(),
            });
            continue;
        }
        if id.is_sync() {
            match parse_sync(&e.frame, cat.slots_per_cycle) {
                Some(s) => out.push(Decoded::Sync {
                    time_ns: t,
                    cycle: s.cycle,
                    mask: s.mask,
                }),
                None => out.push(Decoded::Unattributed {
                    time_ns: t,
                    raw_id: id.raw(),
                    why: "malformed sync".into(),
                }),
            }
            continue;
        }
        if let Some(hb) = parse_heartbeat(&e.frame) {
            out.push(Decoded::Heartbeat {
                time_ns: t,
                module: hb.module,
                state: hb.state,
                fingerprint: hb.fingerprint,
            });
            continue;
        }
        let Some(&ti) = by_id.get(&id.msg_id().0) else {
            out.push(Decoded::Unattributed {
                time_ns: t,
                raw_id: id.raw(),
                why: "unknown message ID".into(),
            });
            continue;
        };
        let (Some(topic), Some(st), Some(buf), Some(n)) = (
            cat.topics.get(ti),
            state.get_mut(ti),
            bufs.get_mut(ti),
            frags.get_mut(ti),
        ) else {
            continue;
        };
        *n = n.saturating_add(1);
        match st.step(buf, usize::from(topic.size), &e.frame, t) {
            RxStep::Complete(payload, first) => {
                out.push(Decoded::Message {
                    time_ns: first,
                    topic: ti,
                    payload: payload.to_vec(),
                    fragments: *n,
                });
                *n = 0;
            }
            RxStep::Pending => {}
            RxStep::Restarted => {
                out.push(Decoded::Unattributed {
                    time_ns: t,
                    raw_id: id.raw(),
                    why: "unfinished transfer discarded".into(),
                });
                *n = 1;
            }
            RxStep::Dropped(why) => {
                out.push(Decoded::Unattributed {
                    time_ns: t,
                    raw_id: id.raw(),
                    why: format!("{why:?}"),
                });
                *n = 0;
            }
        }
    }
    out
}

fn class_name(c: Class) -> &'static str {
    match c {
        Class::Hrt => "HRT",
        Class::Srt => "SRT",
        Class::Nrt => "NRT",
    }
}

fn stamp(t: Nanos) -> String {
    format!("{}.{:06}", t / 1_000_000_000, (t % 1_000_000_000) / 1_000)
}

/// One line per record: time, class, topic, fields.
pub fn render(d: &Decoded, cat: &Catalog) -> String {
    match d {
        Decoded::Message {
            time_ns,
            topic,
            payload,
            fragments,
        } => {
            let Some(tp) = cat.topics.get(*topic) else {
                return String::new();
            };
            let mut s = format!("{} {} {}", stamp(*time_ns), class_name(tp.class), tp.name);
            if *fragments > 1 {
                let _ = write!(s, " [{fragments} frames]");
            }
            for f in &tp.fields {
                let count = usize::from(f.len.unwrap_or(1));
                let vals: Vec<String> = (0..count)
                    .filter_map(|k| {
                        let at = f.offset + k * f.prim.size();
                        payload
                            .get(at..at + f.prim.size())
                            .map(|b| render_prim(f.prim, b))
                    })
                    .collect();
                if f.len.is_some() {
                    let _ = write!(s, " {}=[{}]", f.name, vals.join(","));
                } else {
                    let _ = write!(s, " {}={}", f.name, vals.join(""));
                }
            }
            s
        }
        Decoded::Sync {
            time_ns,
            cycle,
            mask,
        } => format!("{} SYNC cycle={cycle} mask={mask:#018x}", stamp(*time_ns)),
        Decoded::Heartbeat {
            time_ns,
            module,
            state,
            fingerprint,
        } => {
            format!(
                "{} NRT heartbeat module={module} state={state} fingerprint={fingerprint:#010x}",
                stamp(*time_ns)
            )
        }
        Decoded::Unattributed {
            time_ns,
            raw_id,
            why,
        } => {
            format!("{} ??? {raw_id:08X} not attributed: {why}", stamp(*time_ns))
        }
    }
}

/// Catalog of a built-in scenario: identity payloads (see `traffic`).
pub fn scenario_catalog(sc: &crate::run::Scenario) -> Catalog {
    let topics = sc
        .topics
        .iter()
        .map(|t| {
            let mut fields = vec![
                FieldDesc {
                    name: "seq".into(),
                    prim: Prim::U32,
                    len: None,
                    offset: 0,
                },
                FieldDesc {
                    name: "node".into(),
                    prim: Prim::U8,
                    len: None,
                    offset: 4,
                },
                FieldDesc {
                    name: "topic".into(),
                    prim: Prim::U8,
                    len: None,
                    offset: 5,
                },
            ];
            if t.size > 6 {
                fields.push(FieldDesc {
                    name: "fill".into(),
                    prim: Prim::U8,
                    len: Some((t.size - 6) as u16),
                    offset: 6,
                });
            }
            TopicDesc {
                msg_id: t.msg_id.0,
                name: format!("{}_n{}_t{}", t.label, t.node, t.tx),
                class: t.class,
                size: t.size as u16,
                fields,
            }
        })
        .collect();
    Catalog {
        slots_per_cycle: sc.bus().map_or(0, |b| b.slots_per_cycle),
        topics,
    }
}

/// Catalog of a robot's plan: every topic sent on the bus, with its type's fields.
pub fn plan_catalog(plan: &rtcan_model::Plan) -> Catalog {
    let topics = plan
        .topics
        .iter()
        .filter(|t| t.on_bus)
        .map(|t| TopicDesc {
            msg_id: t.msg_id.0,
            name: t.name.clone(),
            class: t.class,
            size: t.size,
            fields: plan
                .types
                .get(t.ty)
                .map(|ty| {
                    ty.fields
                        .iter()
                        .map(|f| FieldDesc {
                            name: f.name.clone(),
                            prim: f.ty.prim,
                            len: f.ty.len,
                            offset: f.offset,
                        })
                        .collect()
                })
                .unwrap_or_default(),
        })
        .collect();
    Catalog {
        slots_per_cycle: plan.bus.slots_per_cycle,
        topics,
    }
}
