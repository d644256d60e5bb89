//! CAN fault confinement as the driver reports it (ISO 11898-1 §12): transmit and receive
//! error counters and bus-off. The controller does the counting; the engine reacts
//! (docs/PROTOCOL.md §5.7): error-passive is counted and reported, bus-off stops the
//! module until it has recovered and re-synchronised.

/// Error counters above this make a controller error-passive (ISO 11898-1).
pub const ERROR_PASSIVE_LIMIT: u16 = 128;

/// Fault-confinement state of the CAN controller.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ErrorState {
    /// Transmit error counter (bxCAN `ESR.TEC`).
    pub tec: u16,
    /// Receive error counter (bxCAN `ESR.REC`).
    pub rec: u16,
    /// The controller is bus-off (TEC passed 255; bxCAN `ESR.BOFF`).
    pub bus_off: bool,
}

/// Fault-confinement level derived from an `ErrorState`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Level {
    /// Both counters below 128: normal.
    Active,
    /// A counter at 128 or above: error flags are recessive, the node can no longer
    /// destroy other nodes' frames; it still transmits.
    Passive,
    /// Off the bus until the controller has seen 128 × 11 recessive bits.
    BusOff,
}

impl ErrorState {
    /// Fault-confinement level.
    pub const fn level(&self) -> Level {
        if self.bus_off {
            Level::BusOff
        } else if self.tec >= ERROR_PASSIVE_LIMIT || self.rec >= ERROR_PASSIVE_LIMIT {
            Level::Passive
        } else {
            Level::Active
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels() {
        let s = |tec, rec, bus_off| ErrorState { tec, rec, bus_off }.level();
        assert_eq!(s(0, 0, false), Level::Active);
        assert_eq!(s(127, 127, false), Level::Active);
        assert_eq!(s(128, 0, false), Level::Passive);
        assert_eq!(s(0, 128, false), Level::Passive);
        assert_eq!(s(0, 0, true), Level::BusOff);
        assert_eq!(s(255, 255, true), Level::BusOff);
    }
}
