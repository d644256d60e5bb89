//! Supervision of every module (docs/SERVICES.md §1): the per-module state table the
//! sync master (and every backup, which runs the same code) builds from the heartbeats
//! it times, the robot's rule for what a missing module means, and the table's wire
//! form for the module-table topic.
//!
//! A module is *missing* once its heartbeat is more than `HEARTBEAT_PERIOD_CYCLES +
//! MISSING_SLACK_CYCLES` cycles old: heartbeats come every `HEARTBEAT_PERIOD_CYCLES`
//! cycles, so a dead module shows at most `MISSING_SLACK_CYCLES + 1` cycles after the
//! heartbeat it failed to send was due.
use rtcan_core::confinement::ErrorState;
use rtcan_core::counters::Counters;
use rtcan_core::heartbeat::HEARTBEAT_PERIOD_CYCLES;

use crate::status::SystemStatus;

/// Cycles of lateness tolerated beyond the heartbeat period (the heartbeat is NRT:
/// it may wait for a cycle with free bandwidth).
pub const MISSING_SLACK_CYCLES: u16 = 2;

/// Age (cycles since the last heartbeat) past which a module counts as missing.
pub const MISSING_AFTER_CYCLES: u16 = HEARTBEAT_PERIOD_CYCLES as u16 + MISSING_SLACK_CYCLES;

/// What a missing module means (robot.toml `[modules.<m>] on_missing`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum OnMissing {
    /// Every module enters its safe state.
    SafeAll,
    /// The modules that subscribe to its topics (the dependents) enter their safe state.
    SafeDependents,
    /// Reported in the table, nothing else.
    Warn,
}

/// robot.toml's supervision rule for one module.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ModuleRule {
    /// Module index.
    pub module: u8,
    /// What its absence means.
    pub on_missing: OnMissing,
    /// Modules depending on it (bit m = module m), for `SafeDependents`.
    pub dependents: u64,
}

/// One row of the module table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct ModuleRow {
    /// Module index.
    pub module: u8,
    /// Heard within `MISSING_AFTER_CYCLES`.
    pub alive: bool,
    /// Heard at least once since the table's module powered on.
    pub heard: bool,
    /// Last announced state byte (`NodeState`).
    pub state: u8,
    /// Cycles since its last heartbeat (saturating at 255 on the wire).
    pub age: u16,
    /// Fingerprint its heartbeat carried: the robot's, or the mismatching one.
    pub fingerprint: u32,
}

/// The engine's own counters that go into the table's own row (the reporting module's).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct EngineHealth {
    /// Transmit / receive error counters (`Engine::error_state`), saturated at 255
    /// (bus-off shows in `bus_off`).
    pub tec: u8,
    pub rec: u8,
    /// Counters of `rtcan_core::counters::Counters`.
    pub bus_off: u32,
    pub rx_overrun: u32,
    pub deadline_missed: u32,
    pub hrt_late: u32,
}

impl EngineHealth {
    /// From the engine's counters and `Engine::error_state`.
    pub fn new(c: &Counters, e: &ErrorState) -> Self {
        EngineHealth {
            tec: u8::try_from(e.tec).unwrap_or(u8::MAX),
            rec: u8::try_from(e.rec).unwrap_or(u8::MAX),
            bus_off: c.bus_off,
            rx_overrun: c.rx_overrun,
            deadline_missed: c.deadline_missed,
            hrt_late: c.hrt_late,
        }
    }
}

/// The module table as seen by one module at one cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ModuleTable<const N: usize> {
    /// Reporting module.
    pub reporter: u8,
    /// The module the reporter follows as sync master.
    pub sync_master: u8,
    pub rows: [ModuleRow; N],
    pub health: EngineHealth,
}

/// Bytes of one row on the wire: module, flags (bit0 alive, bit1 heard), state, age
/// (saturated to 255), fingerprint u32 LE.
pub const ROW_BYTES: usize = 8;
/// Header: reporter, sync master, TEC, REC, then bus_off, rx_overrun, deadline_missed,
/// hrt_late as u16 LE each (saturated).
pub const HEADER_BYTES: usize = 12;

/// Wire size of a table of `n` modules.
pub const fn table_bytes(n: usize) -> usize {
    HEADER_BYTES + n * ROW_BYTES
}

fn sat16(v: u32) -> [u8; 2] {
    u16::try_from(v).unwrap_or(u16::MAX).to_le_bytes()
}

impl<const N: usize> ModuleTable<N> {
    /// Snapshot of `status` for modules `0..N`; `fingerprint` is the robot's (rows of
    /// modules that announced another one carry theirs, `mismatch`).
    pub fn snapshot(
        status: &SystemStatus,
        reporter: u8,
        fingerprint: u32,
        mismatch: Option<(u8, u32)>,
        health: EngineHealth,
    ) -> Self {
        let mut rows = [ModuleRow::default(); N];
        for (i, row) in rows.iter_mut().enumerate() {
            let module = u8::try_from(i).unwrap_or(u8::MAX);
            let age = status.module_age(module);
            let own = module == reporter;
            *row = ModuleRow {
                module,
                // A module does not hear its own heartbeat: it is alive while it runs.
                alive: own || age.is_some_and(|a| a <= MISSING_AFTER_CYCLES),
                heard: own || age.is_some(),
                state: status.module_state(module).unwrap_or(0),
                age: if own { 0 } else { age.unwrap_or(u16::MAX) },
                fingerprint: match mismatch {
                    Some((m, f)) if m == module => f,
                    _ => fingerprint,
                },
            };
        }
        ModuleTable {
            reporter,
            sync_master: status.sync_master(),
            rows,
            health,
        }
    }

    /// Missing modules (bit m = module m): heard before or expected, not alive now.
    pub fn missing(&self) -> u64 {
        self.rows
            .iter()
            .filter(|r| !r.alive && r.module < 64)
            .fold(0, |m, r| m | (1u64 << r.module))
    }

    /// Whether module `me` must enter its safe state under `rules`: some missing module's
    /// rule says all, or says its dependents and `me` is one.
    pub fn safe_required(&self, rules: &[ModuleRule], me: u8) -> bool {
        let missing = self.missing();
        rules.iter().any(|r| {
            r.module < 64
                && missing & (1u64 << r.module) != 0
                && match r.on_missing {
                    OnMissing::SafeAll => true,
                    OnMissing::SafeDependents => me < 64 && r.dependents & (1u64 << me) != 0,
                    OnMissing::Warn => false,
                }
        })
    }

    /// Modules reported as warnings only (missing, rule `Warn`, or no rule).
    pub fn warnings(&self, rules: &[ModuleRule]) -> u64 {
        let missing = self.missing();
        let serious = rules
            .iter()
            .filter(|r| r.on_missing != OnMissing::Warn && r.module < 64)
            .fold(0u64, |m, r| m | (1u64 << r.module));
        missing & !serious
    }

    /// Writes the wire form into `buf`; the number of bytes, `None` if `buf` is short.
    pub fn encode(&self, buf: &mut [u8]) -> Option<usize> {
        let len = table_bytes(N);
        let out = buf.get_mut(..len)?;
        let (head, body) = out.split_at_mut(HEADER_BYTES);
        let h = &self.health;
        let [b0, b1] = sat16(h.bus_off);
        let [o0, o1] = sat16(h.rx_overrun);
        let [d0, d1] = sat16(h.deadline_missed);
        let [l0, l1] = sat16(h.hrt_late);
        head.copy_from_slice(&[
            self.reporter,
            self.sync_master,
            h.tec,
            h.rec,
            b0,
            b1,
            o0,
            o1,
            d0,
            d1,
            l0,
            l1,
        ]);
        for (row, chunk) in self.rows.iter().zip(body.chunks_exact_mut(ROW_BYTES)) {
            let [f0, f1, f2, f3] = row.fingerprint.to_le_bytes();
            let flags = u8::from(row.alive) | (u8::from(row.heard) << 1);
            let age = u8::try_from(row.age).unwrap_or(u8::MAX);
            chunk.copy_from_slice(&[row.module, flags, row.state, age, f0, f1, f2, f3]);
        }
        Some(len)
    }

    /// Parses the wire form; `None` for a wrong length or a row out of order.
    pub fn decode(bytes: &[u8]) -> Option<Self> {
        if bytes.len() != table_bytes(N) {
            return None;
        }
        let (head, body) = bytes.split_at(HEADER_BYTES);
        let &[reporter, sync_master, tec, rec, b0, b1, o0, o1, d0, d1, l0, l1] = head else {
            return None;
        };
        let u = |a, b| u32::from(u16::from_le_bytes([a, b]));
        let mut rows = [ModuleRow::default(); N];
        for (i, (row, c)) in rows
            .iter_mut()
            .zip(body.chunks_exact(ROW_BYTES))
            .enumerate()
        {
            let &[module, flags, state, age, f0, f1, f2, f3] = c else {
                return None;
            };
            if usize::from(module) != i || flags > 3 {
                return None;
            }
            *row = ModuleRow {
                module,
                alive: flags & 1 != 0,
                heard: flags & 2 != 0,
                state,
                age: u16::from(age),
                fingerprint: u32::from_le_bytes([f0, f1, f2, f3]),
            };
        }
        Some(ModuleTable {
            reporter,
            sync_master,
            rows,
            health: EngineHealth {
                tec,
                rec,
                bus_off: u(b0, b1),
                rx_overrun: u(o0, o1),
                deadline_missed: u(d0, d1),
                hrt_late: u(l0, l1),
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::status::{SafeReason, SafetyConfig};
    use rtcan_core::driver::Event;

    const CFG: SafetyConfig = SafetyConfig {
        module: 0,
        master: 0,
        max_missed_cycles: 30,
    };

    fn beat(s: &SystemStatus, module: u8) {
        s.event(Event::Heartbeat { module, state: 1 });
    }

    fn cycles(s: &SystemStatus, n: u16) {
        for _ in 0..n {
            s.event(Event::CycleStart);
        }
    }

    #[test]
    fn killed_module_turns_missing_exactly_after_the_slack() {
        let s = SystemStatus::new(CFG);
        s.event(Event::Synced);
        for m in 1..4 {
            beat(&s, m);
        }
        let t = || ModuleTable::<4>::snapshot(&s, 0, 0xAB, None, EngineHealth::default());
        assert_eq!(t().missing(), 0);
        // Modules 1 and 2 keep beating every 10 cycles; 3 is dead from now on.
        for k in 1..=MISSING_AFTER_CYCLES {
            cycles(&s, 1);
            if k % 10 == 0 {
                beat(&s, 1);
                beat(&s, 2);
            }
            assert_eq!(t().missing(), 0, "cycle {k}");
        }
        cycles(&s, 1);
        assert_eq!(t().missing(), 1 << 3);
        let row = t().rows[3];
        assert!(!row.alive && row.heard);
        assert_eq!(row.age, MISSING_AFTER_CYCLES + 1);
        // It comes back: alive again at once.
        beat(&s, 3);
        assert_eq!(t().missing(), 0);
    }

    #[test]
    fn never_heard_module_is_missing_and_own_row_is_alive() {
        let s = SystemStatus::new(CFG);
        let t = ModuleTable::<3>::snapshot(&s, 0, 1, None, EngineHealth::default());
        assert_eq!(t.missing(), 0b110);
        assert!(t.rows[0].alive && !t.rows[1].heard);
    }

    #[test]
    fn rules_all_dependents_warn() {
        let s = SystemStatus::new(CFG);
        beat(&s, 1);
        let t = ModuleTable::<3>::snapshot(&s, 0, 1, None, EngineHealth::default());
        // Module 2 never heard: missing.
        let dep = [ModuleRule {
            module: 2,
            on_missing: OnMissing::SafeDependents,
            dependents: 1 << 1,
        }];
        assert!(t.safe_required(&dep, 1));
        assert!(!t.safe_required(&dep, 0));
        assert_eq!(t.warnings(&dep), 0);
        let all = [ModuleRule {
            on_missing: OnMissing::SafeAll,
            ..dep[0]
        }];
        assert!(t.safe_required(&all, 0) && t.safe_required(&all, 1));
        let warn = [ModuleRule {
            on_missing: OnMissing::Warn,
            ..dep[0]
        }];
        assert!(!t.safe_required(&warn, 1));
        assert_eq!(t.warnings(&warn), 1 << 2);
        // Module 1 is alive: its rule never fires.
        let alive = [ModuleRule {
            module: 1,
            on_missing: OnMissing::SafeAll,
            dependents: 0,
        }];
        assert!(!t.safe_required(&alive, 0));
    }

    #[test]
    fn wire_round_trip_exact_bytes_and_bad_input() {
        let s = SystemStatus::new(CFG);
        s.event(Event::Heartbeat {
            module: 1,
            state: 2,
        });
        cycles(&s, 3);
        let h = EngineHealth {
            tec: 7,
            rec: 9,
            bus_off: 1,
            rx_overrun: 70_000,
            deadline_missed: 3,
            hrt_late: 0,
        };
        let t = ModuleTable::<2>::snapshot(&s, 0, 0x1122_3344, Some((1, 0xDEAD_BEEF)), h);
        let mut buf = [0u8; 40];
        assert_eq!(t.encode(&mut buf[..27]), None);
        let n = t.encode(&mut buf).unwrap();
        assert_eq!(n, 28);
        assert_eq!(
            &buf[..n],
            &[
                0, 0, 7, 9, 1, 0, 0xFF, 0xFF, 3, 0, 0, 0, // header
                0, 3, 0, 0, 0x44, 0x33, 0x22, 0x11, // own row
                1, 3, 2, 3, 0xEF, 0xBE, 0xAD, 0xDE, // module 1, mismatching
            ]
        );
        let back = ModuleTable::<2>::decode(&buf[..n]).unwrap();
        assert_eq!(back.rows, t.rows);
        assert_eq!(back.health.rx_overrun, 0xFFFF);
        assert_eq!(ModuleTable::<2>::decode(&buf[..n - 1]), None);
        let mut bad = buf;
        bad[20] = 5; // row 1 claims module 5
        assert_eq!(ModuleTable::<2>::decode(&bad[..n]), None);
        bad = buf;
        bad[13] = 4; // unknown flag
        assert_eq!(ModuleTable::<2>::decode(&bad[..n]), None);
    }

    #[test]
    fn safe_state_follows_the_backup_that_took_over() {
        // Module 2 is a plain slave; 0 the configured master, 1 its backup.
        let slave = SafetyConfig {
            module: 2,
            master: 0,
            max_missed_cycles: 30,
        };
        let s = SystemStatus::with_backups(slave, &[1]);
        s.event(Event::Synced);
        beat(&s, 0);
        beat(&s, 1);
        assert_eq!(s.safe_reason(), None);
        assert_eq!(s.sync_master(), 0);
        // The master dies; the backup takes over and keeps beating, running.
        for k in 1..=100u16 {
            cycles(&s, 1);
            if k % 10 == 0 {
                beat(&s, 1);
            }
        }
        assert_eq!(s.sync_master(), 1);
        assert_eq!(
            s.safe_reason(),
            None,
            "follows the backup, not the dead master"
        );
        // The backup announces Stop: now the rule fires on *its* state.
        s.event(Event::Heartbeat {
            module: 1,
            state: crate::node::NodeState::Stop as u8,
        });
        assert_eq!(s.safe_reason(), Some(SafeReason::MasterStopped));
        // And when the backup dies as well, the master is silent.
        cycles(&s, 31);
        assert_eq!(s.safe_reason(), Some(SafeReason::MasterSilent));
        // Without backups declared, the old behaviour: the configured master only.
        let plain = SystemStatus::new(slave);
        plain.event(Event::Synced);
        beat(&plain, 0);
        cycles(&plain, 31);
        beat(&plain, 1);
        assert_eq!(plain.safe_reason(), Some(SafeReason::MasterSilent));
    }

    #[test]
    fn backup_that_took_over_is_its_own_master() {
        let backup = SafetyConfig {
            module: 1,
            master: 0,
            max_missed_cycles: 30,
        };
        let s = SystemStatus::with_backups(backup, &[1]);
        s.event(Event::Synced);
        beat(&s, 0);
        assert_eq!(s.safe_reason(), None);
        cycles(&s, 31);
        // Master silent; the engine took over (`Synced`), so no safe state here.
        assert_eq!(s.sync_master(), 1);
        assert_eq!(s.safe_reason(), None);
        s.event(Event::SyncLost);
        assert_eq!(s.safe_reason(), Some(SafeReason::NoSync));
    }
}
