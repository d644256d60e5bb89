//! Diagnostics: structured (code, message, byte span, help) for the proc macro, and
//! rendered rustc-style (`file:line:col`, excerpt, caret, help) for the CLI and build.rs.
use std::fmt::Write as _;
use std::ops::Range;

/// Byte range in the robot.toml source.
pub type Span = Range<usize>;

/// Whether an error makes the input invalid, or only the robot not schedulable.
/// `rtcan check` exits 2 for the first and 1 for the second.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Category {
    /// The description is malformed or inconsistent.
    Input,
    /// The description is well formed but the bus cannot carry it in time.
    Schedule,
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
    /// The admission search hit its step budget.
    AdmissionTooHard = "admission-too-hard", Schedule;
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
    /// 1-based line and column (in characters) of a byte offset.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        line_col(&self.source, offset)
    }
    /// Every diagnostic rendered, separated by blank lines, plus a summary line.
    pub fn render(&self) -> String {
        let mut out = String::new();
        for d in &self.items {
            out.push_str(&self.render_one(d));
            out.push('\n');
        }
        let n = self.items.len();
        let _ = writeln!(
            out,
            "error: {} {} in {}",
            n,
            if n == 1 { "error" } else { "errors" },
            self.file
        );
        out
    }

    /// One diagnostic, rustc style.
    pub fn render_one(&self, d: &Diagnostic) -> String {
        let mut out = String::new();
        let _ = writeln!(out, "error[{}]: {}", d.code.name(), d.message);
        let mut gutter = 1;
        if let Some(span) = &d.span {
            let start = span.start.min(self.source.len());
            let (line, col) = self.line_col(start);
            gutter = line.to_string().len();
            let pad = " ".repeat(gutter);
            let _ = writeln!(out, "{pad}--> {}:{}:{}", self.file, line, col);
            let text = line_text(&self.source, start);
            let _ = writeln!(out, "{pad} |");
            let _ = writeln!(out, "{line} | {text}");
            // Caret under the span, clipped to the first line of a multi-line span.
            let line_start = start - (col_bytes(&self.source, start));
            let line_end = line_start + text.len();
            let end = span.end.clamp(start, line_end.max(start));
            let width = self
                .source
                .get(start..end)
                .map_or(1, |s| s.chars().count())
                .max(1);
            let _ = writeln!(out, "{pad} | {}{}", " ".repeat(col - 1), "^".repeat(width));
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

/// Bytes from the start of the line to `offset`.
fn col_bytes(source: &str, offset: usize) -> usize {
    let before = source.get(..offset).unwrap_or(source);
    before.len() - before.rfind('\n').map_or(0, |i| i + 1)
}

/// 1-based line and character column of a byte offset (clamped to the source).
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

/// The text of the line holding `offset`, without its newline.
fn line_text(source: &str, offset: usize) -> &str {
    let offset = floor_char_boundary(source, offset.min(source.len()));
    let start = source
        .get(..offset)
        .and_then(|s| s.rfind('\n'))
        .map_or(0, |i| i + 1);
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
