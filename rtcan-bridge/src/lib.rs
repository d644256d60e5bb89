//! Every topic of a robot on Zenoh: each message the bus carries is put on
//! `rtcan/<robot>/<topic>` (a JSON object with robot.toml's field names, or the raw
//! little-endian payload with `raw`); samples that remote Zenoh nodes put on those keys
//! are commands, accepted only for the topics robot.toml marks `writable` (Triskar2:
//! `teleop`), everything else refused and counted. `ros2` speaks rmw_zenoh's format for
//! the topics robot.toml maps to standard ROS 2 types. The bus is any `rtcan_host::Link`.
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::indexing_slicing,
        clippy::panic
    )
)]

pub mod ros2;

use rtcan_host::value::{from_json, to_json};
use rtcan_host::Link;
use rtcan_sim::candump::Entry;
use rtcan_sim::decode::{Catalog, Decoded, Decoder};
use zenoh::handlers::FifoChannelHandler;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::sample::{Locality, Sample};
use zenoh::{Session, Wait};

/// Key expression prefix of every robot.
pub const PREFIX: &str = "rtcan";

/// The key of `topic` of robot `robot`.
pub fn key(robot: &str, topic: &str) -> String {
    format!("{PREFIX}/{robot}/{topic}")
}

/// Bridge options.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// `<robot>` of the key expressions.
    pub robot: String,
    /// Zenoh endpoints to listen on (`tcp/127.0.0.1:7447`).
    pub listen: Vec<String>,
    /// Zenoh endpoints to connect to.
    pub connect: Vec<String>,
    /// Put raw little-endian payloads instead of JSON.
    pub raw: bool,
    /// Topics accepted from Zenoh.
    pub writable: Vec<String>,
    /// Topics taken from other robots (WAN of CANs): (local topic, robot, its topic).
    pub imports: Vec<(String, String, String)>,
}

/// What a bridge did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Messages put on Zenoh.
    pub published: u64,
    /// Commands from Zenoh published on the bus.
    pub accepted: u64,
    /// Samples on topics not writable from outside (or not topics at all).
    pub refused: u64,
    /// Samples on writable topics whose value did not fit the type, or that the link
    /// could not send.
    pub bad: u64,
    /// Messages of other robots published on this bus (`remote` imports).
    pub imported: u64,
}

/// Opens a Zenoh peer session on `listen`/`connect` (no multicast scouting: peers are
/// named explicitly).
pub fn open_session(listen: &[String], connect: &[String]) -> Result<Session, String> {
    let mut c = zenoh::Config::default();
    let set = |c: &mut zenoh::Config, k: &str, v: String| {
        c.insert_json5(k, &v)
            .map_err(|e| format!("zenoh config {k}: {e}"))
    };
    set(&mut c, "mode", "\"peer\"".into())?;
    set(&mut c, "scouting/multicast/enabled", "false".into())?;
    let list = |v: &[String]| serde_json::to_string(v).unwrap_or_else(|_| "[]".into());
    if !listen.is_empty() {
        set(&mut c, "listen/endpoints", list(listen))?;
    }
    if !connect.is_empty() {
        set(&mut c, "connect/endpoints", list(connect))?;
    }
    zenoh::open(c)
        .wait()
        .map_err(|e| format!("opening the Zenoh session: {e}"))
}

/// A running bridge between one bus and Zenoh.
pub struct Bridge<'c> {
    _session: Session,
    cat: &'c Catalog,
    pubs: Vec<Publisher<'static>>,
    commands: Subscriber<FifoChannelHandler<Sample>>,
    /// One subscriber per import, with its local topic index.
    imports: Vec<(usize, Subscriber<FifoChannelHandler<Sample>>)>,
    dec: Decoder<'c>,
    opts: Options,
    /// Counts so far.
    pub counts: Counts,
    /// The last refusal or bad command, for the report.
    pub last_error: Option<String>,
}

impl<'c> Bridge<'c> {
    /// Declares a publisher for every topic of `cat` and the command subscriber.
    pub fn new(cat: &'c Catalog, opts: Options) -> Result<Self, String> {
        let session = open_session(&opts.listen, &opts.connect)?;
        let mut pubs = Vec::new();
        for t in &cat.topics {
            pubs.push(
                session
                    .declare_publisher(key(&opts.robot, &t.name))
                    .wait()
                    .map_err(|e| format!("declaring {}: {e}", t.name))?,
            );
        }
        // Only remote samples are commands: the bridge's own puts are not.
        let commands = session
            .declare_subscriber(key(&opts.robot, "*"))
            .allowed_origin(Locality::Remote)
            .wait()
            .map_err(|e| format!("declaring the command subscriber: {e}"))?;
        let mut imports = Vec::new();
        for (local, robot, topic) in &opts.imports {
            let Some(i) = cat.topics.iter().position(|t| t.name == *local) else {
                return Err(format!("import into `{local}`: not a topic on the bus"));
            };
            let sub = session
                .declare_subscriber(key(robot, topic))
                .allowed_origin(Locality::Remote)
                .wait()
                .map_err(|e| format!("declaring the import of {robot}/{topic}: {e}"))?;
            imports.push((i, sub));
        }
        Ok(Bridge {
            _session: session,
            cat,
            pubs,
            commands,
            imports,
            dec: Decoder::new(cat),
            opts,
            counts: Counts::default(),
            last_error: None,
        })
    }

    fn command(&mut self, s: &Sample, link: &mut dyn Link) {
        let k = s.key_expr().as_str();
        let topic = k
            .strip_prefix(&format!("{PREFIX}/{}/", self.opts.robot))
            .unwrap_or(k);
        let Some(t) = self
            .cat
            .topics
            .iter()
            .find(|t| t.name == topic)
            .filter(|t| self.opts.writable.contains(&t.name))
        else {
            self.counts.refused += 1;
            self.last_error = Some(format!(
                "refused a command on `{k}`: writable from outside: {}",
                self.opts.writable.join(", ")
            ));
            return;
        };
        match self.value(t, s).and_then(|p| link.publish(&t.name, &p)) {
            Ok(()) => self.counts.accepted += 1,
            Err(e) => {
                self.counts.bad += 1;
                self.last_error = Some(format!("command on `{k}`: {e}"));
            }
        }
    }

    /// A sample's value as topic `t`'s payload (JSON, or raw with `raw`).
    fn value(&self, t: &rtcan_sim::decode::TopicDesc, s: &Sample) -> Result<Vec<u8>, String> {
        let bytes = s.payload().to_bytes();
        if self.opts.raw {
            if bytes.len() == usize::from(t.size) {
                Ok(bytes.to_vec())
            } else {
                Err(format!(
                    "{} bytes, `{}` has {}",
                    bytes.len(),
                    t.name,
                    t.size
                ))
            }
        } else {
            serde_json::from_slice::<serde_json::Value>(&bytes)
                .map_err(|e| format!("not JSON: {e}"))
                .and_then(|v| from_json(t, &v))
        }
    }

    /// Publishes on this bus what the imported robots' topics carried.
    fn import(&mut self, link: &mut dyn Link) {
        let mut got = Vec::new();
        for (i, sub) in &self.imports {
            while let Ok(Some(s)) = sub.try_recv() {
                got.push((*i, s));
            }
        }
        for (i, s) in got {
            let Some(t) = self.cat.topics.get(i) else {
                continue;
            };
            match self.value(t, &s).and_then(|p| link.publish(&t.name, &p)) {
                Ok(()) => self.counts.imported += 1,
                Err(e) => {
                    self.counts.bad += 1;
                    self.last_error = Some(format!("import on `{}`: {e}", s.key_expr()));
                }
            }
        }
    }

    /// Takes the pending commands, then forwards one batch of the bus; `false` when the
    /// bus ended.
    pub fn step(&mut self, link: &mut dyn Link) -> Result<bool, String> {
        while let Ok(Some(s)) = self.commands.try_recv() {
            self.command(&s, link);
        }
        self.import(link);
        let Some(batch) = link.recv()? else {
            return Ok(false);
        };
        for (topic, payload) in messages(&mut self.dec, batch) {
            self.put(topic, &payload)?;
        }
        Ok(true)
    }

    /// Puts one message of topic index `topic` on Zenoh.
    pub fn put(&mut self, topic: usize, payload: &[u8]) -> Result<(), String> {
        let (Some(t), Some(p)) = (self.cat.topics.get(topic), self.pubs.get(topic)) else {
            return Ok(());
        };
        let r = if self.opts.raw {
            p.put(payload.to_vec()).wait()
        } else {
            p.put(to_json(t, payload).to_string()).wait()
        };
        r.map_err(|e| format!("zenoh put {}: {e}", t.name))?;
        self.counts.published += 1;
        Ok(())
    }
}

/// The whole messages (catalog topic index, payload) a batch of bus frames completes.
pub fn messages(dec: &mut Decoder<'_>, batch: Vec<rtcan_host::Stamped>) -> Vec<(usize, Vec<u8>)> {
    let mut out = Vec::new();
    for f in batch {
        let e = Entry {
            time_ns: f.time_ns,
            iface: String::new(),
            frame: f.frame,
            standard: false,
        };
        if let Some(Decoded::Message { topic, payload, .. }) = dec.push(&e) {
            out.push((topic, payload.to_vec()));
        }
    }
    out
}
