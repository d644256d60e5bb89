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

use crate::slot_grid::SlotGrid;
use crate::status::SystemStatus;
use rtcan_core::time::Nanos;

/// Cycles of lateness tolerated beyond the heartbeat period (the heartbeat is NRT:
/// it may wait for a cycle with free bandwidth).
pub const MISSING_SLACK_CYCLES: u16 = 2;

/// Age (cycles since the last heartbeat) past which a module counts as missing, with
/// the engine's default heartbeat period.
pub const MISSING_AFTER_CYCLES: u16 = HEARTBEAT_PERIOD_CYCLES as u16 + MISSING_SLACK_CYCLES;

/// Lateness tolerated on a supervised robot (robot.toml `on_missing`, whose heartbeats
/// come every `heartbeat_cycles`, 1 on the Triskar2): a heartbeat may slip by up to two
/// cycles (NRT, sent after the module's queued frames, again after an error frame: at
/// BER 1e-4 the simulated Triskar2 shows ages of 3 cycles, 1 in 400 samples; with 1 cycle
/// of slack the motors stopped twice in 10 s for nothing).
pub const SUPERVISED_SLACK_CYCLES: u16 = 2;

/// Age past which a module of a supervised robot counts as missing (the generated
/// `supervision::MISSING_AFTER_CYCLES`): with a heartbeat every cycle, 3, so a module is
/// missing 3 cycle starts after the heartbeat it failed to send (3 to 4 cycles after its
/// death, depending on where in the cycle it died).
pub const fn missing_after(heartbeat_cycles: u8) -> u16 {
    heartbeat_cycles as u16 + SUPERVISED_SLACK_CYCLES
}

/// The module table's missing age at this moment (docs/SERVICES.md §1). Before the
/// cycle's due phase (`heartbeats_overdue`), the rules' age (`missing_after`): a sync
/// frame destroyed by an error frame silences every slave for a cycle or two, and while
/// their heartbeats come back one by one in the next cycle none of them may look
/// missing. Once the cycle's heartbeats are overdue, `heartbeat_cycles`: with a heartbeat
/// every cycle a module is missing when its heartbeat of the previous cycle never came
/// and the one of this cycle has not come by the due phase. A module killed just after
/// its heartbeat is thus shown missing 2 cycles + the due phase after that heartbeat,
/// 2.5 cycles at most after its death with the due phase at mid-cycle (the rules' age
/// alone: up to 4 cycles).
pub const fn table_missing_after_at(heartbeat_cycles: u8, overdue: bool) -> u16 {
    if overdue {
        heartbeat_cycles as u16
    } else {
        missing_after(heartbeat_cycles)
    }
}

/// Whether this cycle's heartbeats are overdue at local time `now`: the phase in the
/// cycle (on the slot grid, `SystemStatus::grid`) is past `due_ns`. Every engine sends
/// its heartbeat in the first free window of the cycle (after its queued frames: on the
/// simulated Triskar2 they end 0.8 to 3.6 ms after the sync's start, at BER 1e-4 too),
/// so `due_ns` half a cycle leaves them more than a millisecond. The last tenth of the
/// cycle never counts as overdue: there the engine's cycle start (which ages the
/// heartbeats) and the grid snapshot may disagree on which cycle `now` is in, and an age
/// counted in the next cycle must not meet a phase of the previous one. No grid (not
/// synchronised): never overdue (the cycle-count rule alone).
pub fn heartbeats_overdue(grid: Option<SlotGrid>, now: Nanos, due_ns: Nanos) -> bool {
    let Some(g) = grid else { return false };
    let c = g.cycle_local;
    if c == 0 {
        return false;
    }
    let phase = if now >= g.start {
        (now - g.start) % c
    } else {
        (c - (g.start - now) % c) % c
    };
    phase >= due_ns && phase < c - c / 10
}

/// Local time of the next due phase after `now` on `grid` (when a sync master polls its
/// `Supervisor` so a verdict is not left waiting for some other wake-up).
pub fn next_due(grid: Option<SlotGrid>, now: Nanos, due_ns: Nanos) -> Option<Nanos> {
    let g = grid?;
    let c = g.cycle_local;
    if c == 0 || now < g.start {
        return None;
    }
    let cycle_start = now - (now - g.start) % c;
    let due = cycle_start + due_ns;
    Some(if due > now { due } else { due + c })
}

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

/// Whether `rule`, when its module is missing, puts module `me` in its safe state.
pub fn applies(rule: &ModuleRule, me: u8) -> bool {
    match rule.on_missing {
        OnMissing::SafeAll => true,
        OnMissing::SafeDependents => me < 64 && rule.dependents & (1u64 << me) != 0,
        OnMissing::Warn => false,
    }
}

/// One module's engine health: what its `ModuleHealth` topic carries and its row of the
/// module table shows. Counts above `u16::MAX` saturate on the wire.
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
}

/// Wire size of a module's health (`ModuleHealth`): TEC, REC, then bus-off count, RX
/// overruns and deadline misses as u16 LE.
pub const HEALTH_BYTES: usize = 8;

fn sat16(v: u32) -> u16 {
    u16::try_from(v).unwrap_or(u16::MAX)
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
        }
    }

    /// What survives the wire: the counts saturated to u16.
    pub fn saturated(self) -> Self {
        EngineHealth {
            bus_off: u32::from(sat16(self.bus_off)),
            rx_overrun: u32::from(sat16(self.rx_overrun)),
            deadline_missed: u32::from(sat16(self.deadline_missed)),
            ..self
        }
    }

    /// Writes the `HEALTH_BYTES` wire form; `None` if `out` is short.
    pub fn encode(&self, out: &mut [u8]) -> Option<usize> {
        let out = out.get_mut(..HEALTH_BYTES)?;
        let [b0, b1] = sat16(self.bus_off).to_le_bytes();
        let [o0, o1] = sat16(self.rx_overrun).to_le_bytes();
        let [d0, d1] = sat16(self.deadline_missed).to_le_bytes();
        out.copy_from_slice(&[self.tec, self.rec, b0, b1, o0, o1, d0, d1]);
        Some(HEALTH_BYTES)
    }

    /// Parses the wire form; `None` for a wrong length.
    pub fn decode(bytes: &[u8]) -> Option<Self> {
        let &[tec, rec, b0, b1, o0, o1, d0, d1] = bytes else {
            return None;
        };
        let u = |a, b| u32::from(u16::from_le_bytes([a, b]));
        Some(EngineHealth {
            tec,
            rec,
            bus_off: u(b0, b1),
            rx_overrun: u(o0, o1),
            deadline_missed: u(d0, d1),
        })
    }
}

/// One row of the module table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct ModuleRow {
    /// Module index.
    pub module: u8,
    /// Heard within the missing age (not missing).
    pub alive: bool,
    /// Heard at least once since the table's module powered on.
    pub heard: bool,
    /// Last announced state byte (`NodeState`).
    pub state: u8,
    /// Cycles since its last heartbeat (saturating at 255 on the wire).
    pub age: u16,
    /// Fingerprint its heartbeat carried: the robot's, or the mismatching one.
    pub fingerprint: u32,
    /// Its engine health as last received (`ModuleHealth` topic; the reporter's own
    /// from its engine); zero until one arrived.
    pub health: EngineHealth,
}

/// The module table as seen by one module at one cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ModuleTable<const N: usize> {
    /// Reporting module.
    pub reporter: u8,
    /// The module the reporter follows as sync master.
    pub sync_master: u8,
    pub rows: [ModuleRow; N],
}

/// Header: reporter, sync master.
pub const HEADER_BYTES: usize = 2;
/// Bytes per module, over the columns: flags (bit0 alive, bit1 heard), state, age
/// (saturated to 255), fingerprint u32, TEC, REC, bus-off u16, RX overruns u16, deadline
/// misses u16 (all LE).
pub const ROW_BYTES: usize = 15;

/// Wire size of a table of `n` modules: the header, then one array per column
/// (rtcan_model::module_state::state_fields: the generated `ModuleState`).
pub const fn table_bytes(n: usize) -> usize {
    HEADER_BYTES + n * ROW_BYTES
}

impl<const N: usize> ModuleTable<N> {
    /// Snapshot of `status` for modules `0..N`; `fingerprint` is the robot's (rows of
    /// modules that announced another one carry theirs, `mismatch`); `health[m]` is
    /// module m's last known health. Missing after `MISSING_AFTER_CYCLES` (the default
    /// heartbeat period).
    pub fn snapshot(
        status: &SystemStatus,
        reporter: u8,
        fingerprint: u32,
        mismatch: Option<(u8, u32)>,
        health: &[EngineHealth; N],
    ) -> Self {
        Self::snapshot_after(
            status,
            reporter,
            fingerprint,
            mismatch,
            health,
            MISSING_AFTER_CYCLES,
        )
    }

    /// As `snapshot`, a module being missing once its heartbeat is more than
    /// `missing_after` cycles old (`missing_after(heartbeat period)`).
    pub fn snapshot_after(
        status: &SystemStatus,
        reporter: u8,
        fingerprint: u32,
        mismatch: Option<(u8, u32)>,
        health: &[EngineHealth; N],
        missing_after: u16,
    ) -> Self {
        let mut rows = [ModuleRow::default(); N];
        for (i, (row, h)) in rows.iter_mut().zip(health).enumerate() {
            let module = u8::try_from(i).unwrap_or(u8::MAX);
            let age = status.module_age(module);
            let own = module == reporter;
            *row = ModuleRow {
                module,
                // A module does not hear its own heartbeat: it is alive while it runs.
                alive: own || !status.module_missing(module, missing_after),
                heard: own || age.is_some(),
                state: status.module_state(module).unwrap_or(0),
                age: if own { 0 } else { age.unwrap_or(u16::MAX) },
                fingerprint: match mismatch {
                    Some((m, f)) if m == module => f,
                    _ => fingerprint,
                },
                health: *h,
            };
        }
        ModuleTable {
            reporter,
            sync_master: status.sync_master(),
            rows,
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
        rules
            .iter()
            .any(|r| r.module < 64 && missing & (1u64 << r.module) != 0 && applies(r, me))
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
        head.copy_from_slice(&[self.reporter, self.sync_master]);
        // Column by column: (offset of the column, bytes per module, the bytes of row r).
        let mut col = 0;
        let mut put = |width: usize, f: &dyn Fn(&ModuleRow) -> [u8; 4]| {
            for (r, row) in self.rows.iter().enumerate() {
                let at = col + r * width;
                if let (Some(dst), Some(src)) = (body.get_mut(at..at + width), f(row).get(..width))
                {
                    dst.copy_from_slice(src);
                }
            }
            col += N * width;
        };
        let b = |v: u8| [v, 0, 0, 0];
        let w = |v: u32| {
            let [x, y] = sat16(v).to_le_bytes();
            [x, y, 0, 0]
        };
        put(1, &|r| b(u8::from(r.alive) | (u8::from(r.heard) << 1)));
        put(1, &|r| b(r.state));
        put(1, &|r| b(u8::try_from(r.age).unwrap_or(u8::MAX)));
        put(4, &|r| r.fingerprint.to_le_bytes());
        put(1, &|r| b(r.health.tec));
        put(1, &|r| b(r.health.rec));
        put(2, &|r| w(r.health.bus_off));
        put(2, &|r| w(r.health.rx_overrun));
        put(2, &|r| w(r.health.deadline_missed));
        Some(len)
    }

    /// Parses the wire form; `None` for a wrong length or an unknown flag bit.
    pub fn decode(bytes: &[u8]) -> Option<Self> {
        if bytes.len() != table_bytes(N) {
            return None;
        }
        let (head, body) = bytes.split_at(HEADER_BYTES);
        let &[reporter, sync_master] = head else {
            return None;
        };
        // Byte k of row r's value in the column at `col` of `width` bytes per module.
        let get = |col: usize, width: usize, r: usize| -> [u8; 4] {
            let mut v = [0u8; 4];
            let at = col * N + r * width;
            if let (Some(src), Some(dst)) = (body.get(at..at + width), v.get_mut(..width)) {
                dst.copy_from_slice(src);
            }
            v
        };
        let u16_at = |col: usize, r: usize| {
            let [a, b, _, _] = get(col, 2, r);
            u32::from(u16::from_le_bytes([a, b]))
        };
        let mut rows = [ModuleRow::default(); N];
        for (r, row) in rows.iter_mut().enumerate() {
            let [flags, ..] = get(0, 1, r);
            if flags > 3 {
                return None;
            }
            *row = ModuleRow {
                module: u8::try_from(r).ok()?,
                alive: flags & 1 != 0,
                heard: flags & 2 != 0,
                state: get(1, 1, r)[0],
                age: u16::from(get(2, 1, r)[0]),
                fingerprint: u32::from_le_bytes(get(3, 4, r)),
                health: EngineHealth {
                    tec: get(7, 1, r)[0],
                    rec: get(8, 1, r)[0],
                    bus_off: u16_at(9, r),
                    rx_overrun: u16_at(11, r),
                    deadline_missed: u16_at(13, r),
                },
            };
        }
        Some(ModuleTable {
            reporter,
            sync_master,
            rows,
        })
    }
}

/// What a module publishes for supervision now (`Supervisor::poll`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Publish<const N: usize> {
    /// Its own health, for its `health_<module>` topic.
    pub health: Option<EngineHealth>,
    /// The module table, for its `module_state_<module>` topic (the current sync
    /// master only).
    pub table: Option<ModuleTable<N>>,
}

/// One module's side of the module-state topics: the health it last received from
/// every module, and when to publish its own health and (as the current sync master)
/// the table. Owned by the module's glue (no static, no heap).
///
/// Health goes out every `every` cycles. The table goes out every `every` cycles and
/// at once when a row's alive flag or state changes, so a module that goes missing
/// reaches the other modules in the cycle it is declared missing, not up to `every`
/// cycles later.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Supervisor<const N: usize> {
    me: u8,
    every: u32,
    health: [EngineHealth; N],
    last_health: Option<u32>,
    last_table: Option<(u32, [(bool, u8); N])>,
}

impl<const N: usize> Supervisor<N> {
    /// For module `me`, publishing every `every` cycles (at least 1).
    pub const fn new(me: u8, every: u32) -> Self {
        Supervisor {
            me,
            every: if every == 0 { 1 } else { every },
            health: [EngineHealth {
                tec: 0,
                rec: 0,
                bus_off: 0,
                rx_overrun: 0,
                deadline_missed: 0,
            }; N],
            last_health: None,
            last_table: None,
        }
    }

    /// Module `module`'s health arrived (its `ModuleHealth` topic).
    pub fn health_rx(&mut self, module: u8, h: EngineHealth) {
        if let Some(slot) = self.health.get_mut(usize::from(module)) {
            *slot = h;
        }
    }

    /// The health last known of every module.
    pub fn health(&self) -> &[EngineHealth; N] {
        &self.health
    }

    /// What to publish now: `own` is this module's engine health, `is_master` whether
    /// its engine sends the sync now. Call it at least once per cycle; the cycle is
    /// `status.cycles()`, so nothing is published before the first cycle.
    pub fn poll(
        &mut self,
        status: &SystemStatus,
        own: EngineHealth,
        is_master: bool,
        fingerprint: u32,
        missing_after: u16,
    ) -> Publish<N> {
        let cycle = status.cycles();
        // What the wire carries, so a table row equals the health topic's value.
        self.health_rx(self.me, own.saturated());
        let due = |last: Option<u32>| last.is_none_or(|l| cycle.wrapping_sub(l) >= self.every);
        let health = (cycle > 0 && due(self.last_health)).then(|| {
            self.last_health = Some(cycle);
            own.saturated()
        });
        if !is_master || cycle == 0 {
            // A master that takes over publishes at once.
            self.last_table = None;
            return Publish {
                health,
                table: None,
            };
        }
        let mismatch = match status.safe_reason() {
            Some(crate::status::SafeReason::FingerprintMismatch {
                module,
                fingerprint,
            }) => Some((module, fingerprint)),
            _ => None,
        };
        let mut table = ModuleTable::snapshot_after(
            status,
            self.me,
            fingerprint,
            mismatch,
            &self.health,
            missing_after,
        );
        // Its engine sends the sync: it is the sync master, whatever `SystemStatus`
        // (which follows heartbeats, not its own engine) would name.
        table.sync_master = self.me;
        let mut shown = [(false, 0u8); N];
        for (s, r) in shown.iter_mut().zip(&table.rows) {
            *s = (r.alive, r.state);
        }
        // A table goes out on its period, at once when a module turns missing, and for
        // other changes (modules heard one by one at start-up, state changes) at most
        // once a cycle: a newer table replaces one still on the bus, and a burst of them
        // would leave only broken transfers on the wire.
        let send = match self.last_table {
            None => true,
            Some((at, was)) => {
                let newly_missing = was.iter().zip(&shown).any(|(w, n)| w.0 && !n.0);
                cycle.wrapping_sub(at) >= self.every
                    || newly_missing
                    || (was != shown && cycle != at)
            }
        };
        if send {
            self.last_table = Some((cycle, shown));
        }
        Publish {
            health,
            table: send.then_some(table),
        }
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
        let t = || ModuleTable::<4>::snapshot(&s, 0, 0xAB, None, &Default::default());
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
    fn fast_heartbeat_missing_at_the_fourth_silent_cycle() {
        let s = SystemStatus::new(CFG);
        s.event(Event::Synced);
        beat(&s, 1);
        beat(&s, 2);
        let after = missing_after(1);
        assert_eq!(after, 3);
        let t = || ModuleTable::<3>::snapshot_after(&s, 0, 1, None, &Default::default(), after);
        // Module 1 beats every cycle; 2 is silent: alive for 3 cycles, missing at the 4th.
        for k in 1..=3 {
            cycles(&s, 1);
            beat(&s, 1);
            assert_eq!(t().missing(), 0, "cycle {k}");
        }
        cycles(&s, 1);
        beat(&s, 1);
        assert_eq!(t().missing(), 1 << 2);
        assert_eq!(t().rows[2].age, 4);
    }

    #[test]
    fn everybody_silent_at_once_is_the_sync_not_the_modules() {
        let s = SystemStatus::new(CFG);
        s.event(Event::Synced);
        (1..4).for_each(|m| beat(&s, m));
        let after = missing_after(1);
        let t = || ModuleTable::<4>::snapshot_after(&s, 0, 1, None, &Default::default(), after);
        // Nobody beats for 5 cycles (a sync outage): nobody missing.
        cycles(&s, 5);
        assert_eq!(t().missing(), 0);
        // Module 1 is heard again: 2 and 3, still silent, are missing now.
        beat(&s, 1);
        assert_eq!(t().missing(), 0b1100);
        // With a single other module heard, its age alone decides.
        let pair = SystemStatus::new(CFG);
        beat(&pair, 1);
        cycles(&pair, 3);
        let two =
            || ModuleTable::<2>::snapshot_after(&pair, 0, 1, None, &Default::default(), after);
        assert_eq!(two().missing(), 0);
        cycles(&pair, 1);
        assert_eq!(two().missing(), 0b10);
    }

    #[test]
    fn never_heard_module_is_missing_and_own_row_is_alive() {
        let s = SystemStatus::new(CFG);
        let t = ModuleTable::<3>::snapshot(&s, 0, 1, None, &Default::default());
        assert_eq!(t.missing(), 0b110);
        assert!(t.rows[0].alive && !t.rows[1].heard);
    }

    #[test]
    fn rules_all_dependents_warn() {
        let s = SystemStatus::new(CFG);
        beat(&s, 1);
        let t = ModuleTable::<3>::snapshot(&s, 0, 1, None, &Default::default());
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
        let h0 = EngineHealth {
            tec: 7,
            rec: 9,
            bus_off: 1,
            rx_overrun: 70_000,
            deadline_missed: 3,
        };
        let h1 = EngineHealth {
            tec: 0x80,
            rec: 0,
            bus_off: 0,
            rx_overrun: 5,
            deadline_missed: 0x1234,
        };
        let t = ModuleTable::<2>::snapshot(&s, 0, 0x1122_3344, Some((1, 0xDEAD_BEEF)), &[h0, h1]);
        let mut buf = [0u8; 40];
        assert_eq!(t.encode(&mut buf[..31]), None);
        let n = t.encode(&mut buf).unwrap();
        assert_eq!(n, 32);
        assert_eq!(
            &buf[..n],
            &[
                0, 0, // reporter, sync master
                3, 3, // flags: alive and heard
                0, 2, // state
                0, 3, // age
                0x44, 0x33, 0x22, 0x11, 0xEF, 0xBE, 0xAD,
                0xDE, // fingerprints (1 mismatching)
                7, 0x80, // TEC
                9, 0, // REC
                1, 0, 0, 0, // bus-off
                0xFF, 0xFF, 5, 0, // RX overruns (70000 saturated)
                3, 0, 0x34, 0x12, // deadline misses
            ]
        );
        let back = ModuleTable::<2>::decode(&buf[..n]).unwrap();
        assert_eq!(back.rows[1], t.rows[1]);
        assert_eq!(back.rows[0].health, h0.saturated());
        assert_eq!(back.rows[0].health.rx_overrun, 0xFFFF);
        assert_eq!((back.reporter, back.sync_master), (0, 0));
        assert_eq!(ModuleTable::<2>::decode(&buf[..n - 1]), None);
        assert_eq!(ModuleTable::<2>::decode(&buf[..n + 1]), None);
        let mut bad = buf;
        bad[3] = 4; // unknown flag of module 1
        assert_eq!(ModuleTable::<2>::decode(&bad[..n]), None);
    }

    #[test]
    fn health_wire_form_exact_bytes() {
        let h = EngineHealth {
            tec: 200,
            rec: 1,
            bus_off: 2,
            rx_overrun: 0x1_0000,
            deadline_missed: 0x0102,
        };
        let mut b = [0u8; 8];
        assert_eq!(h.encode(&mut b[..7]), None);
        assert_eq!(h.encode(&mut b), Some(8));
        assert_eq!(b, [200, 1, 2, 0, 0xFF, 0xFF, 0x02, 0x01]);
        assert_eq!(EngineHealth::decode(&b), Some(h.saturated()));
        assert_eq!(EngineHealth::decode(&b[..7]), None);
        assert_eq!(EngineHealth::decode(&[0; 9]), None);
    }

    #[test]
    fn supervisor_publishes_on_its_period_and_at_once_on_a_change() {
        let s = SystemStatus::new(CFG);
        s.event(Event::Synced);
        let mut sv = Supervisor::<3>::new(0, 10);
        let own = EngineHealth {
            tec: 1,
            ..EngineHealth::default()
        };
        let after = missing_after(1);
        let mut poll = |s: &SystemStatus, master: bool| sv.poll(s, own, master, 0xF00D, after);
        // Before the first cycle: nothing.
        assert_eq!(poll(&s, true).health, None);
        assert_eq!(poll(&s, true).table, None);
        let step = |s: &SystemStatus| {
            cycles(s, 1);
            beat(s, 1);
            beat(s, 2);
        };
        step(&s);
        // Cycle 1: health and table, then nothing more in the same cycle.
        let p = poll(&s, true);
        assert_eq!(p.health, Some(own));
        let t = p.table.unwrap();
        assert_eq!(t.rows[0].health, own);
        assert_eq!(t.rows[1].fingerprint, 0xF00D);
        assert_eq!((t.reporter, t.sync_master), (0, 0));
        assert_eq!(
            poll(&s, true),
            Publish {
                health: None,
                table: None
            }
        );
        // Cycles 2..=10: nothing changes, nothing sent; cycle 11: both again.
        for c in 2..=10 {
            step(&s);
            assert_eq!(
                poll(&s, true),
                Publish {
                    health: None,
                    table: None
                },
                "cycle {c}"
            );
        }
        step(&s);
        let p = poll(&s, true);
        assert!(p.health.is_some() && p.table.is_some());
        // Module 2 falls silent: the table goes out in the cycle it turns missing.
        let mut sent = Vec::new();
        for c in 12..=16 {
            cycles(&s, 1);
            beat(&s, 1);
            if let Some(t) = poll(&s, true).table {
                sent.push((c, t.missing()));
            }
        }
        // Heard at cycle 11: age 4 > 3 at cycle 15.
        assert_eq!(sent, vec![(15, 1 << 2)]);
        // A received health shows in its row.
        let h2 = EngineHealth {
            deadline_missed: 9,
            ..EngineHealth::default()
        };
        sv.health_rx(2, h2);
        sv.health_rx(7, h2); // no such module: ignored
        assert_eq!(sv.health()[2], h2);
        // Not the master: no table, and the next takeover publishes at once.
        cycles(&s, 10);
        beat(&s, 1);
        let p = sv.poll(&s, own, false, 0xF00D, after);
        assert!(p.health.is_some() && p.table.is_none());
        let t = sv.poll(&s, own, true, 0xF00D, after).table.unwrap();
        assert_eq!(t.rows[2].health, h2);
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
    fn status_applies_the_rules_of_missing_modules() {
        use crate::status::Supervised;
        // Module 2 of 4: module 1 is safe_dependents with 2 dependent, 3 is warn.
        const RULES: &[ModuleRule] = &[
            ModuleRule {
                module: 1,
                on_missing: OnMissing::SafeDependents,
                dependents: 1 << 2,
            },
            ModuleRule {
                module: 3,
                on_missing: OnMissing::Warn,
                dependents: 0,
            },
        ];
        let sv = Supervised {
            modules: 4,
            missing_after: missing_after(1),
            rules: RULES,
        };
        let me = |module| SafetyConfig {
            module,
            master: 0,
            max_missed_cycles: 30,
        };
        let s = SystemStatus::supervised(me(2), &[], sv);
        let other = SystemStatus::supervised(me(3), &[], sv);
        let all = |f: &dyn Fn(&SystemStatus)| {
            f(&s);
            f(&other)
        };
        all(&|s| s.event(Event::Synced));
        all(&|s| (0..4).for_each(|m| beat(s, m)));
        assert_eq!(s.safe_reason(), None);
        // 1 and 3 fall silent; 0 keeps beating every cycle.
        for _ in 0..3 {
            all(&|s| cycles(s, 1));
            all(&|s| beat(s, 0));
            assert_eq!(s.safe_reason(), None);
        }
        all(&|s| cycles(s, 1));
        all(&|s| beat(s, 0));
        assert_eq!(
            s.safe_reason(),
            Some(SafeReason::ModuleMissing { module: 1 })
        );
        // Module 3 is not a dependent of 1, and 3's own rule only warns.
        assert_eq!(other.safe_reason(), None);
        // Back: the rule no longer applies.
        beat(&s, 1);
        assert_eq!(s.safe_reason(), None);
        // Without supervision, the same silence changes nothing.
        let plain = SystemStatus::new(me(2));
        plain.event(Event::Synced);
        beat(&plain, 0);
        cycles(&plain, 5);
        beat(&plain, 0);
        assert_eq!(plain.safe_reason(), None);
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

    #[test]
    fn heartbeats_overdue_from_the_due_phase_to_the_last_tenth_of_the_cycle() {
        let g = SlotGrid {
            cycle: 7,
            start: 21_000_000,
            cycle_local: 10_000_000,
        };
        let due = 5_000_000;
        let at = |phase: u64, cycles_later: u64| 21_000_000 + cycles_later * 10_000_000 + phase;
        assert!(!heartbeats_overdue(Some(g), at(4_999_999, 0), due));
        assert!(heartbeats_overdue(Some(g), at(5_000_000, 0), due));
        assert!(heartbeats_overdue(Some(g), at(8_999_999, 3), due));
        // The last tenth: the cycle start may already have aged the heartbeats.
        assert!(!heartbeats_overdue(Some(g), at(9_000_000, 3), due));
        assert!(!heartbeats_overdue(Some(g), at(0, 4), due));
        // Before the snapshot's cycle: the same phases.
        assert!(heartbeats_overdue(Some(g), 21_000_000 - 4_000_000, due));
        assert!(!heartbeats_overdue(Some(g), 21_000_000 - 6_000_000, due));
        // Not synchronised, or a degenerate grid: the cycle-count rule alone.
        assert!(!heartbeats_overdue(None, at(6_000_000, 0), due));
        let flat = SlotGrid {
            cycle_local: 0,
            ..g
        };
        assert!(!heartbeats_overdue(Some(flat), at(6_000_000, 0), due));
        // The next due phase after now.
        assert_eq!(next_due(Some(g), at(1, 2), due), Some(at(5_000_000, 2)));
        assert_eq!(
            next_due(Some(g), at(5_000_000, 2), due),
            Some(at(5_000_000, 3))
        );
        assert_eq!(next_due(Some(g), 10, due), None);
        assert_eq!(next_due(None, at(1, 2), due), None);
    }

    #[test]
    fn table_missing_age_drops_to_one_cycle_past_the_due_phase() {
        assert_eq!(table_missing_after_at(1, false), 3);
        assert_eq!(table_missing_after_at(1, true), 1);
        let s = SystemStatus::new(CFG);
        s.event(Event::Synced);
        beat(&s, 1);
        beat(&s, 2);
        let t = |overdue| {
            ModuleTable::<3>::snapshot_after(
                &s,
                0,
                1,
                None,
                &Default::default(),
                table_missing_after_at(1, overdue),
            )
        };
        // Module 2 beats in the next cycle, module 1 does not.
        cycles(&s, 1);
        beat(&s, 2);
        assert_eq!((t(false).missing(), t(true).missing()), (0, 0));
        // The cycle after: module 1's previous heartbeat never came, and by the due
        // phase neither has this one: missing then, not before.
        cycles(&s, 1);
        assert_eq!(t(false).missing(), 0);
        beat(&s, 2);
        assert_eq!(t(false).missing(), 0);
        assert_eq!(t(true).missing(), 0b10);
        assert_eq!(t(true).rows[1].age, 2);
        // It comes back: alive at once.
        beat(&s, 1);
        assert_eq!(t(true).missing(), 0);
        // Every other module silent for two cycles (a lost sync): nobody is missing.
        cycles(&s, 2);
        assert_eq!(t(true).missing(), 0);
        // Their heartbeats coming back one by one before the due phase: still nobody.
        cycles(&s, 1);
        beat(&s, 2);
        assert_eq!(t(false).missing(), 0);
        beat(&s, 1);
        assert_eq!(t(true).missing(), 0);
    }

    #[test]
    fn supervisor_sends_other_changes_once_a_cycle_and_a_missing_module_at_once() {
        let s = SystemStatus::new(CFG);
        s.event(Event::Synced);
        let mut sv = Supervisor::<3>::new(0, 10);
        let own = EngineHealth::default();
        cycles(&s, 1);
        beat(&s, 1);
        beat(&s, 2);
        assert!(sv.poll(&s, own, true, 1, 3).table.is_some());
        // Module 2 announces another state in the same cycle: not yet.
        s.event(Event::Heartbeat {
            module: 2,
            state: 3,
        });
        assert_eq!(sv.poll(&s, own, true, 1, 3).table, None);
        // Next cycle: sent, with the new state.
        cycles(&s, 1);
        beat(&s, 1);
        let t = sv.poll(&s, own, true, 1, 3).table.unwrap();
        assert_eq!(t.rows[2].state, 3);
        // The next cycle: module 1 announces another state, sent (a new cycle); past
        // the due phase (missing age 1) module 2, silent this cycle and the last, turns
        // missing and goes out at once, in the same cycle.
        cycles(&s, 1);
        s.event(Event::Heartbeat {
            module: 1,
            state: 5,
        });
        assert_eq!(
            sv.poll(&s, own, true, 1, 3).table.map(|t| t.missing()),
            Some(0)
        );
        let t = sv.poll(&s, own, true, 1, 1).table.unwrap();
        assert_eq!(t.missing(), 1 << 2);
    }
}
