//! Tree → `Model`, collecting every error. Names are collected first so references may
//! point forward; each section is then checked key by key.
use crate::diag::{Code, Diagnostic, Span};
use crate::model::{
    Board, Bus, BusSpans, Field, FieldType, FilterMode, Model, Module, MsgType, Node, Prim,
    Subscriber, Topic, TopicSpans,
};
use crate::names;
use crate::syntax::{self, Entry, Kind};
use crate::units;
use rtcan_core::bit_timing::{BitTiming, BitTimingError};
use rtcan_core::fragment::{fragment_count, wire_len, MAX_PAYLOAD};
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::timing::{bits_to_ns, worst_case_bits};
use rtcan_core::Class;

const TOP_KEYS: &[&str] = &[
    "bus", "types", "modules", "nodes", "topics", "sim", "params", "robot", "chains", "services",
];
const BUS_KEYS: &[&str] = &[
    "bitrate",
    "cycle",
    "cycle_us",
    "slots",
    "laxity",
    "laxity_unit",
    "guard",
    "tolerance",
    "master",
    "backup_masters",
];
// `on_missing` and `dependents` are read by `supervision`.
const MODULE_KEYS: &[&str] = &["board", "filters", "on_missing", "dependents"];
const NODE_KEYS: &[&str] = &["module", "priority"];
const TOPIC_KEYS: &[&str] = &[
    "type",
    "publisher",
    "class",
    "rate",
    "period",
    "period_slots",
    "deadline",
    "lead",
    "subscribers",
    "queue",
    // Outside-world keys, read by `bridge_keys`.
    "writable",
    "link",
    "ros2",
    "remote",
];
const SUB_KEYS: &[&str] = &["node", "queue"];

/// Most modules on one bus: heartbeat IDs 0x100..0x13F.
pub const MAX_MODULES: usize = 64;
/// Highest node priority (Cortex-M3 NVIC as used by RTIC on the F103: 4 bits).
pub const MAX_PRIORITY: i64 = 15;
/// Default lead time of an HRT publisher (`lead`), ns: room for a node callback of a few
/// hundred µs on a 72 MHz Cortex-M3 before the frame is prepared. Raised to one slot
/// and capped at the topic's period where those demand it.
pub const DEFAULT_HRT_LEAD_NS: u64 = 500_000;

struct V<'d> {
    diags: &'d mut Vec<Diagnostic>,
    /// "Did you mean" suggestions computed so far: each costs a scan of the declared
    /// names, so only the first [`MAX_SUGGESTIONS`] unknown references get one.
    suggestions: usize,
}

/// Unknown references that get a "did you mean" (8 000 misspellings against 8 000 names
/// must not cost 64 M edit distances).
const MAX_SUGGESTIONS: usize = 50;
/// Longest word an edit distance is computed for (the distance is quadratic in length).
const MAX_SUGGEST_LEN: usize = 64;
/// Names listed when no suggestion is close.
const MAX_LISTED: usize = 12;

/// Declared names of one kind, in file order, with a hash index (a name lookup per
/// reference must not scan 64 000 topics).
struct Names<'a> {
    list: Vec<&'a str>,
    index: std::collections::HashMap<&'a str, usize>,
}

impl<'a> Names<'a> {
    fn new(entries: &'a [Entry]) -> Self {
        let list: Vec<&str> = entries.iter().map(|e| e.key.as_str()).collect();
        let mut index = std::collections::HashMap::with_capacity(list.len());
        for (i, n) in list.iter().enumerate() {
            index.entry(*n).or_insert(i);
        }
        Names { list, index }
    }
    fn find(&self, name: &str) -> Option<usize> {
        self.index.get(name).copied()
    }
    fn get(&self, i: usize) -> &'a str {
        self.list.get(i).copied().unwrap_or("")
    }
}

fn get<'n>(entries: &'n [Entry], key: &str) -> Option<&'n Entry> {
    entries.iter().find(|e| e.key == key)
}

/// Levenshtein distance, for "did you mean" hints.
fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row.first().copied().unwrap_or(0);
        if let Some(first) = row.first_mut() {
            *first = i + 1;
        }
        for (j, cb) in b.iter().enumerate() {
            let cur = row.get(j + 1).copied().unwrap_or(0);
            let left = row.get(j).copied().unwrap_or(0);
            let v = (prev + usize::from(ca != *cb)).min(cur + 1).min(left + 1);
            if let Some(slot) = row.get_mut(j + 1) {
                *slot = v;
            }
            prev = cur;
        }
    }
    row.last().copied().unwrap_or(0)
}

/// The closest candidate within a small edit distance (`max(2, len / 3)`); candidates
/// whose length alone puts them further away are skipped without computing a distance.
pub fn suggest<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    if word.len() > MAX_SUGGEST_LEN {
        return None;
    }
    candidates
        .into_iter()
        .filter(|c| c.len().abs_diff(word.len()) <= 2.max(c.len() / 3))
        .map(|c| (distance(word, c), c))
        .filter(|(d, c)| *d <= 2.max(c.len() / 3))
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

/// `a`, `b`, `c` (the first [`MAX_LISTED`], then "and N more").
/// A name for a message: the first 64 characters of a long one.
fn clip_name(name: &str) -> String {
    match name.char_indices().nth(64) {
        Some((i, _)) => format!("{}... ({} bytes)", name.get(..i).unwrap_or(""), name.len()),
        None => name.to_string(),
    }
}

fn list(names: &[&str]) -> String {
    let mut out = names
        .iter()
        .take(MAX_LISTED)
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > MAX_LISTED {
        out.push_str(&format!(" and {} more", names.len() - MAX_LISTED));
    }
    out
}

impl V<'_> {
    fn push(&mut self, d: Diagnostic) {
        self.diags.push(d);
    }

    fn table<'n>(&mut self, e: &'n Entry, what: &str) -> Option<&'n [Entry]> {
        match &e.value.kind {
            Kind::Table(t) => Some(t),
            other => {
                self.push(Diagnostic::new(
                    Code::WrongType,
                    e.value.span.clone(),
                    format!("{what} must be a table, found {}", other.type_name()),
                ));
                None
            }
        }
    }

    fn check_keys(&mut self, entries: &[Entry], what: &str, allowed: &[&str]) {
        for e in entries {
            if !allowed.contains(&e.key.as_str()) {
                let mut d = Diagnostic::new(
                    Code::UnknownKey,
                    e.key_span.clone(),
                    format!("unknown key `{}` in {what}", e.key),
                );
                d = match suggest(&e.key, allowed.iter().copied()) {
                    Some(s) => d.help(format!("did you mean `{s}`?")),
                    None => d.help(format!("expected one of {}", list(allowed))),
                };
                self.push(d);
            }
        }
    }

    fn string<'n>(&mut self, e: &'n Entry, what: &str) -> Option<&'n str> {
        match &e.value.kind {
            Kind::Str(s) => Some(s),
            other => {
                self.push(Diagnostic::new(
                    Code::WrongType,
                    e.value.span.clone(),
                    format!("{what} must be a string, found {}", other.type_name()),
                ));
                None
            }
        }
    }

    fn int(&mut self, e: &Entry, what: &str, min: i64, max: i64) -> Option<i64> {
        match &e.value.kind {
            Kind::Int(i) if (min..=max).contains(i) => Some(*i),
            Kind::Int(i) => {
                self.push(Diagnostic::new(
                    Code::BadValue,
                    e.value.span.clone(),
                    format!("{what} is {i}, out of range {min}..={max}"),
                ));
                None
            }
            other => {
                self.push(Diagnostic::new(
                    Code::WrongType,
                    e.value.span.clone(),
                    format!("{what} must be an integer, found {}", other.type_name()),
                ));
                None
            }
        }
    }

    /// A string value parsed by `parse`, reporting `BadValue` at the value.
    fn parsed<T>(
        &mut self,
        e: &Entry,
        what: &str,
        parse: impl Fn(&str) -> Result<T, String>,
    ) -> Option<T> {
        let s = self.string(e, what)?;
        match parse(s) {
            Ok(v) => Some(v),
            Err(msg) => {
                self.push(Diagnostic::new(
                    Code::BadValue,
                    e.value.span.clone(),
                    format!("{what}: {msg}"),
                ));
                None
            }
        }
    }

    fn name(&mut self, e: &Entry, what: &str, camel: bool) -> bool {
        let n = &e.key;
        let mut chars = n.chars();
        let form_ok = if camel {
            chars.next().is_some_and(|c| c.is_ascii_uppercase())
                && chars.all(|c| c.is_ascii_alphanumeric())
        } else {
            chars.next().is_some_and(|c| c.is_ascii_lowercase())
                && chars.all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
        };
        let form = if camel {
            "CamelCase, e.g. `WheelSpeeds`"
        } else {
            "snake_case, e.g. `wheel_speeds`"
        };
        if !form_ok {
            self.push(
                Diagnostic::new(
                    Code::BadName,
                    e.key_span.clone(),
                    format!("{what} name `{}` is not a valid name", clip_name(n)),
                )
                .help(format!(
                    "{what} names are {form}, not a Rust keyword; they become Rust identifiers"
                )),
            );
            return false;
        }
        if names::is_keyword(n) {
            let raw = if names::NOT_RAW.contains(&n.as_str()) {
                "it cannot be an identifier at all, not even `r#"
            } else {
                "it would need the raw identifier `r#"
            };
            let end = if names::NOT_RAW.contains(&n.as_str()) {
                "`"
            } else {
                "` at every use"
            };
            self.push(
                Diagnostic::new(
                    Code::BadName,
                    e.key_span.clone(),
                    format!("{what} name `{n}` is a Rust keyword"),
                )
                .help(format!("{what} names become Rust identifiers; {raw}{n}{end}: rename it, e.g. `{}`", if camel { format!("{n}Msg") } else { format!("{n}_") }))
                .note("every strict, reserved and weak keyword of editions 2015 to 2024 is refused (docs/ROBOT_TOML.md, \"Names\")"),
            );
            return false;
        }
        true
    }

    /// Resolves a name reference, or reports `code` with a did-you-mean.
    fn resolve(&mut self, e: &Entry, what: &str, names: &Names<'_>, code: Code) -> Option<usize> {
        let s = self.string(e, what)?;
        if let Some(i) = names.find(s) {
            return Some(i);
        }
        let kind = match code {
            Code::UnknownType => "type",
            Code::UnknownNode => "node",
            _ => "module",
        };
        let mut d = Diagnostic::new(
            code,
            e.value.span.clone(),
            format!("unknown {kind} `{s}` in {what}"),
        );
        let suggestion = if self.suggestions < MAX_SUGGESTIONS {
            self.suggestions += 1;
            suggest(s, names.list.iter().copied())
        } else {
            None
        };
        d = match suggestion {
            Some(c) => d.help(format!("did you mean `{c}`?")),
            None if names.list.is_empty() => d.help(format!("no {kind} is declared")),
            None => d.help(format!("declared {kind}s: {}", list(&names.list))),
        };
        self.push(d);
        None
    }
}

fn section<'n>(v: &mut V<'_>, root: &'n [Entry], key: &str) -> &'n [Entry] {
    match get(root, key) {
        Some(e) => v.table(e, &format!("`[{key}]`")).unwrap_or(&[]),
        None => &[],
    }
}

/// Worst-case duration of one frame with `dlc` bytes, ns.
pub fn frame_ns(dlc: u8, bitrate: u32) -> u64 {
    bits_to_ns(worst_case_bits(dlc), bitrate)
}

/// Worst-case time to send all fragments of a `size`-byte payload back to back, ns.
pub fn message_ns(size: usize, bitrate: u32) -> u64 {
    let n = usize::from(fragment_count(size)).max(1);
    let wire = wire_len(size);
    let last = wire.saturating_sub(8 * (n - 1)).min(8) as u8;
    frame_ns(8, bitrate) * (n as u64 - 1) + frame_ns(last, bitrate)
}

/// Validates the parsed document. Returns the model when there is no input error
/// (schedule errors found here, like an unrepresentable period, still give a model).
pub fn validate(root: &syntax::Node, diags: &mut Vec<Diagnostic>) -> Option<Model> {
    let start = diags.len();
    let mut v = V {
        diags,
        suggestions: 0,
    };
    let Kind::Table(root) = &root.kind else {
        return None;
    };
    v.check_keys(root, "robot.toml (top level)", TOP_KEYS);

    let type_entries = section(&mut v, root, "types");
    let module_entries = section(&mut v, root, "modules");
    let node_entries = section(&mut v, root, "nodes");
    let topic_entries = section(&mut v, root, "topics");
    let type_names = Names::new(type_entries);
    let module_names = Names::new(module_entries);
    let node_names = Names::new(node_entries);

    let types: Vec<MsgType> = type_entries.iter().map(|e| msg_type(&mut v, e)).collect();
    let modules: Vec<Module> = module_entries.iter().map(|e| module(&mut v, e)).collect();
    if modules.len() > MAX_MODULES {
        let e = module_entries.get(MAX_MODULES);
        v.push(
            Diagnostic::new(
                Code::TooManyModules,
                e.and_then(|e| e.key_span.clone()),
                format!(
                    "{} modules declared; a bus has at most {MAX_MODULES}",
                    modules.len()
                ),
            )
            .note("heartbeat message IDs 0x0100..0x013F give one ID per module"),
        );
    }
    let nodes: Vec<Node> = node_entries
        .iter()
        .map(|e| node(&mut v, e, &module_names))
        .collect();
    let bus = bus(&mut v, root, &module_names);

    let mut topics = Vec::new();
    for e in topic_entries {
        if let Some(t) = topic(&mut v, e, &type_names, &node_names, &types, bus.as_ref()) {
            topics.push(t);
        }
    }
    generated_name_clashes(&mut v, module_entries, topic_entries);
    if let Some(b) = &bus {
        bit_timing(&mut v, b, &modules);
    }
    let bus = bus?;
    let failed = diags.get(start..).is_some_and(|new| {
        new.iter()
            .any(|d| d.code.category() == crate::Category::Input)
    });
    if failed {
        return None;
    }
    Some(Model {
        bus,
        types,
        modules,
        nodes,
        topics,
        bridge: crate::bridge_keys::BridgeDecl::default(),
        services: Vec::new(),
        params: Vec::new(),
        module_state: None,
    })
}

/// The bit rate must be reachable exactly from every board's CAN clock, by the same
/// computation the firmware's `can_btr!` runs at compile time (rtcan_core::bit_timing).
fn bit_timing(v: &mut V<'_>, bus: &Bus, modules: &[Module]) {
    for board in Board::ALL {
        let Some(clock) = board.can_clock_hz() else {
            continue;
        };
        let users: Vec<&str> = modules
            .iter()
            .filter(|m| m.board == board)
            .map(|m| m.name.as_str())
            .collect();
        if users.is_empty() {
            continue;
        }
        let why = match BitTiming::compute(clock, bus.bitrate) {
            Ok(_) => continue,
            Err(BitTimingError::OutOfRange) => "above an eighth of the clock".to_string(),
            Err(BitTimingError::NoExactPrescaler) => format!(
                "no prescaler 1..=1024 divides {} MHz into 8..=25 time quanta per bit",
                units::trim_float(f64::from(clock) / 1e6)
            ),
        };
        let near: Vec<String> = COMMON_BITRATES
            .iter()
            .filter(|r| BitTiming::compute(clock, **r).is_ok())
            .map(|r| units::trim_float(f64::from(*r) / 1e3) + " kbit/s")
            .collect();
        v.push(
            Diagnostic::new(
                Code::BitrateUnreachable,
                bus.spans
                    .bitrate
                    .clone()
                    .or_else(|| bus.spans.table.clone()),
                format!(
                    "bit rate {} bit/s is not reachable on board {} (CAN clock {} MHz): {why}",
                    bus.bitrate,
                    board.name(),
                    units::trim_float(f64::from(clock) / 1e6)
                ),
            )
            .help(format!(
                "bit rates this board reaches exactly: {}",
                near.join(", ")
            ))
            .note(format!("modules on this board: {}", list(&users))),
        );
    }
}

/// Bit rates offered in the hint of `bitrate-unreachable`.
const COMMON_BITRATES: &[u32] = &[
    1_000_000, 800_000, 500_000, 250_000, 125_000, 100_000, 50_000, 20_000, 10_000,
];

/// Names that are valid alone but collide in the generated code: a module named like a
/// generated item or a primitive type, and topics whose `<Camel>Topic` aliases are equal.
fn generated_name_clashes(v: &mut V<'_>, modules: &[Entry], topics: &[Entry]) {
    for m in modules {
        if names::RESERVED_MODULE_NAMES.contains(&m.key.as_str()) {
            let what = match m.key.as_str() {
                "topics" => "the generated module holding the topic constants",
                "link" => "the generated module holding the serial link's topic numbers",
                "nodes" => "the generated module placing every node on its module",
                "supervision" => "the generated module holding the supervision rules",
                "rtcan" => "the `rtcan` crate (`rtcan::robot!` next to it would be ambiguous)",
                _ => "a primitive type the generated message structs use",
            };
            v.push(
                Diagnostic::new(
                    Code::NameCollision,
                    m.key_span.clone(),
                    format!("module name `{}` collides with {what}", m.key),
                )
                .help(format!("rename the module, e.g. `{}_module`", m.key)),
            );
        }
    }
    let mut aliases: std::collections::HashMap<String, &str> =
        std::collections::HashMap::with_capacity(topics.len());
    for t in topics {
        let alias = names::topic_alias(&t.key);
        match aliases.get(&alias) {
            Some(first) => v.push(
                Diagnostic::new(
                    Code::NameCollision,
                    t.key_span.clone(),
                    format!(
                        "topics `{}` and `{}` both become the Rust type `{}`",
                        clip_name(first),
                        clip_name(&t.key),
                        clip_name(&alias)
                    ),
                )
                .help("names that differ only in underscores collide after conversion to CamelCase: rename one"),
            ),
            None => {
                aliases.insert(alias, &t.key);
            }
        }
    }
}

fn msg_type(v: &mut V<'_>, e: &Entry) -> MsgType {
    v.name(e, "type", true);
    let mut fields = Vec::new();
    let mut offset = 0;
    for f in v.table(e, &format!("type `{}`", e.key)).unwrap_or(&[]) {
        v.name(f, "field", false);
        let Some(text) = v.string(f, &format!("field `{}.{}`", e.key, f.key)) else {
            continue;
        };
        match parse_field_type(text) {
            Ok(ty) => {
                fields.push(Field { name: f.key.clone(), ty, offset });
                offset += ty.size();
            }
            Err(FieldTypeError::Unknown) => v.push(
                Diagnostic::new(
                    Code::UnknownType,
                    f.value.span.clone(),
                    format!("unknown field type `{text}` for `{}.{}`", e.key, f.key),
                )
                .help(format!("field types are u8, u16, u32, u64, i8, i16, i32, i64, f32, f64, bool, or an array `[T; N]` of one with N in 1..={MAX_PAYLOAD}")),
            ),
            Err(FieldTypeError::Length(n)) => v.push(
                Diagnostic::new(
                    Code::BadValue,
                    f.value.span.clone(),
                    format!("array length {n} of field `{}.{}` is out of range 1..={MAX_PAYLOAD}", e.key, f.key),
                )
                .help(format!("a message carries at most {MAX_PAYLOAD} bytes; an array has 1 to {MAX_PAYLOAD} elements")),
            ),
        }
    }
    if offset > MAX_PAYLOAD {
        v.push(
            Diagnostic::new(
                Code::PayloadTooLarge,
                e.key_span.clone(),
                format!(
                    "type `{}` is {offset} bytes; a message carries at most {MAX_PAYLOAD} bytes",
                    e.key
                ),
            )
            .note("32 fragments of 8 bytes: the fragment field keeps 2 bits for the transfer ID"),
        );
    }
    MsgType {
        name: e.key.clone(),
        fields,
        size: offset,
        span: e.key_span.clone(),
    }
}

/// `f32` or `[i16; 3]` (1 <= N <= MAX_PAYLOAD).
pub fn field_type(text: &str) -> Option<FieldType> {
    parse_field_type(text).ok()
}

/// Why a field type does not parse.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FieldTypeError {
    /// Not a primitive or `[primitive; N]`.
    Unknown,
    /// `[T; N]` with N, as written, outside 1..=MAX_PAYLOAD.
    Length(String),
}

/// [`field_type`], telling an unknown type from an array length out of range.
pub fn parse_field_type(text: &str) -> Result<FieldType, FieldTypeError> {
    let t = text.trim();
    if let Some(inner) = t.strip_prefix('[').and_then(|s| s.strip_suffix(']')) {
        let (p, n) = inner.split_once(';').ok_or(FieldTypeError::Unknown)?;
        let prim = Prim::from_name(p.trim()).ok_or(FieldTypeError::Unknown)?;
        let written = n.trim();
        // Any integer literal is a length (out of range or not); anything else is not a type.
        let digits = written.strip_prefix('-').unwrap_or(written);
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit() || b == b'_') {
            return Err(FieldTypeError::Unknown);
        }
        match written.replace('_', "").parse::<u16>() {
            Ok(n) if (1..=MAX_PAYLOAD as u16).contains(&n) => Ok(FieldType { prim, len: Some(n) }),
            _ => Err(FieldTypeError::Length(written.to_string())),
        }
    } else {
        Prim::from_name(t)
            .map(|prim| FieldType { prim, len: None })
            .ok_or(FieldTypeError::Unknown)
    }
}

fn module(v: &mut V<'_>, e: &Entry) -> Module {
    v.name(e, "module", false);
    let mut m = Module {
        name: e.key.clone(),
        board: Board::Stm32f103c8,
        filters: FilterMode::Exact,
        span: e.key_span.clone(),
    };
    let what = format!("module `{}`", e.key);
    let Some(t) = v.table(e, &what) else { return m };
    v.check_keys(t, &what, MODULE_KEYS);
    match get(t, "board") {
        None => v.push(
            Diagnostic::new(
                Code::MissingKey,
                e.key_span.clone(),
                format!("{what} has no `board`"),
            )
            .help(format!(
                "add `board = \"stm32f103c8\"` (boards: {})",
                board_list()
            )),
        ),
        Some(b) => {
            if let Some(name) = v.string(b, "`board`") {
                match Board::from_name(name) {
                    Some(board) => m.board = board,
                    None => v.push(
                        Diagnostic::new(
                            Code::UnknownBoard,
                            b.value.span.clone(),
                            format!("unknown board `{name}`"),
                        )
                        .help(format!("boards: {}", board_list())),
                    ),
                }
            }
        }
    }
    if let Some(f) = get(t, "filters") {
        match v.string(f, "`filters`") {
            Some("exact") => m.filters = FilterMode::Exact,
            Some("accept-all") => m.filters = FilterMode::AcceptAll,
            Some(other) => v.push(
                Diagnostic::new(
                    Code::BadValue,
                    f.value.span.clone(),
                    format!("`filters` is `{other}`"),
                )
                .help("expected \"exact\" or \"accept-all\""),
            ),
            None => {}
        }
    }
    m
}

fn board_list() -> String {
    let names: Vec<&str> = Board::ALL.iter().map(|b| b.name()).collect();
    list(&names)
}

fn node(v: &mut V<'_>, e: &Entry, modules: &Names<'_>) -> Node {
    v.name(e, "node", false);
    let mut n = Node {
        name: e.key.clone(),
        module: 0,
        priority: 1,
        span: e.key_span.clone(),
    };
    let what = format!("node `{}`", e.key);
    let Some(t) = v.table(e, &what) else { return n };
    v.check_keys(t, &what, NODE_KEYS);
    match get(t, "module") {
        Some(m) => {
            if let Some(i) = v.resolve(m, &format!("{what} `module`"), modules, Code::UnknownModule)
            {
                n.module = i;
            }
        }
        None => v.push(Diagnostic::new(
            Code::MissingKey,
            e.key_span.clone(),
            format!("{what} has no `module`"),
        )),
    }
    if let Some(p) = get(t, "priority") {
        if let Some(p) = v.int(p, "`priority`", 1, MAX_PRIORITY) {
            n.priority = p as u8;
        }
    }
    n
}

fn bus(v: &mut V<'_>, root: &[Entry], modules: &Names<'_>) -> Option<Bus> {
    let Some(be) = get(root, "bus") else {
        v.push(
            Diagnostic::new(
                Code::NoMaster,
                Some(0..0),
                "no `[bus]` table, so no master module",
            )
            .help("add `[bus]` with `master = \"<module>\"`: the module that sends the sync frame"),
        );
        return None;
    };
    let t = v.table(be, "`[bus]`")?;
    v.check_keys(t, "`[bus]`", BUS_KEYS);
    let mut ok = true;
    let mut spans = BusSpans {
        table: be.key_span.clone(),
        ..BusSpans::default()
    };

    let mut bitrate = 1_000_000u64;
    if let Some(e) = get(t, "bitrate") {
        spans.bitrate = e.value.span.clone();
        // The value as written goes into the message (`-1000000`, not a clamped 0).
        let parsed = match &e.value.kind {
            Kind::Int(i) => Some((i128::from(*i), i.to_string())),
            Kind::Str(text) => v
                .parsed(e, "`bitrate`", units::bitrate)
                .map(|b| (i128::from(b), format!("\"{text}\" ({b} bit/s)"))),
            _ => v
                .parsed(e, "`bitrate`", units::bitrate)
                .map(|b| (i128::from(b), b.to_string())),
        };
        match parsed {
            Some((b, _)) if (10_000..=1_000_000).contains(&b) => bitrate = b as u64,
            Some((b, written)) => {
                let why = if b < 0 { "negative" } else { "out of range" };
                v.push(
                    Diagnostic::new(
                        Code::BadValue,
                        e.value.span.clone(),
                        format!("bit rate {written} is {why}"),
                    )
                    .help("classic CAN runs at 10 kbit/s to 1 Mbit/s: write e.g. \"500kbit/s\" or 1000000"),
                );
                ok = false;
            }
            None => ok = false,
        }
    }
    let bitrate = bitrate as u32;

    let mut cycle_ns = 10_000_000u64;
    match (get(t, "cycle"), get(t, "cycle_us")) {
        (Some(_), Some(b)) => {
            v.push(
                Diagnostic::new(
                    Code::BadValue,
                    b.key_span.clone(),
                    "both `cycle` and `cycle_us` are given",
                )
                .help("keep one of them"),
            );
            ok = false;
        }
        (Some(c), None) => {
            spans.cycle = c.value.span.clone();
            match v.parsed(c, "`cycle`", units::duration_ns) {
                Some(ns) => cycle_ns = ns,
                None => ok = false,
            }
        }
        (None, Some(c)) => {
            spans.cycle = c.value.span.clone();
            match v.int(c, "`cycle_us`", 1, 1_000_000_000) {
                Some(us) => cycle_ns = us as u64 * 1000,
                None => ok = false,
            }
        }
        (None, None) => {}
    }

    let mut slots = 60u8;
    if let Some(e) = get(t, "slots") {
        spans.slots = e.value.span.clone();
        match &e.value.kind {
            Kind::Int(n) if *n > 64 => {
                v.push(
                    Diagnostic::new(
                        Code::TooManySlots,
                        e.value.span.clone(),
                        format!("{n} slots per cycle; at most 64"),
                    )
                    .note(
                        "the sync frame's 8-byte payload is the reservation mask: one bit per slot",
                    ),
                );
                ok = false;
            }
            _ => match v.int(e, "`slots`", 2, 64) {
                Some(n) => slots = n as u8,
                None => ok = false,
            },
        }
    }
    let slot_ns = cycle_ns / u64::from(slots);

    let mut guard_ns = 5_000u64;
    if let Some(e) = get(t, "guard") {
        match v.parsed(e, "`guard`", units::duration_ns) {
            Some(ns) => guard_ns = ns,
            None => ok = false,
        }
    }
    let mut tolerance = 0.02;
    if let Some(e) = get(t, "tolerance") {
        match v.parsed(e, "`tolerance`", units::percent) {
            Some(p) if (0.0..=0.5).contains(&p) => tolerance = p,
            Some(_) => {
                v.push(Diagnostic::new(
                    Code::BadValue,
                    e.value.span.clone(),
                    "`tolerance` must be 0% to 50%",
                ));
                ok = false;
            }
            None => ok = false,
        }
    }

    let mut unit_ns = u32::try_from(slot_ns).unwrap_or(u32::MAX).max(1);
    if let Some(e) = get(t, "laxity_unit") {
        match v.parsed(e, "`laxity_unit`", units::duration_ns) {
            Some(ns) if ns <= u64::from(u32::MAX) => unit_ns = ns as u32,
            Some(_) => {
                v.push(Diagnostic::new(
                    Code::BadValue,
                    e.value.span.clone(),
                    "`laxity_unit` must be below 4.29 s",
                ));
                ok = false;
            }
            None => ok = false,
        }
    }
    let mut laxity = LaxityEncoding::Linear { unit_ns };
    if let Some(e) = get(t, "laxity") {
        match v.string(e, "`laxity`") {
            Some("linear") => {}
            Some("log") => laxity = LaxityEncoding::Log { unit_ns },
            Some(other) => {
                v.push(
                    Diagnostic::new(
                        Code::BadValue,
                        e.value.span.clone(),
                        format!("`laxity` is `{other}`"),
                    )
                    .help("expected \"linear\" or \"log\""),
                );
                ok = false;
            }
            None => ok = false,
        }
    }

    let worst_frame_ns = frame_ns(8, bitrate);
    if ok && slot_ns < worst_frame_ns + guard_ns {
        let fit = cycle_ns / (worst_frame_ns + guard_ns);
        v.push(
            Diagnostic::new(
                Code::SlotTooShort,
                spans.slots.clone().or_else(|| spans.cycle.clone()).or_else(|| be.key_span.clone()),
                format!(
                    "slot of {} is shorter than a worst-case 8-byte frame ({} at {} bit/s) plus the guard ({})",
                    units::fmt_ns(slot_ns as f64),
                    units::fmt_ns(worst_frame_ns as f64),
                    bitrate,
                    units::fmt_ns(guard_ns as f64)
                ),
            )
            .help(format!(
                "use at most {fit} slots per cycle, or a cycle of at least {}",
                units::fmt_ns(((worst_frame_ns + guard_ns) * u64::from(slots)) as f64)
            )),
        );
    }

    let master = match get(t, "master") {
        None => {
            v.push(
                Diagnostic::new(Code::NoMaster, be.key_span.clone(), "the bus has no master").help(
                    "add `master = \"<module>\"` to `[bus]`: the module that sends the sync frame",
                ),
            );
            None
        }
        Some(e) => v.resolve(e, "`[bus] master`", modules, Code::UnknownModule),
    };
    let mut backup_masters = Vec::new();
    if let Some(e) = get(t, "backup_masters") {
        match &e.value.kind {
            Kind::Array(items) => {
                for item in items {
                    let entry = Entry {
                        key: String::new(),
                        key_span: None,
                        value: item.clone(),
                    };
                    if let Some(i) =
                        v.resolve(&entry, "`backup_masters`", modules, Code::UnknownModule)
                    {
                        if backup_masters.contains(&i) || Some(i) == master {
                            v.push(Diagnostic::new(
                                Code::DuplicateName,
                                item.span.clone(),
                                format!(
                                    "module `{}` is already a master or backup master",
                                    modules.get(i)
                                ),
                            ));
                        } else {
                            backup_masters.push(i);
                        }
                    }
                }
            }
            other => v.push(Diagnostic::new(
                Code::WrongType,
                e.value.span.clone(),
                format!(
                    "`backup_masters` must be an array of module names, found {}",
                    other.type_name()
                ),
            )),
        }
    }
    let master = master?;
    ok.then_some(Bus {
        bitrate,
        cycle_ns,
        slots,
        slot_ns,
        laxity,
        guard_ns,
        master,
        backup_masters,
        tolerance,
        worst_frame_ns,
        spans,
    })
}

fn topic(
    v: &mut V<'_>,
    e: &Entry,
    type_names: &Names<'_>,
    node_names: &Names<'_>,
    types: &[MsgType],
    bus: Option<&Bus>,
) -> Option<Topic> {
    v.name(e, "topic", false);
    let what = format!("topic `{}`", e.key);
    let t = v.table(e, &what)?;
    v.check_keys(t, &what, TOPIC_KEYS);
    let missing = |v: &mut V<'_>, key: &str, example: &str| {
        v.push(
            Diagnostic::new(
                Code::MissingKey,
                e.key_span.clone(),
                format!("{what} has no `{key}`"),
            )
            .help(format!("add `{key} = {example}`")),
        );
    };
    let ty = match get(t, "type") {
        Some(x) => v.resolve(x, &format!("{what} `type`"), type_names, Code::UnknownType),
        None => {
            missing(v, "type", "\"<Type>\"");
            None
        }
    };
    let publisher = match get(t, "publisher") {
        Some(x) => v.resolve(
            x,
            &format!("{what} `publisher`"),
            node_names,
            Code::UnknownNode,
        ),
        None => {
            missing(v, "publisher", "\"<node>\"");
            None
        }
    };
    let class = match get(t, "class") {
        None => {
            missing(v, "class", "\"hrt\"");
            None
        }
        Some(c) => match v.string(c, "`class`") {
            Some("hrt") => Some(Class::Hrt),
            Some("srt") => Some(Class::Srt),
            Some("nrt") => Some(Class::Nrt),
            Some(other) => {
                v.push(
                    Diagnostic::new(
                        Code::BadValue,
                        c.value.span.clone(),
                        format!("`class` is `{other}`"),
                    )
                    .help("expected \"hrt\", \"srt\" or \"nrt\""),
                );
                None
            }
            None => None,
        },
    };

    let mut default_queue = 1u16;
    if let Some(q) = get(t, "queue") {
        if let Kind::Int(0) = q.value.kind {
            v.push(queue_zero(q.value.span.clone(), &e.key));
        } else if let Some(n) = v.int(q, "`queue`", 1, 255) {
            default_queue = n as u16;
        }
    }
    let subscribers = subscribers(v, e, t, node_names, default_queue);

    // Timing keys: at most one of rate / period / period_slots.
    let timing_keys: Vec<&Entry> = ["rate", "period", "period_slots"]
        .iter()
        .filter_map(|k| get(t, k))
        .collect();
    if let [_, second, ..] = timing_keys.as_slice() {
        v.push(
            Diagnostic::new(
                Code::BadValue,
                second.key_span.clone(),
                format!("{what} gives more than one of `rate`, `period`, `period_slots`"),
            )
            .help("keep one"),
        );
    }
    let timing = timing_keys.first().copied();
    let mut spans = TopicSpans {
        name: e.key_span.clone(),
        timing: timing.and_then(|x| x.value.span.clone()),
        deadline: None,
    };
    let requested_ns: Option<f64> = timing.and_then(|x| match x.key.as_str() {
        "rate" => v
            .parsed(x, "`rate`", units::frequency_hz)
            .map(|hz| 1e9 / hz),
        "period" => v
            .parsed(x, "`period`", units::duration_ns)
            .map(|ns| ns as f64),
        _ => {
            let slot = bus.map_or(0, |b| b.slot_ns) as f64;
            v.int(x, "`period_slots`", 1, 1_000_000)
                .map(|n| n as f64 * slot)
        }
    });
    let deadline = get(t, "deadline");
    spans.deadline = deadline.and_then(|d| d.value.span.clone());
    let lead = get(t, "lead");

    let class = class?;
    let mut period_slots = None;
    let mut rate_hz = None;
    let mut deadline_ns = None;
    match class {
        Class::Hrt => {
            if let Some(d) = deadline {
                v.push(
                    Diagnostic::new(Code::ClassMismatch, d.key_span.clone(), format!("{what} is HRT: `deadline` applies to SRT topics"))
                        .help("an HRT message's deadline is its slot; remove `deadline` or make the topic `class = \"srt\"`"),
                );
            }
            match (timing, bus) {
                (None, _) => missing(v, "rate", "\"100Hz\" (or `period = \"10ms\"`)"),
                (Some(x), Some(bus)) => {
                    if let Some(req) = requested_ns {
                        period_slots = discretise(v, &e.key, x, req, bus);
                    }
                }
                (Some(_), None) => {}
            }
        }
        Class::Srt | Class::Nrt => {
            rate_hz = requested_ns.map(|ns| 1e9 / ns);
            if class == Class::Srt {
                match deadline {
                    None => missing(v, "deadline", "\"10ms\""),
                    Some(d) => deadline_ns = v.parsed(d, "`deadline`", units::duration_ns),
                }
            } else if let Some(d) = deadline {
                v.push(
                    Diagnostic::new(
                        Code::ClassMismatch,
                        d.key_span.clone(),
                        format!("{what} is NRT: `deadline` applies to SRT topics"),
                    )
                    .help("make the topic `class = \"srt\"` or remove `deadline`"),
                );
            }
        }
    }
    let lead_ns = hrt_lead(v, &e.key, class, lead, period_slots, bus);
    let (ty, publisher) = (ty?, publisher?);

    if let (Some(dl), Some(bus), Some(mt)) = (deadline_ns, bus, types.get(ty)) {
        let tx = message_ns(mt.size, bus.bitrate);
        if dl < tx {
            let n = fragment_count(mt.size);
            v.push(
                Diagnostic::new(
                    Code::SrtDeadlineTooShort,
                    spans.deadline.clone(),
                    format!(
                        "SRT topic `{}` has deadline {}, shorter than its own transmission time ({} {} of `{}`, {} worst case)",
                        e.key,
                        units::fmt_ns(dl as f64),
                        n,
                        if n == 1 { "frame" } else { "frames" },
                        mt.name,
                        units::fmt_ns(tx as f64)
                    ),
                )
                .help(format!("the deadline must be at least {}", units::fmt_ns(tx as f64))),
            );
        }
    }
    Some(Topic {
        name: e.key.clone(),
        ty,
        publisher,
        class,
        period_slots,
        requested_period_ns: requested_ns.filter(|_| class == Class::Hrt),
        deadline_ns,
        rate_hz,
        lead_ns,
        subscribers: subscribers?,
        spans,
    })
}

/// Lead time of an HRT topic's publisher (`lead`, R2P §3.4.5 synchronous publishers):
/// its callback runs this long before each of the topic's slots, so the sample is at
/// most this old on the bus. At least one slot: the images prepare a slot's frame half
/// a slot ahead (boards/app `Driver`), and the callback must have published by then.
/// At most the topic's period, or the callback would run for two instances at once. `None` for SRT/NRT (a `lead` there is an error) and for unplanned periods.
fn hrt_lead(
    v: &mut V<'_>,
    topic: &str,
    class: Class,
    lead: Option<&Entry>,
    period_slots: Option<u32>,
    bus: Option<&Bus>,
) -> Option<u64> {
    if class != Class::Hrt {
        if let Some(l) = lead {
            v.push(
                Diagnostic::new(
                    Code::ClassMismatch,
                    l.key_span.clone(),
                    format!("topic `{topic}` is not HRT: `lead` applies to HRT topics"),
                )
                .help("SRT/NRT publishers run when they have data; remove `lead` or make the topic `class = \"hrt\"`"),
            );
        }
        return None;
    }
    let (bus, period) = (bus?, u64::from(period_slots?));
    let period_ns = period.saturating_mul(bus.slot_ns);
    let Some(l) = lead else {
        return Some(DEFAULT_HRT_LEAD_NS.max(bus.slot_ns).min(period_ns));
    };
    let ns = v.parsed(l, "`lead`", units::duration_ns)?;
    if ns < bus.slot_ns || ns > period_ns {
        let at = l.value.span.clone();
        v.push(
            Diagnostic::new(
                Code::BadValue,
                at,
                format!(
                    "HRT topic `{topic}`: `lead` of {} is outside one slot ({}) ..= its period ({period} slots = {period_ns} ns)",
                    units::fmt_ns(ns as f64),
                    units::fmt_ns(bus.slot_ns as f64),
                ),
            )
            .help(format!(
                "give `lead` from {} (the frame is prepared half a slot ahead) to {period_ns}ns",
                units::fmt_ns(bus.slot_ns as f64),
            )),
        );
        return None;
    }
    Some(ns)
}

fn queue_zero(span: Option<Span>, topic: &str) -> Diagnostic {
    Diagnostic::new(
        Code::QueueZero,
        span,
        format!("subscriber queue of topic `{topic}` has length 0"),
    )
    .help("a subscriber needs room for at least one message: use `queue = 1` or more")
}

fn subscribers(
    v: &mut V<'_>,
    e: &Entry,
    t: &[Entry],
    node_names: &Names<'_>,
    default_queue: u16,
) -> Option<Vec<Subscriber>> {
    let Some(s) = get(t, "subscribers") else {
        return Some(Vec::new());
    };
    let Kind::Array(items) = &s.value.kind else {
        v.push(
            Diagnostic::new(
                Code::WrongType,
                s.value.span.clone(),
                format!(
                    "`subscribers` must be an array, found {}",
                    s.value.kind.type_name()
                ),
            )
            .help("write `subscribers = [\"node\", { node = \"other\", queue = 4 }]`"),
        );
        return None;
    };
    let mut out: Vec<Subscriber> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    let mut ok = true;
    for item in items {
        let (node_entry, queue) = match &item.kind {
            Kind::Str(_) => (
                Entry {
                    key: String::new(),
                    key_span: None,
                    value: item.clone(),
                },
                default_queue,
            ),
            Kind::Table(fields) => {
                v.check_keys(fields, "a subscriber", SUB_KEYS);
                let mut queue = default_queue;
                if let Some(q) = get(fields, "queue") {
                    if let Kind::Int(0) = q.value.kind {
                        v.push(queue_zero(q.value.span.clone(), &e.key));
                        ok = false;
                    } else if let Some(n) = v.int(q, "`queue`", 1, 255) {
                        queue = n as u16;
                    } else {
                        ok = false;
                    }
                }
                match get(fields, "node") {
                    Some(n) => (n.clone(), queue),
                    None => {
                        v.push(Diagnostic::new(
                            Code::MissingKey,
                            item.span.clone(),
                            "subscriber has no `node`",
                        ));
                        ok = false;
                        continue;
                    }
                }
            }
            other => {
                v.push(Diagnostic::new(
                    Code::WrongType,
                    item.span.clone(),
                    format!(
                        "a subscriber is a node name or `{{ node = \"..\", queue = N }}`, found {}",
                        other.type_name()
                    ),
                ));
                ok = false;
                continue;
            }
        };
        let Some(node) = v.resolve(
            &node_entry,
            &format!("topic `{}` subscribers", e.key),
            node_names,
            Code::UnknownNode,
        ) else {
            ok = false;
            continue;
        };
        if !seen.insert(node) {
            v.push(Diagnostic::new(
                Code::DuplicateName,
                node_entry.value.span.clone(),
                format!(
                    "node `{}` subscribes to topic `{}` twice",
                    node_names.get(node),
                    e.key
                ),
            ));
            ok = false;
            continue;
        }
        out.push(Subscriber {
            node,
            queue,
            span: node_entry.value.span.clone(),
        });
    }
    ok.then_some(out)
}

/// HRT period in slots = round(requested / slot); an error when that misses the request
/// by more than the bus tolerance. Returns the (clamped) period either way, so planning
/// can still report further problems.
fn discretise(v: &mut V<'_>, topic: &str, x: &Entry, requested_ns: f64, bus: &Bus) -> Option<u32> {
    let slot = bus.slot_ns as f64;
    let n = (requested_ns / slot).round().clamp(0.0, u32::MAX as f64) as u32;
    let actual = f64::from(n) * slot;
    let err = (actual - requested_ns).abs() / requested_ns;
    if n == 0 || err > bus.tolerance + 1e-12 {
        let lo = ((requested_ns / slot).floor() as u32).max(1);
        let hi = lo.saturating_add(1);
        let opt = |k: u32| {
            let ns = f64::from(k) * slot;
            format!(
                "{k} slots ({}, {})",
                units::fmt_ns(ns),
                units::fmt_hz(1e9 / ns)
            )
        };
        let got = if n == 0 {
            "shorter than one slot".to_string()
        } else {
            format!(
                "nearest is {} ({:+.1}%)",
                opt(n),
                100.0 * (actual - requested_ns) / requested_ns
            )
        };
        v.push(
            Diagnostic::new(
                Code::PeriodNotRepresentable,
                x.value.span.clone(),
                format!(
                    "topic `{topic}` requests a period of {} ({}), not representable in {} slots: {got}",
                    units::fmt_ns(requested_ns),
                    units::fmt_hz(1e9 / requested_ns),
                    units::fmt_ns(slot)
                ),
            )
            .help(format!("representable periods near it: {}, {}", opt(lo), opt(hi)))
            .note(format!("the bus tolerance is {}%", units::trim_float(bus.tolerance * 100.0))),
        );
    }
    Some(n.max(1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_types() {
        assert_eq!(
            field_type("f32"),
            Some(FieldType {
                prim: Prim::F32,
                len: None
            })
        );
        assert_eq!(
            field_type("[i16; 3]"),
            Some(FieldType {
                prim: Prim::I16,
                len: Some(3)
            })
        );
        assert_eq!(field_type("[u8;0]"), None);
        assert_eq!(field_type("f16"), None);
        assert_eq!(field_type("[f32]"), None);
    }

    #[test]
    fn suggestions() {
        assert_eq!(
            suggest("publsher", TOPIC_KEYS.iter().copied()),
            Some("publisher")
        );
        assert_eq!(suggest("zzzzzz", TOPIC_KEYS.iter().copied()), None);
    }
}
