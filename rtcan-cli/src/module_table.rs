//! The module table of a supervised robot as `rtcan monitor` shows it: the last
//! `module_state_<module>` message seen on the bus (docs/SERVICES.md §1), decoded by the
//! plan's `ModuleState` layout (one array per column, indexed by module).
use std::fmt::Write as _;

use serde_json::Value;

/// One module's row.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Row {
    pub name: String,
    pub alive: bool,
    pub heard: bool,
    pub state: u64,
    pub age: u64,
    pub fingerprint: u64,
    pub tec: u64,
    pub rec: u64,
    pub bus_off: u64,
    pub rx_overrun: u64,
    pub deadline_missed: u64,
}

/// The table as last received.
#[derive(Clone, Debug, PartialEq)]
pub struct TableView {
    /// Bus time of the message, s.
    pub time_s: f64,
    /// Module that published it, and the sync master it follows.
    pub reporter: String,
    pub sync_master: String,
    pub rows: Vec<Row>,
}

fn name(names: &[String], i: u64) -> String {
    usize::try_from(i)
        .ok()
        .and_then(|i| names.get(i))
        .cloned()
        .unwrap_or_else(|| format!("#{i}"))
}

/// From a `ModuleState` value (`rtcan_host::value::to_json`); `None` if a column is
/// missing or shorter than the module list.
pub fn from_json(v: &Value, names: &[String], time_ns: u64) -> Option<TableView> {
    let scalar = |k: &str| v.get(k).and_then(Value::as_u64);
    let col = |k: &str, i: usize| {
        v.get(k)
            .and_then(Value::as_array)
            .and_then(|a| a.get(i))
            .and_then(Value::as_u64)
    };
    let rows = (0..names.len())
        .map(|i| {
            let flags = col("flags", i)?;
            Some(Row {
                name: name(names, i as u64),
                alive: flags & 1 != 0,
                heard: flags & 2 != 0,
                state: col("state", i)?,
                age: col("age", i)?,
                fingerprint: col("fingerprint", i)?,
                tec: col("tec", i)?,
                rec: col("rec", i)?,
                bus_off: col("bus_off", i)?,
                rx_overrun: col("rx_overrun", i)?,
                deadline_missed: col("deadline_missed", i)?,
            })
        })
        .collect::<Option<Vec<Row>>>()?;
    Some(TableView {
        time_s: time_ns as f64 * 1e-9,
        reporter: name(names, scalar("reporter")?),
        sync_master: name(names, scalar("sync_master")?),
        rows,
    })
}

/// The plain-text section `rtcan monitor` prints after its tables.
pub fn render(t: &TableView) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\nMODULE TABLE from {} (sync master {}) at {:.3} s",
        t.reporter, t.sync_master, t.time_s
    );
    let _ = writeln!(
        s,
        "MODULE      ALIVE  STATE  AGE  FINGERPRINT  TEC  REC  BUS-OFF  RX-OVR  DL-MISS"
    );
    for r in &t.rows {
        let alive = match (r.alive, r.heard) {
            (true, _) => "yes",
            (false, true) => "MISSING",
            (false, false) => "never",
        };
        let _ = writeln!(
            s,
            "{:<10} {:<7} {:>5} {:>4}  {:#010x} {:>4} {:>4} {:>8} {:>7} {:>8}",
            r.name,
            alive,
            r.state,
            r.age,
            r.fingerprint,
            r.tec,
            r.rec,
            r.bus_off,
            r.rx_overrun,
            r.deadline_missed
        );
    }
    s
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]
mod tests {
    use super::*;

    #[test]
    fn rows_from_the_columns_and_a_short_column_refused() {
        let names = vec!["gw".to_string(), "m1".to_string()];
        let v = serde_json::json!({
            "reporter": 0, "sync_master": 0,
            "flags": [3, 2], "state": [1, 1], "age": [0, 5],
            "fingerprint": [0x1234, 0x1234], "tec": [0, 8], "rec": [1, 0],
            "bus_off": [0, 2], "rx_overrun": [0, 3], "deadline_missed": [4, 0],
        });
        let t = from_json(&v, &names, 1_500_000_000).unwrap();
        assert_eq!((t.reporter.as_str(), t.sync_master.as_str()), ("gw", "gw"));
        assert!(t.rows[0].alive && !t.rows[1].alive && t.rows[1].heard);
        assert_eq!(t.rows[1].bus_off, 2);
        let text = render(&t);
        assert_eq!(
            text,
            "\nMODULE TABLE from gw (sync master gw) at 1.500 s\n\
             MODULE      ALIVE  STATE  AGE  FINGERPRINT  TEC  REC  BUS-OFF  RX-OVR  DL-MISS\n\
             gw         yes         1    0  0x00001234    0    1        0       0        4\n\
             m1         MISSING     1    5  0x00001234    8    0        2       3        0\n"
        );
        let mut short = v.clone();
        short["tec"] = serde_json::json!([0]);
        assert_eq!(from_json(&short, &names, 0), None);
    }
}
