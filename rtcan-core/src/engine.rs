//! The protocol engine of one module: events in (slot timer, RX, TX done, submit),
//! actions out (load/abort mailboxes through `Controller`, deliver through `Host`,
//! next timer deadline as the return value of `poll`). OWNER: lead.
use crate::counters::Counters;
use crate::driver::{Controller, Host, Mailbox, Token, TxResult};
use crate::frame::Frame;
use crate::tables::NodeTables;
use crate::time::Nanos;

/// Why `Engine::submit` refused a message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SubmitError {
    /// The transmit queue is full (capacity `Q`).
    QueueFull,
    /// `tx` is not a topic of this module, or it is HRT (HRT is sampled, not submitted).
    NotSubmittable,
}

/// Engine of one module. `RX`: receive topics; `ARENA`: reassembly bytes; `Q`: SRT/NRT
/// queue capacity. All sizes come from the generated per-module constants.
pub struct Engine<'t, const RX: usize, const ARENA: usize, const Q: usize> {
    tables: NodeTables<'t>,
    counters: Counters,
}

impl<'t, const RX: usize, const ARENA: usize, const Q: usize> Engine<'t, RX, ARENA, Q> {
    /// A master if `tables.master_masks` is non-empty, else a slave waiting for sync.
    pub fn new(tables: NodeTables<'t>, now: Nanos) -> Self {
        let _ = now;
        Engine { tables, counters: Counters::default() }
    }
    /// Does everything due at local time `now` (slot boundaries, window closes) and
    /// returns the local time at which it must be called next.
    pub fn poll(&mut self, now: Nanos, can: &mut impl Controller, host: &mut impl Host) -> Nanos {
        let _ = (now, can, host, &self.tables);
        todo!()
    }
    /// A frame passed the filters; `sof` is its start-of-frame local timestamp.
    pub fn on_rx(&mut self, frame: &Frame, sof: Nanos, can: &mut impl Controller, host: &mut impl Host) {
        let _ = (frame, sof, can, host);
        todo!()
    }
    /// Mailbox `mailbox` finished with `result` at local time `now`.
    pub fn on_tx_done(
        &mut self,
        mailbox: Mailbox,
        result: TxResult,
        now: Nanos,
        can: &mut impl Controller,
        host: &mut impl Host,
    ) {
        let _ = (mailbox, result, now, can, host);
        todo!()
    }
    /// Queues an SRT/NRT message of topic `tx` (deadline = now + topic deadline).
    pub fn submit(
        &mut self,
        now: Nanos,
        tx: u8,
        token: Token,
        can: &mut impl Controller,
        host: &mut impl Host,
    ) -> Result<(), SubmitError> {
        let _ = (now, tx, token, can, host);
        todo!()
    }
    /// The driver saw an RX FIFO overrun.
    pub fn on_rx_overrun(&mut self) {
        Counters::bump(&mut self.counters.rx_overrun);
    }
    /// The driver saw bus-off.
    pub fn on_bus_off(&mut self) {
        Counters::bump(&mut self.counters.bus_off);
    }
    /// Counters.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }
}
