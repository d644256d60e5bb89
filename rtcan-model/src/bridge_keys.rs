//! What robot.toml says about the world outside the bus (issue 13, docs/BRIDGE.md):
//! `[robot] name` (the `<robot>` of Zenoh keys `rtcan/<robot>/<topic>`, default: the
//! file stem), and per topic `writable = true` (commands from Zenoh or the host accepted),
//! `link = "in" | "out"` (what the gateway forwards over its serial link; link topic
//! numbers are generated from this, 1.. in file order) and `ros2 = "pkg/msg/Type"` (the
//! standard ROS 2 type `rtcan bridge --ros2` maps the topic to) and `remote =
//! "<robot>/<topic>"` (a WAN of CANs, paper 003: the bridge also takes this topic from
//! another robot's bridge, key `rtcan/<robot>/<topic>`). Checked with the rest of
//! robot.toml (`analyze`): every error has a span and a hint.
use crate::diag::{Code, Diagnostic};
use crate::model::{FieldType, Model, Prim};
use crate::syntax::{Entry, Kind};

/// Largest payload of a link topic: the gateway's link frames carry at most 32 bytes
/// (`triskar2_link::MAX_PAYLOAD`, checked equal by rtcan-host's tests).
pub const LINK_MAX_PAYLOAD: usize = 32;
/// Most link topics: numbers are one byte, 0 is not used.
pub const MAX_LINK_TOPICS: usize = 255;
/// Longest robot name.
pub const MAX_NAME_LEN: usize = 64;

/// Direction of a link topic.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkDir {
    /// Host → robot: the gateway publishes what the host sends.
    In,
    /// Robot → host: the gateway forwards every message it receives.
    Out,
}

/// A standard ROS 2 message type a topic can be mapped to, and the robot.toml fields
/// the mapping reads (by name; see docs/BRIDGE.md for the conversion of each).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ros2Type {
    /// `geometry_msgs/msg/Twist` from `vx`, `vy`, `wz`.
    Twist,
    /// `nav_msgs/msg/Odometry` from `x`, `y`, `theta`, `vx`, `vy`, `wz`.
    Odometry,
    /// `sensor_msgs/msg/Range` from `range_mm` (an array: one ROS topic per element).
    Range,
    /// `sensor_msgs/msg/BatteryState` from `mv`, `ma`, `pct`.
    BatteryState,
}

impl Ros2Type {
    /// Every supported type.
    pub const ALL: [Ros2Type; 4] = [
        Ros2Type::Twist,
        Ros2Type::Odometry,
        Ros2Type::Range,
        Ros2Type::BatteryState,
    ];
    /// The ROS 2 name (`pkg/msg/Type`).
    pub const fn name(self) -> &'static str {
        match self {
            Ros2Type::Twist => "geometry_msgs/msg/Twist",
            Ros2Type::Odometry => "nav_msgs/msg/Odometry",
            Ros2Type::Range => "sensor_msgs/msg/Range",
            Ros2Type::BatteryState => "sensor_msgs/msg/BatteryState",
        }
    }
    /// The robot.toml fields the mapping reads.
    pub const fn fields(self) -> &'static [&'static str] {
        match self {
            Ros2Type::Twist => &["vx", "vy", "wz"],
            Ros2Type::Odometry => &["x", "y", "theta", "vx", "vy", "wz"],
            Ros2Type::Range => &["range_mm"],
            Ros2Type::BatteryState => &["mv", "ma", "pct"],
        }
    }
    /// Parses a ROS 2 type name.
    pub fn from_name(name: &str) -> Option<Ros2Type> {
        Ros2Type::ALL.into_iter().find(|t| t.name() == name)
    }
}

/// What one topic declares for the outside world.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TopicBridge {
    /// Topic name.
    pub name: String,
    /// Commands from Zenoh / the host accepted.
    pub writable: bool,
    /// Carried over the gateway's serial link, and which way.
    pub link: Option<LinkDir>,
    /// The ROS 2 type `--ros2` maps it to.
    pub ros2: Option<Ros2Type>,
    /// Taken also from another robot: (robot, topic) of `remote = "robot/topic"`.
    pub remote: Option<(String, String)>,
}

/// A topic on the gateway's serial link.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LinkTopic {
    /// Link topic number (1.., robot.toml order of the topics with `link`).
    pub number: u8,
    /// Topic name.
    pub name: String,
    /// Direction.
    pub dir: LinkDir,
    /// Payload size, bytes.
    pub size: usize,
}

/// The robot's outside-world declarations.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BridgeDecl {
    /// `[robot] name`, or the file stem.
    pub robot: String,
    /// One entry per topic of the model, in file order.
    pub topics: Vec<TopicBridge>,
    /// The link topics, numbered.
    pub link: Vec<LinkTopic>,
}

impl BridgeDecl {
    /// The declarations of topic `name`.
    pub fn topic(&self, name: &str) -> Option<&TopicBridge> {
        self.topics.iter().find(|t| t.name == name)
    }
    /// Names of the topics writable from outside.
    pub fn writable(&self) -> Vec<String> {
        self.topics
            .iter()
            .filter(|t| t.writable)
            .map(|t| t.name.clone())
            .collect()
    }
    /// (local topic, remote robot, remote topic) of every `remote` import.
    pub fn imports(&self) -> Vec<(String, String, String)> {
        self.topics
            .iter()
            .filter_map(|t| {
                let (r, n) = t.remote.clone()?;
                Some((t.name.clone(), r, n))
            })
            .collect()
    }
    /// The link topic of `name`.
    pub fn link_topic(&self, name: &str) -> Option<&LinkTopic> {
        self.link.iter().find(|l| l.name == name)
    }
}

/// Whether `name` can be a robot name: one Zenoh key chunk and one ROS 2 name token
/// (ASCII letter first, then letters, digits and `_`).
pub fn valid_robot_name(name: &str) -> bool {
    let mut c = name.chars();
    c.next().is_some_and(|c| c.is_ascii_alphabetic())
        && c.all(|c| c.is_ascii_alphanumeric() || c == '_')
        && name.len() <= MAX_NAME_LEN
        && !name.contains("__")
}

/// The default robot name: the file stem of `file`, with every character a name cannot
/// hold replaced by `_` (`robot` when nothing usable is left).
pub fn default_name(file: &str) -> String {
    let stem = std::path::Path::new(file)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("");
    let mut out = String::new();
    for c in stem.chars().take(MAX_NAME_LEN) {
        let c = if c.is_ascii_alphanumeric() { c } else { '_' };
        if !(c == '_' && out.ends_with('_')) {
            out.push(c);
        }
    }
    let out = out.trim_matches('_').to_string();
    if valid_robot_name(&out) {
        out
    } else {
        "robot".to_string()
    }
}

fn bad(e: &Entry, code: Code, msg: String, help: &str) -> Diagnostic {
    Diagnostic::new(code, e.value.span.clone(), msg).help(help.to_string())
}

/// Reads `[robot]` and the per-topic keys; `file` gives the default name. Errors go to
/// `items`; the result is what could be read.
pub fn validate(
    file: &str,
    root: &[Entry],
    model: &Model,
    items: &mut Vec<Diagnostic>,
) -> BridgeDecl {
    let mut decl = BridgeDecl {
        robot: default_name(file),
        ..BridgeDecl::default()
    };
    if let Some(r) = root.iter().find(|e| e.key == "robot") {
        robot_table(r, &mut decl, items);
    }
    let topic_entries: &[Entry] = match root.iter().find(|e| e.key == "topics") {
        Some(Entry {
            value:
                crate::syntax::Node {
                    kind: Kind::Table(t),
                    ..
                },
            ..
        }) => t,
        _ => &[],
    };
    for t in &model.topics {
        let keys: &[Entry] = match topic_entries.iter().find(|e| e.key == t.name) {
            Some(Entry {
                value:
                    crate::syntax::Node {
                        kind: Kind::Table(k),
                        ..
                    },
                ..
            }) => k,
            _ => &[],
        };
        let what = format!("topic `{}`", t.name);
        let mut tb = TopicBridge {
            name: t.name.clone(),
            ..TopicBridge::default()
        };
        for e in keys {
            match e.key.as_str() {
                "writable" => match &e.value.kind {
                    Kind::Bool(b) => tb.writable = *b,
                    other => items.push(bad(
                        e,
                        Code::WrongType,
                        format!(
                            "{what} `writable` must be a boolean, found {}",
                            other.type_name()
                        ),
                        "write `writable = true` to accept commands from Zenoh and the host",
                    )),
                },
                "link" => match &e.value.kind {
                    Kind::Str(s) if s == "in" => tb.link = Some(LinkDir::In),
                    Kind::Str(s) if s == "out" => tb.link = Some(LinkDir::Out),
                    Kind::Str(s) => items.push(bad(
                        e,
                        Code::BadValue,
                        format!("{what} `link` is \"{s}\""),
                        "expected \"in\" (host → robot) or \"out\" (robot → host)",
                    )),
                    other => items.push(bad(
                        e,
                        Code::WrongType,
                        format!(
                            "{what} `link` must be a string, found {}",
                            other.type_name()
                        ),
                        "expected \"in\" (host → robot) or \"out\" (robot → host)",
                    )),
                },
                "ros2" => tb.ros2 = ros2_key(e, &what, model, t, items),
                "remote" => tb.remote = remote_key(e, &what, items),
                _ => {}
            }
        }
        if let (Some(_), false, Some(e)) = (
            &tb.remote,
            tb.writable,
            keys.iter().find(|e| e.key == "remote"),
        ) {
            items.push(
                Diagnostic::new(
                    Code::BadValue,
                    e.key_span.clone(),
                    format!("{what} takes messages from another robot but is not writable"),
                )
                .help(
                    "add `writable = true`: the bridge publishes imported messages like commands",
                ),
            );
        }
        if let (Some(dir), Some(e)) = (tb.link, keys.iter().find(|e| e.key == "link")) {
            let size = model.topic_size(t);
            if size > LINK_MAX_PAYLOAD {
                items.push(bad(
                    e,
                    Code::BadValue,
                    format!("{what} is {size} bytes; the gateway's link carries at most {LINK_MAX_PAYLOAD}"),
                    "remove `link` or use a smaller type",
                ));
            } else if decl.link.len() >= MAX_LINK_TOPICS {
                items.push(bad(
                    e,
                    Code::BadValue,
                    format!("more than {MAX_LINK_TOPICS} link topics"),
                    "link topic numbers are one byte",
                ));
            } else {
                decl.link.push(LinkTopic {
                    number: u8::try_from(decl.link.len() + 1).unwrap_or(u8::MAX),
                    name: t.name.clone(),
                    dir,
                    size,
                });
            }
        }
        decl.topics.push(tb);
    }
    decl
}

fn robot_table(r: &Entry, decl: &mut BridgeDecl, items: &mut Vec<Diagnostic>) {
    let Kind::Table(keys) = &r.value.kind else {
        items.push(bad(
            r,
            Code::WrongType,
            format!(
                "`robot` must be a table, found {}",
                r.value.kind.type_name()
            ),
            "write `[robot]` with `name = \"...\"`",
        ));
        return;
    };
    for e in keys {
        if e.key != "name" {
            items.push(
                Diagnostic::new(
                    Code::UnknownKey,
                    e.key_span.clone(),
                    format!("unknown key `{}` in `[robot]`", e.key),
                )
                .help("expected `name`"),
            );
            continue;
        }
        match &e.value.kind {
            Kind::Str(s) if valid_robot_name(s) => decl.robot = s.clone(),
            Kind::Str(s) => items.push(bad(
                e,
                Code::BadValue,
                format!("robot name \"{s}\" cannot be a Zenoh key chunk and ROS 2 name"),
                "use an ASCII letter, then letters, digits and single `_` (at most 64), e.g. \"triskar2\"",
            )),
            other => items.push(bad(
                e,
                Code::WrongType,
                format!("`[robot] name` must be a string, found {}", other.type_name()),
                "e.g. `name = \"triskar2\"`",
            )),
        }
    }
}

/// Whether `name` can be a topic name in a key (`a`..`z`, digits, `_`, letter first).
fn valid_topic_name(name: &str) -> bool {
    let mut c = name.chars();
    c.next().is_some_and(|c| c.is_ascii_lowercase())
        && c.all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

fn remote_key(e: &Entry, what: &str, items: &mut Vec<Diagnostic>) -> Option<(String, String)> {
    let help = "write `remote = \"<robot>/<topic>\"`, e.g. \"triskar2/velocity\"";
    let Kind::Str(s) = &e.value.kind else {
        items.push(bad(
            e,
            Code::WrongType,
            format!(
                "{what} `remote` must be a string, found {}",
                e.value.kind.type_name()
            ),
            help,
        ));
        return None;
    };
    match s.split_once('/') {
        Some((r, t)) if valid_robot_name(r) && valid_topic_name(t) => {
            Some((r.to_string(), t.to_string()))
        }
        _ => {
            items.push(bad(
                e,
                Code::BadValue,
                format!("{what} `remote` is \"{s}\": not `<robot>/<topic>`"),
                help,
            ));
            None
        }
    }
}

/// Whether `ty` can be read as a number by a ROS 2 mapping (`array`: arrays allowed).
fn numeric(ty: FieldType, array: bool) -> bool {
    ty.prim != Prim::Bool && (array || ty.len.is_none())
}

fn ros2_key(
    e: &Entry,
    what: &str,
    model: &Model,
    t: &crate::model::Topic,
    items: &mut Vec<Diagnostic>,
) -> Option<Ros2Type> {
    let supported = Ros2Type::ALL
        .iter()
        .map(|t| format!("\"{}\"", t.name()))
        .collect::<Vec<_>>()
        .join(", ");
    let s = match &e.value.kind {
        Kind::Str(s) => s,
        other => {
            items.push(bad(
                e,
                Code::WrongType,
                format!(
                    "{what} `ros2` must be a string, found {}",
                    other.type_name()
                ),
                &format!("one of {supported}"),
            ));
            return None;
        }
    };
    let Some(r) = Ros2Type::from_name(s) else {
        items.push(bad(
            e,
            Code::BadValue,
            format!("{what} `ros2`: no mapping to \"{s}\""),
            &format!("supported: {supported}"),
        ));
        return None;
    };
    let mt = model.types.get(t.ty)?;
    let array = r == Ros2Type::Range;
    let missing: Vec<&str> = r
        .fields()
        .iter()
        .copied()
        .filter(|f| {
            !mt.fields
                .iter()
                .any(|x| x.name == *f && numeric(x.ty, array))
        })
        .collect();
    if !missing.is_empty() {
        items.push(bad(
            e,
            Code::BadValue,
            format!(
                "{what} `ros2 = \"{s}\"` reads field{} {} of `{}`, which it lacks (or not as {})",
                if missing.len() == 1 { "" } else { "s" },
                missing
                    .iter()
                    .map(|m| format!("`{m}`"))
                    .collect::<Vec<_>>()
                    .join(", "),
                mt.name,
                if array { "numbers" } else { "single numbers" }
            ),
            &format!(
                "the mapping reads {} (docs/BRIDGE.md)",
                r.fields().join(", ")
            ),
        ));
        return None;
    }
    Some(r)
}
