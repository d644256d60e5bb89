//! CAN fault confinement of one simulated controller (ISO 11898-1 §12, Bosch CAN 2.0
//! §8): transmit and receive error counters, error-active / error-passive / bus-off,
//! and the recovery from bus-off after 128 occurrences of 11 consecutive recessive bits.
//!
//! Rules modelled (the bus applies them per frame, `bus.rs`):
//! - a transmitter whose frame is destroyed: TEC += 8;
//! - a receiver that detects the error: REC += 1;
//! - a frame sent successfully: TEC -= 1 (not below 0);
//! - a frame received successfully: REC -= 1 if 1..=127, and back to 119 if above 127
//!   (the standard allows 119..=127);
//! - TEC > 255: bus-off; the controller neither sends nor receives; it counts runs of
//!   11 recessive bits and after 128 of them returns error-active with TEC = REC = 0
//!   (bxCAN with automatic bus-off management).
//!
//! Not modelled: the REC += 8 of a receiver that sees a dominant bit after its own error
//! flag, and the transmitter exception for ACK errors while error-passive (no node here
//! transmits alone on a bus without acknowledgers).
use rtcan_core::confinement::{ErrorState, Level};

/// Transmit error counter above which the controller goes bus-off.
pub const BUS_OFF_TEC: u16 = 255;
/// Runs of 11 recessive bits a bus-off controller must see before it recovers.
pub const RECOVERY_RUNS: u32 = 128;
/// Recessive bits in one run.
pub const RUN_BITS: u64 = 11;
/// Recessive bits that end every frame, good or destroyed: ACK delimiter + end of frame +
/// intermission (11), or error delimiter + intermission (11).
pub const TRAILING_RECESSIVE_BITS: u64 = 11;

/// Fault-confinement state of one controller.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Confinement {
    tec: u16,
    rec: u16,
    bus_off: bool,
    runs: u32,
    /// Times the controller went bus-off.
    pub bus_off_entries: u32,
}

impl Confinement {
    /// The state as the driver reports it to the engine.
    pub fn state(&self) -> ErrorState {
        ErrorState {
            tec: self.tec,
            rec: self.rec,
            bus_off: self.bus_off,
        }
    }

    /// Fault-confinement level.
    pub fn level(&self) -> Level {
        self.state().level()
    }

    /// Off the bus.
    pub fn is_bus_off(&self) -> bool {
        self.bus_off
    }

    /// Back to power-on values (error-active, TEC = REC = 0), keeping the bus-off count:
    /// the controller was reset with its MCU.
    pub fn reset(&mut self) {
        *self = Confinement {
            bus_off_entries: self.bus_off_entries,
            ..Confinement::default()
        };
    }

    /// This controller's frame was destroyed by an error.
    pub fn tx_error(&mut self) {
        if self.bus_off {
            return;
        }
        self.tec = self.tec.saturating_add(8);
        if self.tec > BUS_OFF_TEC {
            self.bus_off = true;
            self.runs = 0;
            self.bus_off_entries += 1;
        }
    }

    /// The bus is held dominant (a stuck transceiver): after its error flag the
    /// controller keeps seeing dominant bits, REC +8 per 8 (8-bit in bxCAN: it ends at
    /// 255, error-passive), and if it was transmitting TEC +8 per 8: bus-off.
    pub fn stuck_dominant(&mut self, transmitting: bool) {
        if self.bus_off {
            return;
        }
        self.rec = 255;
        if transmitting {
            self.tec = BUS_OFF_TEC + 1;
            self.bus_off = true;
            self.runs = 0;
            self.bus_off_entries += 1;
        }
    }

    /// Alone on a cut stub: its frames get no acknowledgement, TEC +8 each until
    /// error-passive, where acknowledgement errors no longer count (ISO 11898-1 §12.1.4.2
    /// exception): TEC ends at 128 or above.
    pub fn unacknowledged(&mut self) {
        if !self.bus_off {
            self.tec = self.tec.max(128);
        }
    }

    /// This controller's frame was sent and acknowledged.
    pub fn tx_ok(&mut self) {
        if !self.bus_off {
            self.tec = self.tec.saturating_sub(1);
        }
    }

    /// This controller detected an error in a frame it was receiving.
    pub fn rx_error(&mut self) {
        if !self.bus_off {
            // bxCAN's REC is 8 bits wide; past 127 only "passive" matters.
            self.rec = self.rec.saturating_add(1).min(255);
        }
    }

    /// This controller received a frame without error.
    pub fn rx_ok(&mut self) {
        if self.bus_off {
            return;
        }
        if self.rec > 127 {
            self.rec = 119;
        } else {
            self.rec = self.rec.saturating_sub(1);
        }
    }

    /// The bus was recessive for `bits` consecutive bits; returns true if this ended
    /// bus-off (every complete run of 11 counts; the remainder is not carried over, as a
    /// dominant bit follows the run).
    pub fn recessive(&mut self, bits: u64) -> bool {
        if !self.bus_off {
            return false;
        }
        let runs = u32::try_from(bits / RUN_BITS).unwrap_or(u32::MAX);
        self.runs = self.runs.saturating_add(runs);
        if self.runs >= RECOVERY_RUNS {
            *self = Confinement {
                bus_off_entries: self.bus_off_entries,
                ..Confinement::default()
            };
            return true;
        }
        false
    }

    /// Recessive bits still needed to recover (0 when not bus-off), if the bus stays
    /// idle: what an idle bus must give a bus-off node.
    pub fn recovery_bits_left(&self) -> u64 {
        if self.bus_off {
            u64::from(RECOVERY_RUNS.saturating_sub(self.runs)) * RUN_BITS
        } else {
            0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counters_follow_the_iso_rules_exactly() {
        let mut c = Confinement::default();
        for _ in 0..3 {
            c.tx_error();
        }
        c.tx_ok();
        for _ in 0..5 {
            c.rx_error();
        }
        c.rx_ok();
        assert_eq!(
            c.state(),
            ErrorState {
                tec: 23,
                rec: 4,
                bus_off: false
            }
        );
        assert_eq!(c.level(), Level::Active);
        // Counters never go below zero.
        let mut z = Confinement::default();
        z.tx_ok();
        z.rx_ok();
        assert_eq!((z.state().tec, z.state().rec), (0, 0));
    }

    #[test]
    fn error_passive_at_128_and_rec_back_to_119() {
        let mut c = Confinement::default();
        for _ in 0..15 {
            c.tx_error();
        }
        assert_eq!((c.state().tec, c.level()), (120, Level::Active));
        c.tx_error();
        assert_eq!((c.state().tec, c.level()), (128, Level::Passive));
        c.tx_ok();
        assert_eq!((c.state().tec, c.level()), (127, Level::Active));
        let mut r = Confinement::default();
        for _ in 0..128 {
            r.rx_error();
        }
        assert_eq!((r.state().rec, r.level()), (128, Level::Passive));
        r.rx_ok();
        assert_eq!((r.state().rec, r.level()), (119, Level::Active));
        for _ in 0..1000 {
            r.rx_error();
        }
        assert_eq!(r.state().rec, 255);
    }

    #[test]
    fn bus_off_when_tec_passes_255_not_at_it() {
        let mut c = Confinement::default();
        // 31 errors: 248; one success: 247; one more error: 255 — still on the bus.
        for _ in 0..31 {
            c.tx_error();
        }
        c.tx_ok();
        c.tx_error();
        assert_eq!(c.state().tec, 255);
        assert!(!c.is_bus_off());
        assert_eq!(c.level(), Level::Passive);
        c.tx_error();
        assert!(c.is_bus_off());
        assert_eq!(c.level(), Level::BusOff);
        assert_eq!(c.bus_off_entries, 1);
        // Off the bus nothing counts.
        let before = c.state();
        c.tx_ok();
        c.rx_error();
        c.rx_ok();
        c.tx_error();
        assert_eq!(c.state(), before);
        // 32 errors in a row from 0 (8 x 32 = 256 > 255).
        let mut d = Confinement::default();
        for k in 1..=32 {
            d.tx_error();
            assert_eq!(d.is_bus_off(), k == 32, "{k}");
        }
    }

    #[test]
    fn recovery_takes_128_runs_of_11_recessive_bits() {
        let mut c = Confinement::default();
        for _ in 0..32 {
            c.tx_error();
        }
        assert_eq!(c.recovery_bits_left(), 128 * 11);
        // 127 frames on a busy bus: each ends with exactly one run of 11.
        for _ in 0..127 {
            assert!(!c.recessive(TRAILING_RECESSIVE_BITS));
        }
        // A run of 10 does not count; 21 counts once.
        assert!(!c.recessive(10));
        assert_eq!(c.recovery_bits_left(), 11);
        assert!(c.recessive(21));
        assert_eq!(c.state(), ErrorState::default());
        assert_eq!(c.level(), Level::Active);
        assert_eq!(c.bus_off_entries, 1);
        // On an idle bus: exactly 1408 bits.
        for _ in 0..32 {
            c.tx_error();
        }
        assert!(!c.recessive(1407)); // 127 runs and 10 bits
        assert_eq!(c.recovery_bits_left(), 11);
        let mut e = Confinement::default();
        for _ in 0..32 {
            e.tx_error();
        }
        assert!(e.recessive(1408));
        assert_eq!(e.bus_off_entries, 1);
    }
}
