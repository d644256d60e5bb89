//! Per-path CPU cost tables (instructions per firmware path, RTIC priorities, CPI bound),
//! the input of the build-time timing check (`timing.rs`) and of the simulator's CPU
//! model. The tables are committed TOML files under `rtcan-model/costs/`, embedded here
//! so that build.rs and the proc macro have them without reading files at build time.
//! Format: docs/ROBOT_TOML.md, "Timing check".
use crate::syntax::{self, Entry, Kind};

/// The firmware design of issue 10: slot timer on top doing only precomputed work.
pub const PRIORITISED_TOML: &str = include_str!("../costs/cortex-m3.toml");
/// The design before issue 10: every handler at one priority (kept for the before/after).
pub const SINGLE_PRIORITY_TOML: &str = include_str!("../costs/cortex-m3-single-priority.toml");

/// The paths a table must give, as named by `bash boards/run-qemu.sh` (plus `systick`).
pub const PATHS: [&str; 8] = [
    "isr_slot_timer",
    "isr_can_rx",
    "isr_can_tx",
    "task_rx_process",
    "task_sync_slave",
    "task_prepare_slot",
    "slot_boundary_to_txrq",
    "systick",
];

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
        match self {
            Design::Prioritised => CostTable::parse(PRIORITISED_TOML),
            Design::SinglePriority => CostTable::parse(SINGLE_PRIORITY_TOML),
        }
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
    /// Design name (`design` key).
    pub design: String,
    /// Where the figures come from (`source` key).
    pub source: String,
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
    /// Parses a table; every path of [`PATHS`] must be present, every value in range.
    pub fn parse(text: &str) -> Result<CostTable, String> {
        let root = syntax::parse(text).map_err(|e| e.first_line())?;
        let Kind::Table(top) = root.kind else {
            return Err("a cost table is a TOML table".into());
        };
        let str_key = |k: &str| match find(&top, k) {
            Some(Kind::Str(s)) => Ok(s.clone()),
            _ => Err(format!("cost table: `{k}` must be a string")),
        };
        let int_key = |k: &str, lo: i64, hi: i64| match find(&top, k) {
            Some(Kind::Int(v)) if (lo..=hi).contains(v) => Ok(*v),
            _ => Err(format!(
                "cost table: `{k}` must be an integer in {lo}..={hi}"
            )),
        };
        let cpi = match find(&top, "cpi") {
            Some(Kind::Float(v)) if (0.5..=10.0).contains(v) => *v,
            Some(Kind::Int(v)) if (1..=10).contains(v) => *v as f64,
            _ => return Err("cost table: `cpi` must be a number in 0.5..=10".into()),
        };
        let Some(Kind::Table(paths)) = find(&top, "paths") else {
            return Err("cost table: `[paths]` missing".into());
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
                None => None,
                Some(Kind::Int(v)) if (0..=255).contains(v) => Some(*v as u8),
                Some(_) => {
                    return Err(format!(
                        "cost table: `paths.{}.priority` must be in 0..=255",
                        e.key
                    ))
                }
            };
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
            match out.iter().find(|(n, _)| n == name) {
                None => return Err(format!("cost table: path `{name}` missing")),
                Some((_, p)) if p.priority.is_none() && name != "slot_boundary_to_txrq" => {
                    return Err(format!("cost table: path `{name}` needs a `priority`"));
                }
                _ => {}
            }
        }
        Ok(CostTable {
            design: str_key("design")?,
            source: str_key("source")?,
            cpi,
            irq_entry_cycles: int_key("irq_entry_cycles", 0, 1000)? as u32,
            systick_period_ns: int_key("systick_period_ns", 1_000, 1_000_000_000)? as u64,
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
            assert_eq!(t.design, d.name());
            for p in PATHS {
                assert!(t.paths.iter().any(|(n, _)| n == p), "{p}");
            }
        }
        let new = Design::Prioritised.table().unwrap();
        assert_eq!(new.cpi, 1.25);
        assert!(new.priority("isr_slot_timer") > new.priority("isr_can_rx"));
        let old = Design::SinglePriority.table().unwrap();
        assert_eq!(old.handler_max("isr_can_rx"), 3766 + 2497 + 1402);
        assert_eq!(old.path("task_sync_slave").runs_in, Some("isr_can_rx"));
        assert_eq!(new.handler_max("isr_can_rx"), 150);
        assert_eq!(old.priority("isr_slot_timer"), old.priority("isr_can_rx"));
    }

    #[test]
    fn bad_tables_are_errors_not_panics() {
        let good = PRIORITISED_TOML;
        assert!(CostTable::parse("not toml [").is_err());
        let no_rx = good.replace("[paths.isr_can_rx]", "[paths.isr_can_rx_typo]");
        assert_eq!(
            CostTable::parse(&no_rx).unwrap_err(),
            "cost table: path `isr_can_rx` missing"
        );
        let neg = good.replace("max = 150", "max = -150");
        assert!(CostTable::parse(&neg)
            .unwrap_err()
            .contains("isr_can_rx.max"));
        let mean_above = good.replace("max = 150", "max = 10");
        assert!(CostTable::parse(&mean_above)
            .unwrap_err()
            .contains("mean above max"));
        let cpi = good.replace("cpi = 1.25", "cpi = 0.0");
        assert!(CostTable::parse(&cpi).unwrap_err().contains("cpi"));
        let runs_in = good.replace(
            "priority = 1\n",
            "priority = 1\nruns_in = \"task_rx_process\"\n",
        );
        assert!(CostTable::parse(&runs_in).unwrap_err().contains("runs_in"));
        assert_eq!(Design::from_name("old"), Some(Design::SinglePriority));
        assert_eq!(Design::from_name("prioritised"), Some(Design::Prioritised));
        assert_eq!(Design::from_name("fast"), None);
    }
}
