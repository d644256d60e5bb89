//! The module-state topics on the simulated Triskar2 (docs/SERVICES.md §1): every module
//! publishes its engine health (`health_<module>`), the current sync master its module
//! table (`module_state_<module>`), through the generated `module_state` glue of each
//! module and a `supervision::Supervisor` — the same calls a firmware makes. What was
//! published and what each module received is logged (`StateLog`) when the run asks for
//! it (`TriskarConfig::supervise`, `module_dies_at`), so a test compares the table *as
//! received over the bus* with the engines' own counters.
use rtcan::core::Nanos;
use rtcan::pubsub::{supervision, EngineHealth};
use rtcan::robot_toml as robot;

use robot::supervision::{Supervisor, Table, PUBLISH_CYCLES};

/// One module's generated module-state glue and its supervisor.
pub struct StateIo {
    pub sv: Supervisor,
    me: u8,
    publish_health: fn(EngineHealth, Nanos) -> bool,
    publish_table: fn(&Table, Nanos) -> bool,
    drain_health: fn(&mut dyn FnMut(u8, EngineHealth)),
    drain_tables: fn(&mut dyn FnMut(Table)),
}

macro_rules! io {
    ($m:ident) => {
        StateIo {
            sv: Supervisor::new(robot::$m::INDEX, PUBLISH_CYCLES),
            me: robot::$m::INDEX,
            publish_health: robot::$m::module_state::publish_health,
            publish_table: robot::$m::module_state::publish_table,
            drain_health: robot::$m::module_state::drain_health,
            drain_tables: robot::$m::module_state::drain_tables,
        }
    };
}

impl StateIo {
    /// The glue of module `n` (bus index = generated index).
    pub fn for_module(n: usize) -> StateIo {
        match n {
            0 => io!(gateway),
            1 => io!(motor1),
            2 => io!(motor2),
            3 => io!(motor3),
            4 => io!(proximity),
            _ => io!(psu),
        }
    }

    /// The module powered on again: nothing received, nothing published yet.
    pub fn reboot(&mut self) {
        self.sv = Supervisor::new(self.me, PUBLISH_CYCLES);
    }

    /// One pass of the module's loop: take in the healths received, publish what is
    /// due, read the tables received. `now` local, `global` for the log. Returns when
    /// the sync master wants its next pass: at the next due phase of the heartbeats, so
    /// a module whose heartbeat did not come is shown missing then, not at whatever
    /// wakes the module next.
    pub fn poll(
        &mut self,
        status: &rtcan::pubsub::SystemStatus,
        own: EngineHealth,
        is_master: bool,
        now: Nanos,
        global: Nanos,
        log: &mut StateLog,
    ) -> Option<Nanos> {
        let sv = &mut self.sv;
        (self.drain_health)(&mut |m, h| sv.health_rx(m, h));
        let grid = status.grid();
        let due = robot::supervision::HEARTBEAT_DUE_NS;
        let overdue = supervision::heartbeats_overdue(grid, now, due);
        let p = self.sv.poll(
            status,
            own,
            is_master,
            robot::FINGERPRINT,
            supervision::table_missing_after_at(robot::supervision::HEARTBEAT_CYCLES, overdue),
        );
        let me = usize::from(self.me);
        if let Some(h) = p.health {
            let ok = (self.publish_health)(h, now);
            if log.record && ok {
                log.health_tx.push((global, me, h));
            }
        }
        if let Some(t) = p.table {
            let ok = (self.publish_table)(&t, now);
            if log.record && ok {
                log.table_tx.push((global, t));
            }
        }
        let record = log.record;
        let rx = &mut log.table_rx;
        (self.drain_tables)(&mut |t| {
            if record {
                rx.push((global, me, t));
            }
        });
        is_master
            .then(|| supervision::next_due(grid, now, due))
            .flatten()
    }
}

/// What the module-state topics carried in one run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StateLog {
    /// Log at all (a live run would grow without end).
    pub record: bool,
    /// Health publications: global time, module, value.
    pub health_tx: Vec<(Nanos, usize, EngineHealth)>,
    /// Table publications: global time, table (its `reporter` published it).
    pub table_tx: Vec<(Nanos, Table)>,
    /// Tables received over the bus: global time, receiving module, table.
    pub table_rx: Vec<(Nanos, usize, Table)>,
}
