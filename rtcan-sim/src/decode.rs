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
    /// Index of the publishing module (the heartbeat's `module`), when known.
    pub module: Option<u8>,
}

/// What the decoder knows about a bus.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Catalog {
    /// Slots per cycle (to parse sync frames).
    pub slots_per_cycle: u8,
    /// Topics.
    pub topics: Vec<TopicDesc>,
    /// The robot's fingerprint: heartbeats carrying another one come from another robot.
    pub fingerprint: Option<u32>,
    /// IDs robot.lock retired, with the topic each carried: a frame under one comes from
    /// an image built before that topic changed (same lineage, so its heartbeat's
    /// fingerprint matches); the decoder names the topic and its module.
    pub retired: Vec<rtcan_model::lock::Retired>,
}

impl Catalog {
    /// Why a frame of `msg_id`, which no topic of the robot has, is on the bus: the
    /// retired topic it carried, what that topic is now and who publishes it.
    pub fn stale_reason(&self, msg_id: u16) -> Option<String> {
        let r = self.retired.iter().find(|r| r.msg_id == msg_id)?;
        if r.name.is_empty() {
            return Some(format!(
                "retired message ID {msg_id:#06x} (robot.lock): an image built from an older robot.toml is on the bus"
            ));
        }
        let now = match &r.now {
            Some((id, layout)) => format!("now {id:#06x} {layout}"),
            None => "now removed".into(),
        };
        let who = self
            .topics
            .iter()
            .find(|t| t.name == r.name)
            .and_then(|t| t.module)
            .map_or(String::new(), |m| format!(" (its publisher is module {m})"));
        Some(format!(
            "retired ID of topic `{}` (then {}; {now}): an image built before that change is on the bus{who}; rebuild and flash it",
            r.name, r.layout
        ))
    }
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
        /// `Some(fp)`: decoded with `force` although its sender's heartbeat carries
        /// fingerprint `fp`, not the robot's (the fields are likely meaningless).
        foreign: Option<u32>,
    },
    /// A complete message not decoded: its sender's heartbeat carries fingerprint
    /// `fingerprint`, not the robot's (`Decoder::force` decodes it anyway).
    Refused {
        time_ns: Nanos,
        topic: usize,
        module: u8,
        fingerprint: u32,
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

/// Counts kept by a `Decoder`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DecodeCounts {
    /// Frames fed.
    pub frames: u64,
    /// Messages decoded (foreign ones decoded with `force` included).
    pub messages: u64,
    /// Frames not attributed (unknown ID, reassembly drop, standard ID, bad sync).
    pub unattributed: u64,
    /// Heartbeats carrying another fingerprint than the robot's.
    pub foreign_heartbeats: u64,
    /// Frames under a retired ID (`Catalog::retired`): sent by a stale image.
    pub stale: u64,
    /// Messages of senders with another fingerprint, not decoded.
    pub refused: u64,
    /// Messages of senders with another fingerprint, decoded because of `force`.
    pub forced: u64,
}

/// Streaming decoder: one frame in, at most one record out; memory bounded by the
/// catalog, not by the log.
pub struct Decoder<'c> {
    cat: &'c Catalog,
    by_id: HashMap<u16, usize>,
    state: Vec<RxState>,
    bufs: Vec<Vec<u8>>,
    frags: Vec<u8>,
    /// Last heartbeat fingerprint per module index, when it differs from the robot's.
    foreign: HashMap<u8, u32>,
    /// Modules whose last heartbeat carried the robot's fingerprint.
    matching: std::collections::HashSet<u8>,
    /// A foreign fingerprint heard, while no module has matched: the verdict for
    /// senders not heard from yet (one robot's modules share one fingerprint).
    bus_foreign: Option<u32>,
    /// Decode messages of foreign senders too (marked).
    pub force: bool,
    /// Counts so far.
    pub counts: DecodeCounts,
}

impl<'c> Decoder<'c> {
    /// A decoder for the bus `cat` describes.
    pub fn new(cat: &'c Catalog) -> Self {
        Decoder {
            cat,
            by_id: cat
                .topics
                .iter()
                .enumerate()
                .map(|(i, t)| (t.msg_id, i))
                .collect(),
            state: vec![RxState::default(); cat.topics.len()],
            bufs: cat
                .topics
                .iter()
                .map(|t| vec![0u8; wire_len(usize::from(t.size))])
                .collect(),
            frags: vec![0; cat.topics.len()],
            foreign: HashMap::new(),
            matching: std::collections::HashSet::new(),
            bus_foreign: None,
            force: false,
            counts: DecodeCounts::default(),
        }
    }

    fn unattributed(&mut self, time_ns: Nanos, raw_id: u32, why: String) -> Option<Decoded> {
        self.counts.unattributed += 1;
        Some(Decoded::Unattributed {
            time_ns,
            raw_id,
            why,
        })
    }

    /// Feeds one logged frame; returns the record it completes, if any.
    pub fn push(&mut self, e: &Entry) -> Option<Decoded> {
        self.counts.frames += 1;
        let id = e.frame.id();
        let t = e.time_ns;
        if e.standard {
            return self.unattributed(t, id.raw(), "standard identifier".into());
        }
        if id.is_sync() {
            return match parse_sync(&e.frame, self.cat.slots_per_cycle) {
                Some(s) => Some(Decoded::Sync {
                    time_ns: t,
                    cycle: s.cycle,
                    mask: s.mask,
                }),
                None => self.unattributed(t, id.raw(), "malformed sync".into()),
            };
        }
        if let Some(hb) = parse_heartbeat(&e.frame) {
            match self.cat.fingerprint {
                Some(fp) if fp != hb.fingerprint => {
                    self.counts.foreign_heartbeats += 1;
                    self.foreign.insert(hb.module, hb.fingerprint);
                    self.matching.remove(&hb.module);
                    if self.matching.is_empty() {
                        self.bus_foreign = Some(hb.fingerprint);
                    }
                }
                _ => {
                    self.foreign.remove(&hb.module);
                    self.matching.insert(hb.module);
                    self.bus_foreign = None;
                }
            }
            return Some(Decoded::Heartbeat {
                time_ns: t,
                module: hb.module,
                state: hb.state,
                fingerprint: hb.fingerprint,
            });
        }
        let Some(&ti) = self.by_id.get(&id.msg_id().0) else {
            let why = match self.cat.stale_reason(id.msg_id().0) {
                Some(why) => {
                    self.counts.stale += 1;
                    why
                }
                None => "unknown message ID".into(),
            };
            return self.unattributed(t, id.raw(), why);
        };
        let (Some(topic), Some(st), Some(buf), Some(n)) = (
            self.cat.topics.get(ti),
            self.state.get_mut(ti),
            self.bufs.get_mut(ti),
            self.frags.get_mut(ti),
        ) else {
            return None;
        };
        *n = n.saturating_add(1);
        match st.step(buf, usize::from(topic.size), &e.frame, t) {
            RxStep::Complete(payload, first) => {
                let fragments = *n;
                *n = 0;
                // The sender's own heartbeat decides; a sender not heard yet takes the
                // bus's verdict.
                let sender = topic.module.and_then(|m| match self.foreign.get(&m) {
                    Some(&fp) => Some((m, fp)),
                    None if !self.matching.contains(&m) => self.bus_foreign.map(|fp| (m, fp)),
                    None => None,
                });
                match sender {
                    Some((module, fingerprint)) if !self.force => {
                        self.counts.refused += 1;
                        Some(Decoded::Refused {
                            time_ns: first,
                            topic: ti,
                            module,
                            fingerprint,
                        })
                    }
                    _ => {
                        self.counts.messages += 1;
                        if sender.is_some() {
                            self.counts.forced += 1;
                        }
                        Some(Decoded::Message {
                            time_ns: first,
                            topic: ti,
                            payload: payload.to_vec(),
                            fragments,
                            foreign: sender.map(|s| s.1),
                        })
                    }
                }
            }
            RxStep::Pending => None,
            RxStep::Restarted => {
                *n = 1;
                self.unattributed(t, id.raw(), "unfinished transfer discarded".into())
            }
            RxStep::Dropped(why) => {
                *n = 0;
                self.unattributed(t, id.raw(), format!("{why:?}"))
            }
        }
    }
}

/// Decodes `entries` with `cat` (a `Decoder` over a slice).
pub fn decode(entries: &[Entry], cat: &Catalog) -> Vec<Decoded> {
    let mut d = Decoder::new(cat);
    entries.iter().filter_map(|e| d.push(e)).collect()
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
            foreign,
        } => {
            let Some(tp) = cat.topics.get(*topic) else {
                return String::new();
            };
            let mut s = format!("{} {} {}", stamp(*time_ns), class_name(tp.class), tp.name);
            if let Some(fp) = foreign {
                let _ = write!(s, " [FOREIGN SENDER fingerprint={fp:#010x}]");
            }
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
            let mut s = format!(
                "{} NRT heartbeat module={module} state={state} fingerprint={fingerprint:#010x}",
                stamp(*time_ns)
            );
            if let Some(fp) = cat.fingerprint.filter(|fp| fp != fingerprint) {
                let _ = write!(s, " MISMATCH (robot: {fp:#010x})");
            }
            s
        }
        Decoded::Refused {
            time_ns,
            topic,
            module,
            fingerprint,
        } => format!(
            "{} ??? {} not decoded: sender module {module} runs another robot (fingerprint {fingerprint:#010x})",
            stamp(*time_ns),
            cat.topics.get(*topic).map_or("?", |t| t.name.as_str())
        ),
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
                module: u8::try_from(t.node).ok(),
            }
        })
        .collect();
    Catalog {
        slots_per_cycle: sc.bus().map_or(0, |b| b.slots_per_cycle),
        topics,
        fingerprint: sc.bus().map(|b| b.fingerprint),
        retired: Vec::new(),
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
            module: u8::try_from(t.module).ok(),
        })
        .collect();
    Catalog {
        slots_per_cycle: plan.bus.slots_per_cycle,
        topics,
        fingerprint: Some(plan.fingerprint),
        retired: plan.retired.clone(),
    }
}
