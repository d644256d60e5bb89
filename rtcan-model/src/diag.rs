//! Diagnostics: structured (code, message, byte span, help) for the proc macro, and
//! rendered rustc-style (`file:line:col`, excerpt, caret, help) for the CLI and build.rs.
use std::fmt::Write as _;
use std::ops::Range;

/// Byte range in the robot.toml source.
pub type Span = Range<usize>;

/// Whether an error makes the input invalid, the robot not schedulable, or admission
/// undecided. `rtcan check` exits 2, 1 and 3 respectively.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Category {
    /// The description is malformed or inconsistent.
    Input,
    /// The description is well formed but the bus cannot carry it in time.
    Schedule,
    /// The admission search ran out of budget: neither admitted nor refuted.
    Undecided,
}

macro_rules! codes {
    ($($(#[$doc:meta])* $variant:ident = $name:literal, $cat:ident;)*) => {
        /// Stable diagnostic codes; the rendered name (`error[name]`) never changes.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Code { $($(#[$doc])* $variant,)* }

        impl Code {
            /// Every code, in documentation order.
            pub const ALL: &'static [Code] = &[$(Code::$variant,)*];
            /// The stable name, e.g. `unknown-key`.
            pub const fn name(self) -> &'static str {
                match self { $(Code::$variant => $name,)* }
            }
            /// Input or schedule error.
            pub const fn category(self) -> Category {
                match self { $(Code::$variant => Category::$cat,)* }
            }
        }
    };
}

codes! {
    /// The file is not valid TOML.
    TomlSyntax = "toml-syntax", Input;
    /// The file could not be read.
    Io = "io", Input;
    /// The file is larger than `MAX_SOURCE_BYTES` (16 MiB).
    FileTooLarge = "file-too-large", Input;
    /// The file is not UTF-8.
    InvalidUtf8 = "invalid-utf8", Input;
    /// Tables or arrays nested deeper than the parser accepts.
    TooDeep = "too-deep", Input;
    /// A key the schema does not know.
    UnknownKey = "unknown-key", Input;
    /// A required key is absent.
    MissingKey = "missing-key", Input;
    /// A value of the wrong TOML type (string where a number is expected, ...).
    WrongType = "wrong-type", Input;
    /// A number or unit that does not parse or is out of range.
    BadValue = "bad-value", Input;
    /// A name that is not a lowercase identifier.
    BadName = "bad-name", Input;
    /// Two items with the same (normalised) name.
    DuplicateName = "duplicate-name", Input;
    /// Names that collide in the generated code (`enc1` and `enc_1` → `Enc1Topic`), or
    /// a module named like a generated item or a primitive type.
    NameCollision = "name-collision", Input;
    /// The bit rate is not reachable exactly from the CAN clock of a module's board.
    BitrateUnreachable = "bitrate-unreachable", Input;
    /// A topic's message pool exceeds what `rtcan_pubsub::Topic` supports.
    PoolTooLarge = "pool-too-large", Input;
    /// A message type, or a field type, that does not exist.
    UnknownType = "unknown-type", Input;
    /// A node reference that does not exist.
    UnknownNode = "unknown-node", Input;
    /// A module reference that does not exist.
    UnknownModule = "unknown-module", Input;
    /// A board the model does not know.
    UnknownBoard = "unknown-board", Input;
    /// `[bus] master` is missing.
    NoMaster = "no-master", Input;
    /// More than 64 slots per cycle (the sync frame's mask has 64 bits).
    TooManySlots = "too-many-slots", Input;
    /// More than 64 modules (heartbeat IDs 0x100..0x13F).
    TooManyModules = "too-many-modules", Input;
    /// A key that does not apply to the topic's class.
    ClassMismatch = "class-mismatch", Input;
    /// Payload above the fragmentation limit.
    PayloadTooLarge = "payload-too-large", Input;
    /// A subscriber queue of length 0.
    QueueZero = "queue-zero", Input;
    /// A module needs more CAN filter banks than its board has.
    FilterBanksExhausted = "filter-banks-exhausted", Input;
    /// robot.lock is malformed (it is generated: restore it or delete it).
    LockInvalid = "lock-invalid", Input;
    /// An end-to-end chain's worst-case latency bound exceeds its budget, or it has none.
    ChainOverBudget = "chain-over-budget", Schedule;
    /// A module's tables exceed what the engine can index.
    TableTooLarge = "table-too-large", Input;
    /// The slot is shorter than a worst-case 8-byte frame plus the guard.
    SlotTooShort = "slot-too-short", Schedule;
    /// An HRT period that is not a whole number of slots within tolerance.
    PeriodNotRepresentable = "period-not-representable", Schedule;
    /// No phase assignment exists for the HRT set.
    InadmissibleHrt = "inadmissible-hrt", Schedule;
    /// HRT reservations exceed the slots of the hyperperiod.
    HrtOverCapacity = "hrt-over-capacity", Schedule;
    /// The HRT hyperperiod is longer than the engine's calendar bound.
    HyperperiodTooLong = "hyperperiod-too-long", Schedule;
    /// Too many HRT topics for the admission test.
    TooManyHrt = "too-many-hrt", Schedule;
    /// The admission search hit its step budget: neither a placement nor a proof that
    /// none exists (undecided; the build refuses it too).
    AdmissionUndecided = "admission-undecided", Undecided;
    /// HRT plus average SRT/NRT load exceeds the bus capacity.
    BusOverload = "bus-overload", Schedule;
    /// An SRT deadline shorter than the message's own transmission time.
    SrtDeadlineTooShort = "srt-deadline-too-short", Schedule;
    /// A module's slot-boundary latency plus clock error exceeds the guard (timing.rs).
    GuardTooShort = "guard-too-short", Schedule;
    /// A module's protocol CPU load at full bus load exceeds its CPU (timing.rs).
    CpuOverload = "cpu-overload", Schedule;
    /// A module's RX interrupt may answer later than its receive FIFO lasts (timing.rs).
    RxFifoOverrun = "rx-fifo-overrun", Schedule;
}

/// One error with where it is and what to do about it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    /// Stable code.
    pub code: Code,
    /// One-line message.
    pub message: String,
    /// Primary location, when the error has one in the file.
    pub span: Option<Span>,
    /// `= help:` lines.
    pub help: Vec<String>,
    /// `= note:` lines.
    pub notes: Vec<String>,
}

impl Diagnostic {
    /// A diagnostic without help or notes.
    pub fn new(code: Code, span: Option<Span>, message: impl Into<String>) -> Self {
        Diagnostic {
            code,
            message: message.into(),
            span,
            help: Vec::new(),
            notes: Vec::new(),
        }
    }
    /// Adds a help line.
    pub fn help(mut self, text: impl Into<String>) -> Self {
        self.help.push(text.into());
        self
    }
    /// Adds a note line.
    pub fn note(mut self, text: impl Into<String>) -> Self {
        self.notes.push(text.into());
        self
    }
}

/// All errors of one robot.toml, with the source needed to render them.
#[derive(Clone, Debug)]
pub struct Diagnostics {
    /// File name as shown in `-->` lines.
    pub file: String,
    /// The source text spans point into.
    pub source: String,
    /// The errors, in the order found (file order within each stage).
    pub items: Vec<Diagnostic>,
}

/// Most diagnostics [`Diagnostics::render`] prints in full; the rest are counted in one
/// closing line (`--json` keeps them all).
pub const MAX_RENDERED: usize = 50;

/// Byte offset of every line start of a source, built once so that each position lookup
/// is a binary search (48 000 errors in a 5 MB file cost 48 000 · log(lines), not
/// 48 000 · 5 MB).
#[derive(Clone, Debug)]
pub struct LineIndex {
    /// Byte offset where line k (0-based) starts; `starts[0] == 0`.
    starts: Vec<usize>,
    /// Whether line k is ASCII (then the column is the byte distance).
    ascii: Vec<bool>,
}

impl LineIndex {
    /// Scans `source` once.
    pub fn new(source: &str) -> Self {
        let mut starts = vec![0];
        let mut ascii = Vec::new();
        let mut line_ascii = true;
        for (i, b) in source.bytes().enumerate() {
            if b == b'\n' {
                starts.push(i + 1);
                ascii.push(line_ascii);
                line_ascii = true;
            } else if !b.is_ascii() {
                line_ascii = false;
            }
        }
        ascii.push(line_ascii);
        LineIndex { starts, ascii }
    }

    /// 0-based line holding byte `offset`.
    fn line_of(&self, offset: usize) -> usize {
        self.starts
            .partition_point(|&s| s <= offset)
            .saturating_sub(1)
    }

    /// Byte offset of the start of the line holding `offset`.
    pub fn line_start(&self, offset: usize) -> usize {
        self.starts.get(self.line_of(offset)).copied().unwrap_or(0)
    }

    /// 1-based line and column (in characters) of a byte offset in `source` (the text
    /// this index was built from), clamped to the source.
    pub fn line_col(&self, source: &str, offset: usize) -> (usize, usize) {
        let offset = floor_char_boundary(source, offset.min(source.len()));
        let line = self.line_of(offset);
        let start = self.starts.get(line).copied().unwrap_or(0).min(offset);
        let col = if self.ascii.get(line).copied().unwrap_or(false) {
            offset - start
        } else {
            source.get(start..offset).map_or(0, |s| s.chars().count())
        };
        (line + 1, col + 1)
    }
}

impl Diagnostics {
    /// No errors.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
    /// True when every error is a schedule error (input valid, robot not admissible).
    pub fn only_schedule(&self) -> bool {
        !self.items.is_empty()
            && self
                .items
                .iter()
                .all(|d| d.code.category() == Category::Schedule)
    }
    /// True when admission was undecided and nothing else is wrong with the input (other
    /// schedule errors may be present: the verdict is still open).
    pub fn undecided(&self) -> bool {
        self.items
            .iter()
            .any(|d| d.code.category() == Category::Undecided)
            && self
                .items
                .iter()
                .all(|d| d.code.category() != Category::Input)
    }
    /// The line index of [`Diagnostics::source`] (build it once for many lookups).
    pub fn index(&self) -> LineIndex {
        LineIndex::new(&self.source)
    }
    /// 1-based line and column (in characters) of a byte offset. Scans the source: for
    /// more than one lookup use [`Diagnostics::index`].
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        line_col(&self.source, offset)
    }
    /// The first [`MAX_RENDERED`] diagnostics rendered, separated by blank lines, then
    /// how many more there are, then a summary line.
    pub fn render(&self) -> String {
        let index = self.index();
        let mut out = String::new();
        for d in self.items.iter().take(MAX_RENDERED) {
            out.push_str(&self.render_one_with(&index, d));
            out.push('\n');
        }
        let n = self.items.len();
        if let Some(rest) = self.omitted() {
            let _ = writeln!(
                out,
                "error: {rest} more {} not shown (the first {MAX_RENDERED} are above; `rtcan check --json` lists all)",
                if rest == 1 { "error" } else { "errors" },
            );
        }
        let _ = writeln!(
            out,
            "error: {} {} in {}",
            n,
            if n == 1 { "error" } else { "errors" },
            self.file
        );
        out
    }

    /// How many diagnostics [`Diagnostics::render`] leaves out, if any.
    pub fn omitted(&self) -> Option<usize> {
        self.items
            .len()
            .checked_sub(MAX_RENDERED)
            .filter(|&n| n > 0)
    }

    /// One diagnostic, rustc style. Scans the source: for many, use
    /// [`Diagnostics::render_one_with`].
    pub fn render_one(&self, d: &Diagnostic) -> String {
        self.render_one_with(&self.index(), d)
    }

    /// One diagnostic, rustc style, positions looked up in `index` (of this source).
    pub fn render_one_with(&self, index: &LineIndex, d: &Diagnostic) -> String {
        let mut out = String::new();
        let _ = writeln!(out, "error[{}]: {}", d.code.name(), d.message);
        let mut gutter = 1;
        if let Some(span) = &d.span {
            let start = floor_char_boundary(&self.source, span.start.min(self.source.len()));
            let (line, col) = index.line_col(&self.source, start);
            gutter = line.to_string().len();
            let pad = " ".repeat(gutter);
            let _ = writeln!(out, "{pad}--> {}:{}:{}", self.file, line, col);
            let line_start = index.line_start(start).min(start);
            let text = line_text_from(&self.source, line_start);
            let _ = writeln!(out, "{pad} |");
            let _ = writeln!(out, "{line} | {}", clip(text));
            // Caret under the span, clipped to the first line of a multi-line span.
            let line_end = line_start + text.len();
            let end = span.end.clamp(start, line_end.max(start));
            let width = self
                .source
                .get(start..end)
                .map_or(1, |s| s.chars().count())
                .clamp(1, MAX_EXCERPT);
            if col <= MAX_EXCERPT {
                let _ = writeln!(out, "{pad} | {}{}", " ".repeat(col - 1), "^".repeat(width));
            }
        }
        let pad = " ".repeat(gutter);
        for h in &d.help {
            let _ = writeln!(out, "{pad} = help: {h}");
        }
        for n in &d.notes {
            let _ = writeln!(out, "{pad} = note: {n}");
        }
        out
    }
}

/// Longest excerpt line (characters) shown under a diagnostic: a 5 MB one-line file
/// must not be copied into every error.
const MAX_EXCERPT: usize = 240;

fn clip(text: &str) -> std::borrow::Cow<'_, str> {
    match text.char_indices().nth(MAX_EXCERPT) {
        Some((i, _)) => format!("{} ...", text.get(..i).unwrap_or("")).into(),
        None => text.into(),
    }
}

/// 1-based line and character column of a byte offset (clamped to the source). Scans
/// the source; [`LineIndex`] answers many lookups.
pub fn line_col(source: &str, offset: usize) -> (usize, usize) {
    let offset = floor_char_boundary(source, offset.min(source.len()));
    let before = source.get(..offset).unwrap_or("");
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let col = before.get(line_start..).map_or(0, |s| s.chars().count()) + 1;
    (line, col)
}

fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    while i > 0 && !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// The text of the line starting at byte `start`, without its newline.
fn line_text_from(source: &str, start: usize) -> &str {
    let rest = source.get(start..).unwrap_or("");
    let line = rest.split('\n').next().unwrap_or("");
    line.strip_suffix('\r').unwrap_or(line)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_rustc_style() {
        let src = "[bus]\nslots = 65\n".to_string();
        let d = Diagnostics {
            file: "robot.toml".into(),
            source: src,
            items: vec![
                Diagnostic::new(Code::TooManySlots, Some(14..16), "65 slots").help("at most 64"),
            ],
        };
        assert_eq!(
            d.render(),
            "error[too-many-slots]: 65 slots\n --> robot.toml:2:9\n  |\n2 | slots = 65\n  |         ^^\n  = help: at most 64\n\nerror: 1 error in robot.toml\n"
        );
    }

    #[test]
    fn line_col_counts_chars() {
        assert_eq!(line_col("a\nµb", 4), (2, 2));
        assert_eq!(line_col("abc", 99), (1, 4));
    }

    #[test]
    fn names_are_unique() {
        let mut names: Vec<_> = Code::ALL.iter().map(|c| c.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), Code::ALL.len());
    }
}
