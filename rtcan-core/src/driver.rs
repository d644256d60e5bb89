//! The driver boundary: what the engine needs from the CAN controller below it and
//! from the middleware above it. boards/ (bxCAN) and rtcan-sim both implement
//! `Controller`; rtcan-pubsub implements `Host`.
use crate::frame::Frame;
use crate::time::Nanos;

/// A transmit mailbox, 0..=2 (bxCAN has three).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Mailbox(pub u8);

/// Number of transmit mailboxes.
pub const MAILBOXES: usize = 3;

/// A CAN controller shaped like bxCAN: three transmit mailboxes sent in identifier
/// priority, abortable while pending. Received frames and transmit completions are fed
/// to the engine by the driver (`Engine::on_rx`, `Engine::on_tx_done`).
pub trait Controller {
    /// Loads `frame` into the free mailbox `mailbox`. The engine only names a mailbox it
    /// knows to be free (it tracks completions), so this cannot fail.
    fn load(&mut self, mailbox: Mailbox, frame: &Frame);
    /// Requests abort of a pending mailbox. The driver reports the result through
    /// `Engine::on_tx_done` (aborted, or sent if it was already on the wire).
    fn abort(&mut self, mailbox: Mailbox);
}

/// Result of a transmission attempt, reported by the driver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TxResult {
    /// Sent and acknowledged.
    Sent,
    /// Aborted on request before it started.
    Aborted,
    /// Lost arbitration or bus error with automatic retransmission off.
    Failed,
}

/// What happened to a message the host asked to send, reported to the host.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TxOutcome {
    /// All fragments sent.
    Sent,
    /// Deadline passed before the last fragment was sent: dropped.
    DeadlineMissed,
    /// HRT slot came and the host had nothing to send.
    NothingToSend,
}

/// Opaque handle the host uses to name a message it owns (e.g. a pool block).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Token(pub u16);

/// Events reported to the host besides messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// Slave locked on the master's sync.
    Synced,
    /// No sync frame for the configured number of cycles.
    SyncLost,
    /// A heartbeat from `module` carried another robot fingerprint.
    FingerprintMismatch { module: u8, fingerprint: u32 },
    /// A cycle began (slot-0 boundary on the master and on a synced slave): drives
    /// per-cycle supervision such as missing-heartbeat counting.
    CycleStart,
    /// A heartbeat from `module` was received (state byte as sent).
    Heartbeat { module: u8, state: u8 },
}

/// The layer above the engine (the middleware). It owns message memory; the engine
/// reads payloads in place (zero copy on transmit).
pub trait Host {
    /// An HRT slot of topic `tx` begins a transfer: return the message to send (the
    /// host latches it until `tx_done`), or `None` if the publisher had nothing.
    fn hrt_sample(&mut self, tx: u8) -> Option<Token>;
    /// Payload bytes of a message handed to the engine (`hrt_sample` or `Engine::submit`).
    fn payload(&self, token: Token) -> &[u8];
    /// The engine is done with `token`.
    fn tx_done(&mut self, tx: u8, token: Option<Token>, outcome: TxOutcome);
    /// A complete message for receive topic `rx` arrived; `sof` is the local time of the
    /// first fragment's start of frame.
    fn deliver(&mut self, rx: u8, payload: &[u8], sof: Nanos);
    /// A protocol event.
    fn event(&mut self, event: Event);
    /// State byte this module announces in its heartbeat (middleware defined).
    fn module_state(&self) -> u8 {
        0
    }
    /// A frame of the reserved update range (docs/PROTOCOL.md §2.3, `service.rs`)
    /// passed the filters; `sof` is its start of frame. Default: ignored.
    fn service_rx(&mut self, _frame: &Frame, _sof: Nanos) {}
    /// The next update-channel frame to send, if any: NRT, in the reserved range (else
    /// the engine discards it). Offered again, unchanged, until `service_sent`: the
    /// engine keeps one such frame in a mailbox at a time, so they leave in order.
    fn service_tx(&mut self) -> Option<Frame> {
        None
    }
    /// The frame last returned by `service_tx` was sent (or discarded as not sendable).
    fn service_sent(&mut self) {}
}
