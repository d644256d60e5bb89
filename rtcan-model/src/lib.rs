//! The robot model: robot.toml parsed once with spans, validated (every error collected),
//! planned (HRT admission through rtcan-core, message IDs, CAN filter banks, calendars,
//! bus load, fingerprint) and reported. The proc macro, build.rs, the simulator and the
//! `rtcan` CLI all go through [`analyze`] / [`Robot::load`]: no rule lives twice.
//!
//! The schema is documented in `docs/ROBOT_TOML.md`.
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::indexing_slicing,
        clippy::panic
    )
)]

pub mod bridge_keys;
pub mod chains;
pub mod compat;
pub mod costs;
pub mod diag;
pub mod filters;
pub mod fingerprint;
pub mod ids;
pub mod lock;
pub mod model;
pub mod module_state;
pub mod names;
pub mod params;
pub mod plan;
pub mod report;
pub mod schedule;
pub mod services;
pub mod supervision;
pub mod syntax;
pub mod timing;
pub mod units;
pub mod validate;

pub use diag::{Category, Code, Diagnostic, Diagnostics, Span};
pub use model::{Board, FieldType, FilterMode, Model, MsgType, Prim};
pub use plan::{BusPlan, Load, ModulePlan, ModuleTables, Plan, SubscriberPlan, TopicPlan};

use std::path::Path;

/// Outcome of checking a robot.toml.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Valid and admissible: a plan exists.
    Admissible,
    /// Valid, but the bus cannot carry it (only schedule errors).
    NotAdmissible,
    /// Invalid input.
    Invalid,
    /// Valid input, but the admission search ran out of budget before deciding.
    Undecided,
}

impl Status {
    /// `rtcan check` exit code: 0, 1, 2, 3 (docs/ROBOT_TOML.md).
    pub const fn exit_code(self) -> i32 {
        match self {
            Status::Admissible => 0,
            Status::NotAdmissible => 1,
            Status::Invalid => 2,
            Status::Undecided => 3,
        }
    }
    /// The `status` field of `rtcan check --json`.
    pub const fn name(self) -> &'static str {
        match self {
            Status::Admissible => "admissible",
            Status::NotAdmissible => "not-admissible",
            Status::Invalid => "invalid",
            Status::Undecided => "undecided",
        }
    }
}

/// Everything one check produced.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// The validated model (present when there is no input error).
    pub model: Option<Model>,
    /// The plan (present when there is no error at all).
    pub plan: Option<Plan>,
    /// All errors.
    pub diagnostics: Diagnostics,
}

impl Analysis {
    /// Admissible, not admissible, or invalid.
    pub fn status(&self) -> Status {
        if self.plan.is_some() && self.diagnostics.is_empty() {
            Status::Admissible
        } else if self.model.is_some() && self.diagnostics.undecided() {
            Status::Undecided
        } else if self.model.is_some() && self.diagnostics.only_schedule() {
            Status::NotAdmissible
        } else {
            Status::Invalid
        }
    }
}

/// Parses, validates and plans `source` (named `file` in diagnostics). Never panics.
pub fn analyze(file: &str, source: &str) -> Analysis {
    analyze_locked(file, source, None)
}

/// [`analyze`] with the robot.lock text (`(file name, text)`), whose allocation is kept.
pub fn analyze_locked(file: &str, source: &str, lock: Option<(&str, &str)>) -> Analysis {
    let mut items = Vec::new();
    let lock = match lock.map(|(f, t)| lock::parse(f, t)) {
        Some(Ok(l)) => Some(l),
        Some(Err(d)) => {
            items.push(d);
            None
        }
        None => None,
    };
    let mut model = None;
    let mut plan = None;
    match syntax::parse(source) {
        Err(e) => {
            // A repeated table or key is a TOML error; it gets the duplicate-name code.
            let d = match e.message.lines().find(|l| l.contains("duplicate key")) {
                Some(line) => Diagnostic::new(
                    Code::DuplicateName,
                    e.span,
                    line.trim().replace("`\"", "`").replace("\"`", "`"),
                )
                .help("every type, module, node and topic name must be unique"),
                None if too_deep(&e.message, e.span.as_ref(), source) => Diagnostic::new(
                    Code::TooDeep,
                    e.span.clone(),
                    format!("tables or arrays nested deeper than the TOML parser accepts ({})", e.first_line()),
                )
                .help("robot.toml needs at most 4 levels (e.g. `[topics.x]` with `subscribers = [{ node = \"n\" }]`)"),
                None => Diagnostic::new(Code::TomlSyntax, e.span.clone(), e.first_line()),
            };
            items.push(d);
        }
        Ok(root) => {
            model = validate::validate(&root, &mut items);
            if let (Some(m), syntax::Kind::Table(entries)) = (&mut model, &root.kind) {
                m.bridge = bridge_keys::validate(file, entries, m, &mut items);
            }
            if let (Some(m), syntax::Kind::Table(entries)) = (&mut model, &root.kind) {
                m.params = params::validate(entries, m, &mut items);
            }
            if let (Some(m), syntax::Kind::Table(entries)) = (&mut model, &root.kind) {
                services::validate(entries, m, &mut items);
                // After the services: their topics keep their IDs.
                m.module_state = module_state::append(entries, m, &mut items);
            }
            if let Some(m) = &model {
                plan = plan::build_locked(m, file, lock.as_ref(), &mut items);
                if let (Some(p), syntax::Kind::Table(entries)) = (&mut plan, &root.kind) {
                    // Before `timing`: the heartbeat period is part of each module's load.
                    let (bitrate, cycle) = (p.bus.bitrate, p.bus.cycle_ns);
                    p.supervision = supervision::validate(entries, m, bitrate, cycle, &mut items);
                }
                if let Some(p) = &mut plan {
                    timing::check(m, p, &mut items);
                    if let syntax::Kind::Table(entries) = &root.kind {
                        p.chains = chains::check(entries, m, p, &mut items);
                    }
                }
            }
            if !items.is_empty() {
                plan = None;
            }
        }
    }
    Analysis {
        model,
        plan,
        diagnostics: Diagnostics {
            file: file.to_string(),
            source: source.to_string(),
            items,
        },
    }
}

/// Reads `path` (named `shown` in diagnostics) and its robot.lock when there is one
/// ([`lock::path_for`]), and analyzes them: what build.rs, `rtcan::robot!`, the CLI and
/// [`Robot::load`] all do, so they get the same allocation.
pub fn read_analysis(path: &Path, shown: &str) -> Analysis {
    let source = match read_source(path, shown) {
        Ok(s) => s,
        Err(diagnostics) => {
            return Analysis {
                model: None,
                plan: None,
                diagnostics,
            }
        }
    };
    let lock_path = lock::path_for(path);
    let lock_shown = lock::path_for(Path::new(shown)).display().to_string();
    match lock_path
        .exists()
        .then(|| read_source(&lock_path, &lock_shown))
    {
        None => analyze(shown, &source),
        Some(Ok(text)) => analyze_locked(shown, &source, Some((&lock_shown, &text))),
        Some(Err(d)) => Analysis {
            model: None,
            plan: None,
            diagnostics: Diagnostics {
                file: shown.to_string(),
                source,
                items: d.items,
            },
        },
    }
}

/// Largest robot description read (16 MiB; the Triskar2 robot is 5 KiB): `rtcan check
/// /dev/zero` stops here instead of reading without limit.
pub const MAX_SOURCE_BYTES: u64 = 16 * 1024 * 1024;

/// Reads a robot description for diagnostics naming it `file`: at most
/// [`MAX_SOURCE_BYTES`] (`file-too-large`), UTF-8 (`invalid-utf8` with the byte offset,
/// line and column of the first bad byte), or `io`.
pub fn read_source(path: &Path, file: &str) -> Result<String, Diagnostics> {
    use std::io::Read as _;
    let fail = |source: String, d: Diagnostic| Diagnostics {
        file: file.to_string(),
        source,
        items: vec![d],
    };
    let mut bytes = Vec::new();
    let read = std::fs::File::open(path)
        .and_then(|f| f.take(MAX_SOURCE_BYTES + 1).read_to_end(&mut bytes));
    if let Err(e) = read {
        return Err(fail(
            String::new(),
            Diagnostic::new(Code::Io, None, format!("cannot read `{file}`: {e}")),
        ));
    }
    if bytes.len() as u64 > MAX_SOURCE_BYTES {
        return Err(fail(
            String::new(),
            Diagnostic::new(
                Code::FileTooLarge,
                None,
                format!(
                    "`{file}` is larger than {} MiB",
                    MAX_SOURCE_BYTES / (1024 * 1024)
                ),
            )
            .help("a robot description is a few KiB; is this the right file?"),
        ));
    }
    match String::from_utf8(bytes) {
        Ok(s) => Ok(s),
        Err(e) => {
            let at = e.utf8_error().valid_up_to();
            // The text up to the bad byte is valid, so offsets agree with the lossy copy
            // that is kept for the excerpt.
            let source = String::from_utf8_lossy(e.as_bytes()).into_owned();
            let (line, col) = diag::line_col(&source, at);
            Err(fail(
                source,
                Diagnostic::new(
                    Code::InvalidUtf8,
                    Some(at..at + 1),
                    format!("invalid UTF-8 at byte {at} (line {line}, column {col})"),
                )
                .help("robot.toml must be UTF-8 text"),
            ))
        }
    }
}

/// Whether a TOML error comes from nesting: toml_edit says "recursion limit exceeded"
/// for deep arrays and inline tables, but only "invalid table header" for a header with
/// too many dotted keys (more than [`MAX_HEADER_KEYS`] on the error's line).
fn too_deep(message: &str, span: Option<&Span>, source: &str) -> bool {
    if message.contains("recursion limit") {
        return true;
    }
    if !message.contains("invalid table header") {
        return false;
    }
    let at = span.map_or(0, |s| s.start).min(source.len());
    let start = source
        .get(..at)
        .and_then(|s| s.rfind('\n'))
        .map_or(0, |i| i + 1);
    let line = source
        .get(start..)
        .and_then(|s| s.lines().next())
        .unwrap_or("");
    line.matches('.').count() + 1 > MAX_HEADER_KEYS
}

/// Dotted keys in one table header beyond which a header error is reported as nesting.
const MAX_HEADER_KEYS: usize = 64;

/// Entry point for users of the model.
pub struct Robot;

impl Robot {
    /// Reads and plans a robot.toml; diagnostics name the file as given.
    pub fn load(path: impl AsRef<Path>) -> Result<Plan, Diagnostics> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let a = read_analysis(path, &file);
        match a.plan {
            Some(plan) if a.diagnostics.is_empty() => Ok(plan),
            _ => Err(a.diagnostics),
        }
    }

    /// Plans robot.toml text.
    pub fn parse(file: &str, source: &str) -> Result<Plan, Diagnostics> {
        let a = analyze(file, source);
        match a.plan {
            Some(plan) if a.diagnostics.is_empty() => Ok(plan),
            _ => Err(a.diagnostics),
        }
    }
}
