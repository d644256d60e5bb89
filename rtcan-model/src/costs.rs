//! Per-path CPU cost tables (instructions per firmware path, RTIC priorities), the
//! input of the build-time timing check (`timing.rs`) and of the simulator's CPU model.
//! The tables are committed TOML files, embedded here so that build.rs and the proc macro
//! have them without reading files at build time: `boards/costs/cortex-m3.toml`, generated
//! by `scripts/update-costs.sh` from the QEMU rows of `bash boards/run-qemu.sh`, and
//! `rtcan-model/costs/cortex-m3-single-priority.toml` (the design before issue 10, in the
//! same format). Format: docs/ROBOT_TOML.md, "Timing check".
use crate::syntax::{self, Entry, Kind};

/// The firmware design of issue 10: slot timer on top doing only precomputed work.
pub const PRIORITISED_TOML: &str = include_str!("../../boards/costs/cortex-m3.toml");
/// The design before issue 10: every handler at one priority (kept for the before/after).
pub const SINGLE_PRIORITY_TOML: &str = include_str!("../costs/cortex-m3-single-priority.toml");

/// The paths a table must give, as named by `bash boards/run-qemu.sh`.
pub const PATHS: [&str; 7] = [
    "isr_slot_timer",
    "isr_can_rx",
    "isr_can_tx",
    "task_rx_process",
    "task_sync_slave",
    "task_prepare_slot",
    "slot_boundary_to_txrq",
];

/// Core clock when the table gives none: the STM32F103 at 72 MHz.
pub const DEFAULT_CPU_HZ: u32 = 72_000_000;
/// Cycles per instruction bound when the table gives none (issue 10): F103 flash at 72 MHz
/// has 2 wait states; the prefetch buffer hides them on straight-line code, taken
/// branches and literal loads do not.
pub const DEFAULT_CPI: f64 = 1.25;
/// Cortex-M3 exception entry (stacking), cycles, when the table gives none: instruction
/// counts do not see it.
pub const DEFAULT_IRQ_ENTRY_CYCLES: u32 = 12;
/// The monotonic's SysTick period when the table gives none (1 kHz).
pub const DEFAULT_SYSTICK_PERIOD_NS: u64 = 1_000_000;
/// Instructions of the SysTick handler when the table has no `systick` row: an ESTIMATE
/// (rtic-monotonics' handler: counter update and queue check), not a measurement.
pub const SYSTICK_ESTIMATE: u32 = 60;

/// Which firmware interrupt design a table describes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Design {
    /// Issue 10's design (slot timer on top, work in low-priority tasks). The default.
    Prioritised,
    /// Every handler at one priority (the firmware before issue 10).
    SinglePriority,
}

impl Design {
    /// Both designs, the default first.
    pub const ALL: [Design; 2] = [Design::Prioritised, Design::SinglePriority];

    /// Name used on the command line and in the table's `design` key.
    pub const fn name(self) -> &'static str {
        match self {
            Design::Prioritised => "prioritised",
            Design::SinglePriority => "single-priority",
        }
    }

    /// Parses a design name; `new` and `old` are accepted as aliases.
    pub fn from_name(name: &str) -> Option<Design> {
        match name {
            "new" => Some(Design::Prioritised),
            "old" => Some(Design::SinglePriority),
            _ => Design::ALL.into_iter().find(|d| d.name() == name),
        }
    }

    /// The embedded cost table of this design.
    pub fn table(self) -> Result<CostTable, String> {
        let mut t = match self {
            Design::Prioritised => CostTable::parse(PRIORITISED_TOML),
            Design::SinglePriority => CostTable::parse(SINGLE_PRIORITY_TOML),
        }?;
        if t.design.is_empty() {
            // The generated table is the firmware's own design; it does not name it.
            t.design = self.name().to_string();
        }
        Ok(t)
    }
}

/// One measured path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathCost {
    /// Largest instruction count seen.
    pub max: u32,
    /// Mean instruction count.
    pub mean: u32,
    /// Samples behind max/mean (0: not measured, taken from a goal or a derivation).
    pub samples: u64,
    /// RTIC logical priority the path runs at (higher preempts lower); `None` for
    /// `slot_boundary_to_txrq`, which is a latency, not a handler.
    pub priority: Option<u8>,
    /// A task row whose work the design runs inside this interrupt handler instead of a
    /// task of its own (the single-priority design: reassembly and sync inside the RX
    /// interrupt). Its cost then adds to that handler's.
    pub runs_in: Option<&'static str>,
}

/// A cost table.
#[derive(Clone, Debug, PartialEq)]
pub struct CostTable {
    /// Design name (`design`; empty when not given).
    pub design: String,
    /// Where the figures come from (`source`, else the measured robot).
    pub source: String,
    /// Core clock the figures are for, Hz (`cpu_hz`, default 72 MHz).
    pub clock_hz: u32,
    /// Cycles per instruction bound.
    pub cpi: f64,
    /// Exception entry, cycles.
    pub irq_entry_cycles: u32,
    /// SysTick period, ns.
    pub systick_period_ns: u64,
    /// Paths by name, in file order.
    pub paths: Vec<(String, PathCost)>,
}

impl CostTable {
    /// Parses a table; every path of [`PATHS`] must be present with a priority, every
    /// value in range. Table-wide keys (`design`, `source`, `cpu_hz`, `cpi`,
    /// `irq_entry_cycles`, `systick_period_ns`) sit at the top or in `[meta]`; a handler
    /// row's priority is its own `priority` key or comes from `[priorities]` (`task_*`
    /// rows from `task_protocol`).
    pub fn parse(text: &str) -> Result<CostTable, String> {
        let root = syntax::parse(text).map_err(|e| e.first_line())?;
        let Kind::Table(top) = root.kind else {
            return Err("a cost table is a TOML table".into());
        };
        let empty = Vec::new();
        let meta = match find(&top, "meta") {
            Some(Kind::Table(m)) => m,
            Some(_) => return Err("cost table: `meta` must be a table".into()),
            None => &empty,
        };
        let prios = match find(&top, "priorities") {
            Some(Kind::Table(p)) => p,
            Some(_) => return Err("cost table: `priorities` must be a table".into()),
            None => &empty,
        };
        let Some(Kind::Table(paths)) = find(&top, "paths") else {
            return Err("cost table: `[paths]` missing".into());
        };
        // A table-wide key, in `[meta]` or at the top.
        let key = |k: &str| find(meta, k).or_else(|| find(&top, k));
        let opt_str = |k: &str| match key(k) {
            None => Ok(None),
            Some(Kind::Str(s)) => Ok(Some(s.clone())),
            Some(_) => Err(format!("cost table: `{k}` must be a string")),
        };
        let opt_int = |k: &str, lo: i64, hi: i64| match key(k) {
            None => Ok(None),
            Some(Kind::Int(v)) if (lo..=hi).contains(v) => Ok(Some(*v)),
            Some(_) => Err(format!(
                "cost table: `{k}` must be an integer in {lo}..={hi}"
            )),
        };
        let clock_hz =
            opt_int("cpu_hz", 1_000_000, 1_000_000_000)?.map_or(DEFAULT_CPU_HZ, |v| v as u32);
        let cpi = match key("cpi") {
            None => DEFAULT_CPI,
            Some(Kind::Float(v)) if (0.5..=10.0).contains(v) => *v,
            Some(Kind::Int(v)) if (1..=10).contains(v) => *v as f64,
            Some(_) => return Err("cost table: `cpi` must be a number in 0.5..=10".into()),
        };
        let prio_of = |k: &str| match find(prios, k) {
            Some(Kind::Int(v)) if (0..=255).contains(v) => Ok(Some(*v as u8)),
            Some(_) => Err(format!("cost table: `priorities.{k}` must be in 0..=255")),
            None => Ok(None),
        };
        let mut out = Vec::new();
        for e in paths {
            let Kind::Table(p) = &e.value.kind else {
                return Err(format!("cost table: `paths.{}` must be a table", e.key));
            };
            let num = |k: &str| match find(p, k) {
                Some(Kind::Int(v)) if *v >= 0 => Ok(*v),
                _ => Err(format!(
                    "cost table: `paths.{}.{k}` must be a non-negative integer",
                    e.key
                )),
            };
            let priority = match find(p, "priority") {
                Some(Kind::Int(v)) if (0..=255).contains(v) => Some(*v as u8),
                Some(_) => {
                    return Err(format!(
                        "cost table: `paths.{}.priority` must be in 0..=255",
                        e.key
                    ))
                }
                None if e.key.starts_with("task_") => prio_of("task_protocol")?,
                None if e.key.starts_with("isr_") || e.key == "systick" => prio_of(&e.key)?,
                None => None,
            };
            let handler =
                e.key.starts_with("isr_") || e.key.starts_with("task_") || e.key == "systick";
            if handler && priority.is_none() {
                return Err(format!("cost table: path `{}` needs a priority", e.key));
            }
            let runs_in = match find(p, "runs_in") {
                None => None,
                Some(Kind::Str(h)) => match PATHS.iter().find(|n| *n == h) {
                    Some(n) if n.starts_with("isr_") => Some(*n),
                    _ => {
                        return Err(format!(
                            "cost table: `paths.{}.runs_in` must name an isr_ path",
                            e.key
                        ))
                    }
                },
                Some(_) => {
                    return Err(format!(
                        "cost table: `paths.{}.runs_in` must be a string",
                        e.key
                    ))
                }
            };
            let max = u32::try_from(num("max")?).map_err(|e| e.to_string())?;
            let mean = u32::try_from(num("mean")?).map_err(|e| e.to_string())?;
            if mean > max {
                return Err(format!("cost table: `paths.{}`: mean above max", e.key));
            }
            out.push((
                e.key.clone(),
                PathCost {
                    max,
                    mean,
                    samples: num("samples")? as u64,
                    priority,
                    runs_in,
                },
            ));
        }
        for name in PATHS {
            if !out.iter().any(|(n, _)| n == name) {
                return Err(format!("cost table: path `{name}` missing"));
            }
        }
        if !out.iter().any(|(n, _)| n == "systick") {
            let priority = prio_of("systick")?
                .ok_or("cost table: no `systick` row and no `priorities.systick`")?;
            out.push((
                "systick".into(),
                PathCost {
                    max: SYSTICK_ESTIMATE,
                    mean: SYSTICK_ESTIMATE,
                    samples: 0,
                    priority: Some(priority),
                    runs_in: None,
                },
            ));
        }
        let source = match opt_str("source")? {
            Some(s) => s,
            None => format!(
                "QEMU -icount over {} (scripts/update-costs.sh)",
                opt_str("robot")?.unwrap_or_else(|| "?".into())
            ),
        };
        Ok(CostTable {
            design: opt_str("design")?.unwrap_or_default(),
            source,
            clock_hz,
            cpi,
            irq_entry_cycles: opt_int("irq_entry_cycles", 0, 1000)?
                .map_or(DEFAULT_IRQ_ENTRY_CYCLES, |v| v as u32),
            systick_period_ns: opt_int("systick_period_ns", 1_000, 1_000_000_000)?
                .map_or(DEFAULT_SYSTICK_PERIOD_NS, |v| v as u64),
            paths: out,
        })
    }

    /// A path by name (every name of [`PATHS`] is present in a parsed table).
    pub fn path(&self, name: &str) -> PathCost {
        self.paths.iter().find(|(n, _)| n == name).map_or(
            PathCost {
                max: 0,
                mean: 0,
                samples: 0,
                priority: None,
                runs_in: None,
            },
            |(_, p)| *p,
        )
    }

    /// Priority of a handler path (0 for an unknown one).
    pub fn priority(&self, name: &str) -> u8 {
        self.path(name).priority.unwrap_or(0)
    }

    /// Instructions of one activation of handler `isr`, with the longest task row the
    /// design runs inside it (`runs_in`).
    pub fn handler_max(&self, isr: &str) -> u32 {
        let inline = self
            .paths
            .iter()
            .filter(|(_, p)| p.runs_in == Some(isr))
            .map(|(_, p)| p.max)
            .max()
            .unwrap_or(0);
        self.path(isr).max.saturating_add(inline)
    }

    /// Cycles of `instructions` at this table's CPI bound.
    pub fn cycles(&self, instructions: u32) -> f64 {
        f64::from(instructions) * self.cpi
    }

    /// The same table with another CPI bound (the simulator's `--cpi`).
    pub fn with_cpi(mut self, cpi: f64) -> CostTable {
        self.cpi = cpi;
        self
    }
}

fn find<'a>(entries: &'a [Entry], key: &str) -> Option<&'a Kind> {
    entries.iter().find(|e| e.key == key).map(|e| &e.value.kind)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_tables_parse_with_every_path() {
        for d in Design::ALL {
            let t = d.table().unwrap();
            for p in PATHS.iter().chain(&["systick"]) {
                assert!(t.paths.iter().any(|(n, _)| n == p), "{p}");
            }
            assert_eq!(t.clock_hz, 72_000_000);
            assert_eq!(t.cpi, DEFAULT_CPI);
            assert_eq!(t.irq_entry_cycles, 12);
        }
        let new = Design::Prioritised.table().unwrap();
        assert!(new.priority("isr_slot_timer") > new.priority("isr_can_rx"));
        assert!(new.priority("isr_can_rx") > new.priority("task_rx_process"));
        assert!(new.priority("task_rx_process") > new.priority("systick"));
        assert_eq!(new.path("slot_boundary_to_txrq").priority, None);
        assert_eq!(new.path("systick").samples, 0, "SysTick is not measured");
        assert_eq!(new.handler_max("isr_can_rx"), new.path("isr_can_rx").max);
        let old = Design::SinglePriority.table().unwrap();
        assert_eq!(old.design, "single-priority");
        assert_eq!(old.handler_max("isr_can_rx"), 3766 + 2497 + 1402);
        assert_eq!(old.path("task_sync_slave").runs_in, Some("isr_can_rx"));
        assert_eq!(old.priority("isr_slot_timer"), old.priority("isr_can_rx"));
        assert!(old.priority("systick") > old.priority("isr_slot_timer"));
    }

    const MINIMAL: &str = "[meta]\ncpu_hz = 72000000\n[priorities]\nisr_slot_timer = 4\nisr_can_rx = 3\nisr_can_tx = 3\ntask_protocol = 2\nsystick = 0\n[paths.isr_slot_timer]\nmax = 100\nmean = 50\nsamples = 1\n[paths.isr_can_rx]\nmax = 70\nmean = 70\nsamples = 1\n[paths.isr_can_tx]\nmax = 50\nmean = 50\nsamples = 1\n[paths.task_rx_process]\nmax = 600\nmean = 300\nsamples = 1\n[paths.task_sync_slave]\nmax = 900\nmean = 900\nsamples = 1\n[paths.task_prepare_slot]\nmax = 300\nmean = 100\nsamples = 1\n[paths.slot_boundary_to_txrq]\nmax = 80\nmean = 40\nsamples = 1\n";

    #[test]
    fn bad_tables_are_errors_not_panics() {
        let good = CostTable::parse(MINIMAL).unwrap();
        assert_eq!(good.priority("task_sync_slave"), 2, "from task_protocol");
        assert_eq!(good.source, "QEMU -icount over ? (scripts/update-costs.sh)");
        assert!(CostTable::parse("not toml [").is_err());
        let no_rx = MINIMAL.replace("[paths.isr_can_rx]", "[paths.isr_can_rx_typo]");
        assert_eq!(
            CostTable::parse(&no_rx).unwrap_err(),
            "cost table: path `isr_can_rx_typo` needs a priority"
        );
        let no_sync = MINIMAL.replace("[paths.task_sync_slave]", "[paths.task_sync]");
        assert_eq!(
            CostTable::parse(&no_sync).unwrap_err(),
            "cost table: path `task_sync_slave` missing"
        );
        let no_prio = MINIMAL.replace("task_protocol = 2\n", "");
        assert_eq!(
            CostTable::parse(&no_prio).unwrap_err(),
            "cost table: path `task_rx_process` needs a priority"
        );
        // The same kind of table with the table-wide keys at the top and a priority per row.
        let flat = "design = \"d\"\nsource = \"s\"\ncpi = 2.0\n[paths.isr_slot_timer]\nmax = 1\nmean = 1\nsamples = 1\npriority = 4\n[paths.isr_can_rx]\nmax = 1\nmean = 1\nsamples = 1\npriority = 3\n[paths.isr_can_tx]\nmax = 1\nmean = 1\nsamples = 1\npriority = 3\n[paths.task_rx_process]\nmax = 1\nmean = 1\nsamples = 1\npriority = 2\n[paths.task_sync_slave]\nmax = 1\nmean = 1\nsamples = 1\npriority = 2\n[paths.task_prepare_slot]\nmax = 1\nmean = 1\nsamples = 1\npriority = 2\n[paths.slot_boundary_to_txrq]\nmax = 1\nmean = 1\nsamples = 1\n[paths.systick]\nmax = 5\nmean = 5\nsamples = 0\npriority = 1\n";
        let t = CostTable::parse(flat).unwrap();
        assert_eq!(
            (t.design.as_str(), t.source.as_str(), t.cpi, t.clock_hz),
            ("d", "s", 2.0, 72_000_000)
        );
        assert_eq!(
            (t.priority("task_sync_slave"), t.path("systick").max),
            (2, 5)
        );
        let no_systick = flat.replace("[paths.systick]", "[paths.other]");
        assert_eq!(
            CostTable::parse(&no_systick).unwrap_err(),
            "cost table: no `systick` row and no `priorities.systick`"
        );
        let neg = MINIMAL.replace("max = 70", "max = -70");
        assert!(CostTable::parse(&neg)
            .unwrap_err()
            .contains("isr_can_rx.max"));
        let mean_above = MINIMAL.replace("max = 70", "max = 10");
        assert!(CostTable::parse(&mean_above)
            .unwrap_err()
            .contains("mean above max"));
        let cpi = MINIMAL.replace("cpu_hz = 72000000\n", "cpu_hz = 72000000\ncpi = 0.0\n");
        assert!(CostTable::parse(&cpi).unwrap_err().contains("cpi"));
        let bad_hz = MINIMAL.replace("cpu_hz = 72000000\n", "cpu_hz = 5\n");
        assert!(CostTable::parse(&bad_hz).unwrap_err().contains("cpu_hz"));
        let runs_in = MINIMAL.replace("max = 600\n", "max = 600\nruns_in = \"task_rx_process\"\n");
        assert!(CostTable::parse(&runs_in).unwrap_err().contains("runs_in"));
        assert_eq!(Design::from_name("old"), Some(Design::SinglePriority));
        assert_eq!(Design::from_name("prioritised"), Some(Design::Prioritised));
        assert_eq!(Design::from_name("fast"), None);
    }
}
