//! What `rtcan monitor` shows, kept from the frames and decoded records of a bus: every
//! module with heartbeat age, state and fingerprint match; every topic with rate, last
//! value and transfer time (first to last frame); bus load by class. [`Monitor::render`]
//! prints it as a plain table (the non-interactive mode and the live view alike).
use std::collections::BTreeMap;
use std::fmt::Write as _;

use rtcan_core::{Class, Nanos};
use rtcan_sim::decode::{Catalog, Decoded};

use crate::link::Stamped;
use crate::value::to_json;

/// Nominal bits of an extended data frame with `len` data bytes: SOF, 32 bits of
/// arbitration, 6 of control, data, 15+1 CRC, 2 ACK, 7 EOF, 3 intermission (no stuff bits).
pub fn frame_bits(len: usize) -> u64 {
    67 + 8 * len as u64
}

#[derive(Clone, Debug, Default)]
struct ModuleSeen {
    last_ns: Nanos,
    state: u8,
    fingerprint: u32,
    beats: u64,
}

#[derive(Clone, Debug, Default)]
struct TopicSeen {
    count: u64,
    first_ns: Nanos,
    last_ns: Nanos,
    last: Option<Vec<u8>>,
    last_xfer_ns: Nanos,
}

/// One module as the monitor shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct ModuleRow {
    /// Name (robot.toml), `?` for an index the robot does not have.
    pub name: String,
    /// Bus index.
    pub index: u8,
    /// Time since its last heartbeat, ms.
    pub age_ms: f64,
    /// State byte of its last heartbeat.
    pub state: u8,
    /// Fingerprint of its last heartbeat.
    pub fingerprint: u32,
    /// Whether that is this robot's fingerprint (`None`: the robot's is unknown).
    pub matches: Option<bool>,
}

/// One topic as the monitor shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct TopicRow {
    /// Name.
    pub name: String,
    /// HRT, SRT or NRT.
    pub class: &'static str,
    /// Messages seen.
    pub count: u64,
    /// Mean rate between the first and the last message, Hz.
    pub rate_hz: f64,
    /// First to last frame of the last message, ms.
    pub xfer_ms: f64,
    /// The last value as JSON, `-` before the first.
    pub last: String,
}

/// Everything the monitor shows at one moment.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    /// Bus time, s.
    pub time_s: f64,
    /// Frames seen.
    pub frames: u64,
    /// Modules heard, by index.
    pub modules: Vec<ModuleRow>,
    /// Every topic of the catalog.
    pub topics: Vec<TopicRow>,
    /// Share of the bus per class (sync, HRT, SRT, NRT, other), %.
    pub load: [(&'static str, f64); 5],
    /// Frames under IDs robot.lock retired: images built before a topic changed.
    pub stale: Vec<StaleRow>,
}

/// Frames under one retired ID (`Catalog::retired`): an image that must be rebuilt.
#[derive(Clone, Debug, PartialEq)]
pub struct StaleRow {
    /// The retired message ID.
    pub msg_id: u16,
    /// Frames seen under it.
    pub frames: u64,
    /// The topic it carried, what that topic is now, who to reflash.
    pub reason: String,
}

/// Live figures of one bus.
#[derive(Clone, Debug)]
pub struct Monitor {
    module_names: Vec<String>,
    fingerprint: Option<u32>,
    bitrate: u32,
    modules: BTreeMap<u8, ModuleSeen>,
    topics: Vec<TopicSeen>,
    /// Frames per retired message ID.
    stale: BTreeMap<u16, u64>,
    /// Bits per class: sync (HRT slot), HRT, SRT, NRT, unknown.
    bits: [u64; 5],
    frames: u64,
    first_ns: Option<Nanos>,
    now_ns: Nanos,
}

const CLASSES: [&str; 5] = ["sync", "HRT", "SRT", "NRT", "other"];

impl Monitor {
    /// A monitor for the bus `cat` describes; `module_names` in bus-index order.
    pub fn new(cat: &Catalog, module_names: Vec<String>, bitrate: u32) -> Self {
        Monitor {
            module_names,
            fingerprint: cat.fingerprint,
            bitrate,
            modules: BTreeMap::new(),
            topics: vec![TopicSeen::default(); cat.topics.len()],
            stale: BTreeMap::new(),
            bits: [0; 5],
            frames: 0,
            first_ns: None,
            now_ns: 0,
        }
    }

    /// Counts one frame on the wire (for the bus load).
    pub fn frame(&mut self, s: &Stamped, cat: &Catalog) {
        self.frames += 1;
        self.first_ns.get_or_insert(s.time_ns);
        self.now_ns = self.now_ns.max(s.time_ns);
        let id = s.frame.id();
        let class = if id.is_sync() {
            0
        } else if rtcan_core::heartbeat::parse_heartbeat(&s.frame).is_some() {
            3
        } else {
            match cat.topics.iter().find(|t| t.msg_id == id.msg_id().0) {
                Some(t) => match t.class {
                    Class::Hrt => 1,
                    Class::Srt => 2,
                    Class::Nrt => 3,
                },
                None => {
                    let msg = id.msg_id().0;
                    if cat.retired.iter().any(|r| r.msg_id == msg) {
                        *self.stale.entry(msg).or_default() += 1;
                    }
                    4
                }
            }
        };
        if let Some(b) = self.bits.get_mut(class) {
            *b += frame_bits(s.frame.data().len());
        }
    }

    /// Takes one decoded record; `at_ns` is the time of the frame that completed it.
    pub fn record(&mut self, d: &Decoded, at_ns: Nanos) {
        match d {
            Decoded::Heartbeat {
                time_ns,
                module,
                state,
                fingerprint,
            } => {
                let m = self.modules.entry(*module).or_default();
                m.last_ns = *time_ns;
                m.state = *state;
                m.fingerprint = *fingerprint;
                m.beats += 1;
            }
            Decoded::Message {
                time_ns,
                topic,
                payload,
                ..
            } => {
                if let Some(t) = self.topics.get_mut(*topic) {
                    if t.count == 0 {
                        t.first_ns = *time_ns;
                    }
                    t.count += 1;
                    t.last_ns = *time_ns;
                    t.last = Some(payload.clone());
                    t.last_xfer_ns = at_ns.saturating_sub(*time_ns);
                }
            }
            _ => {}
        }
    }

    /// Messages seen of topic `i` of the catalog.
    pub fn topic_count(&self, i: usize) -> u64 {
        self.topics.get(i).map_or(0, |t| t.count)
    }

    /// Heartbeats seen per module index.
    pub fn heartbeats(&self) -> Vec<(u8, u64)> {
        self.modules.iter().map(|(k, m)| (*k, m.beats)).collect()
    }

    /// Share of the bus time each class took since the first frame, in %.
    pub fn load_pct(&self) -> [f64; 5] {
        let span = self
            .now_ns
            .saturating_sub(self.first_ns.unwrap_or(self.now_ns));
        let bit_ns = 1e9 / f64::from(self.bitrate.max(1));
        self.bits.map(|b| {
            if span == 0 {
                0.0
            } else {
                100.0 * b as f64 * bit_ns / span as f64
            }
        })
    }

    /// What the monitor shows, as of the latest frame: one row per module heard, one per
    /// topic of the catalog, the load per class (the table and the live view alike).
    pub fn view(&self, cat: &Catalog) -> View {
        let now = self.now_ns;
        let modules = self
            .modules
            .iter()
            .map(|(i, m)| ModuleRow {
                name: self
                    .module_names
                    .get(usize::from(*i))
                    .cloned()
                    .unwrap_or_else(|| "?".into()),
                index: *i,
                age_ms: now.saturating_sub(m.last_ns) as f64 * 1e-6,
                state: m.state,
                fingerprint: m.fingerprint,
                matches: self.fingerprint.map(|fp| fp == m.fingerprint),
            })
            .collect();
        let topics = cat
            .topics
            .iter()
            .zip(&self.topics)
            .map(|(t, seen)| TopicRow {
                name: t.name.clone(),
                class: match t.class {
                    Class::Hrt => "HRT",
                    Class::Srt => "SRT",
                    Class::Nrt => "NRT",
                },
                count: seen.count,
                rate_hz: if seen.count > 1 && seen.last_ns > seen.first_ns {
                    (seen.count - 1) as f64 / ((seen.last_ns - seen.first_ns) as f64 * 1e-9)
                } else {
                    0.0
                },
                xfer_ms: seen.last_xfer_ns as f64 * 1e-6,
                last: seen
                    .last
                    .as_ref()
                    .map_or_else(|| "-".to_string(), |p| to_json(t, p).to_string()),
            })
            .collect();
        let mut load = CLASSES.map(|c| (c, 0.0));
        for (slot, p) in load.iter_mut().zip(self.load_pct()) {
            slot.1 = p;
        }
        let stale = self
            .stale
            .iter()
            .map(|(&msg_id, &frames)| StaleRow {
                msg_id,
                frames,
                reason: cat.stale_reason(msg_id).unwrap_or_default(),
            })
            .collect();
        View {
            time_s: now as f64 * 1e-9,
            frames: self.frames,
            modules,
            topics,
            load,
            stale,
        }
    }

    /// The table, as of the latest frame.
    pub fn render(&self, cat: &Catalog) -> String {
        let v = self.view(cat);
        let mut s = String::new();
        let _ = writeln!(s, "bus time {:.3} s, {} frames", v.time_s, v.frames);
        let _ = writeln!(s, "\nMODULE      #   HB AGE ms  STATE  FINGERPRINT  MATCH");
        for m in &v.modules {
            let matches = match m.matches {
                Some(true) => "yes",
                Some(false) => "NO",
                None => "?",
            };
            let _ = writeln!(
                s,
                "{:<10} {:>2} {:>11.1} {:>6}   {:#010x}  {matches}",
                m.name, m.index, m.age_ms, m.state, m.fingerprint
            );
        }
        let _ = writeln!(
            s,
            "\nTOPIC            CLASS  COUNT   RATE Hz  XFER ms  LAST"
        );
        for t in &v.topics {
            let _ = writeln!(
                s,
                "{:<16} {:<5} {:>6} {:>9.1} {:>8.3}  {}",
                t.name, t.class, t.count, t.rate_hz, t.xfer_ms, t.last
            );
        }
        if !v.stale.is_empty() {
            let _ = writeln!(s, "\nSTALE IMAGES (frames under IDs robot.lock retired)");
            for r in &v.stale {
                let _ = writeln!(s, "{:#06x} {:>6}  {}", r.msg_id, r.frames, r.reason);
            }
        }
        let _ = write!(s, "\nLOAD %  ");
        for (c, p) in v.load {
            let _ = write!(s, " {c} {p:.1}");
        }
        s.push('\n');
        s
    }
}
