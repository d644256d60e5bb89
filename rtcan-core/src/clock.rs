//! The slot clock: maps the node-local clock to bus time. The master's local clock is
//! bus time; a slave aligns on the sync frame's start-of-frame and corrects its rate.
//! OWNER: scheduling helper. Signatures fixed.
use crate::tables::BusConfig;
use crate::time::Nanos;

/// Slot clock state.
#[derive(Clone, Copy, Debug)]
pub struct SlotClock {
    _p: (),
}

impl SlotClock {
    /// Master: bus time 0 (slot 0 of cycle 0) is local time `start`.
    pub fn master(bus: &BusConfig, start: Nanos) -> Self {
        let _ = (bus, start);
        todo!()
    }
    /// Slave, not yet locked.
    pub fn slave(bus: &BusConfig) -> Self {
        let _ = bus;
        todo!()
    }
    /// Slave: a sync frame with `cycle_counter` had its SOF at local time `sof`.
    /// Aligns the offset and updates the rate estimate. Returns true when locked.
    pub fn on_sync(&mut self, sof: Nanos, cycle_counter: u16) -> bool {
        let _ = (sof, cycle_counter);
        todo!()
    }
    /// True once the slave has a usable offset (master: always).
    pub fn is_locked(&self) -> bool {
        todo!()
    }
    /// Bus time (ns since slot 0 of absolute cycle 0) at local time `local`.
    pub fn to_bus(&self, local: Nanos) -> Nanos {
        let _ = local;
        todo!()
    }
    /// Local time at which bus time `bus` occurs.
    pub fn to_local(&self, bus: Nanos) -> Nanos {
        let _ = bus;
        todo!()
    }
}
