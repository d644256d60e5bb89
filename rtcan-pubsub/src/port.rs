//! The glue between the engine and a module's topics: every topic sent on the bus is
//! a [`TxPort`], every topic received from it an [`RxPort`], and [`ModuleHost`]
//! implements `rtcan_core::Host` by dispatching on the engine's topic indices
//! (`tx` = index in `NodeTables::tx`, `rx` = index in `NodeTables::rx`). The generated
//! code only lists the topics in table order. Port methods take and return block
//! tokens (`Token(block)`); `ModuleHost` adds the tx index in the high byte so the
//! engine's tokens are unique across topics (see [`join`]).
use rtcan_core::driver::{Controller, Event, Host, Token, TxOutcome};
use rtcan_core::engine::{Engine, SubmitError};
use rtcan_core::time::Nanos;

use crate::message::Message;
use crate::node::{module_state, Node};
use crate::status::SystemStatus;
use crate::topic::Topic;

/// A topic as the engine sees it on the transmit side.
pub trait TxPort: Sync {
    /// HRT slot: the latched latest value, whose reference moves to the engine;
    /// `None` counts a slot with nothing to send and raises the publisher's flag.
    fn hrt_sample(&self) -> Option<Token>;
    /// Wire bytes of a block the engine holds (empty for an unknown token).
    fn payload(&self, token: Token) -> &[u8];
    /// The engine is done: counts the outcome, raises flags, releases the block.
    fn tx_done(&self, token: Option<Token>, outcome: TxOutcome);
    /// When the block the engine holds as `token` was published (sample age at
    /// transmission); `None` for a token it does not hold.
    fn published_at(&self, token: Token) -> Option<Nanos>;
    /// Oldest SRT/NRT message waiting for `Engine::submit`.
    fn pending(&self) -> Option<Token>;
    /// `token` left the head of the queue: accepted by the engine (reference moves
    /// along) or refused as not submittable (released, counted).
    fn pending_done(&self, token: Token, accepted: bool);
}

/// A topic as the engine sees it on the receive side.
pub trait RxPort: Sync {
    /// A complete payload arrived: decode and publish to the local subscribers.
    fn deliver(&self, payload: &[u8], sof: Nanos);
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> TxPort for Topic<T, N, S, Q> {
    fn hrt_sample(&self) -> Option<Token> {
        self.hrt_take()
    }
    fn payload(&self, token: Token) -> &[u8] {
        self.wire_bytes(token)
    }
    fn tx_done(&self, token: Option<Token>, outcome: TxOutcome) {
        self.engine_done(token, outcome);
    }
    fn published_at(&self, token: Token) -> Option<Nanos> {
        self.engine_stamp(token)
    }
    fn pending(&self) -> Option<Token> {
        self.pending_peek()
    }
    fn pending_done(&self, token: Token, accepted: bool) {
        self.pending_pop(token, accepted);
    }
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> RxPort for Topic<T, N, S, Q> {
    fn deliver(&self, payload: &[u8], sof: Nanos) {
        self.deliver_bytes(payload, sof);
    }
}

/// Engine tokens name the topic and the block: `tx << 8 | block` (ports use blocks).
pub fn join(tx: u8, block: Token) -> Token {
    Token(u16::from(tx) << 8 | (block.0 & 0xFF))
}

/// Inverse of [`join`]: (tx index, block token).
pub fn split(token: Token) -> (u8, Token) {
    ((token.0 >> 8) as u8, Token(token.0 & 0xFF))
}

/// `rtcan_core::Host` for one module: its transmit and receive topics in table order,
/// its system status and its nodes (whose worst state goes into the heartbeat).
pub struct ModuleHost<'a> {
    tx: &'a [&'a dyn TxPort],
    rx: &'a [&'a dyn RxPort],
    status: &'a SystemStatus,
    nodes: &'a [&'a Node],
    bad_index: u32,
}

impl<'a> ModuleHost<'a> {
    /// Host over the given tables.
    pub const fn new(
        tx: &'a [&'a dyn TxPort],
        rx: &'a [&'a dyn RxPort],
        status: &'a SystemStatus,
        nodes: &'a [&'a Node],
    ) -> Self {
        ModuleHost {
            tx,
            rx,
            status,
            nodes,
            bad_index: 0,
        }
    }

    /// When the message behind engine token `token` (`join(tx, block)`) was published:
    /// what the simulator subtracts from its frame's SOF (sample age at transmission).
    pub fn published_at(&self, token: Token) -> Option<Nanos> {
        let (tx, block) = split(token);
        self.tx.get(usize::from(tx))?.published_at(block)
    }

    /// The module's system status (the protocol side writes the slot grid into it).
    pub fn status(&self) -> &'a SystemStatus {
        self.status
    }

    /// Calls from the engine with a topic index outside the tables (a table mismatch).
    pub fn bad_index(&self) -> u32 {
        self.bad_index
    }

    fn tx_port(&mut self, tx: u8) -> Option<&'a dyn TxPort> {
        let p = self.tx.get(usize::from(tx)).copied();
        if p.is_none() {
            self.bad_index = self.bad_index.saturating_add(1);
        }
        p
    }

    /// Hands every queued SRT/NRT message to the engine, in publish order per topic,
    /// until the engine queue is full. Call it when a topic's `kick` fires (and after
    /// `poll`, which frees queue room). Returns how many were submitted.
    pub fn pump<const RX: usize, const ARENA: usize, const EQ: usize>(
        &mut self,
        engine: &mut Engine<'_, RX, ARENA, EQ>,
        now: Nanos,
        can: &mut impl Controller,
    ) -> usize {
        let mut submitted = 0;
        let ports = self.tx;
        for (i, port) in ports.iter().enumerate() {
            let Ok(tx) = u8::try_from(i) else { break };
            while let Some(block) = port.pending() {
                match engine.submit(now, tx, join(tx, block), can, self) {
                    Ok(()) => {
                        port.pending_done(block, true);
                        submitted += 1;
                    }
                    Err(SubmitError::QueueFull) => return submitted,
                    Err(SubmitError::NotSubmittable) => port.pending_done(block, false),
                }
            }
        }
        submitted
    }
}

impl Host for ModuleHost<'_> {
    fn hrt_sample(&mut self, tx: u8) -> Option<Token> {
        self.tx_port(tx)?.hrt_sample().map(|b| join(tx, b))
    }

    fn payload(&self, token: Token) -> &[u8] {
        let (tx, block) = split(token);
        match self.tx.get(usize::from(tx)) {
            Some(p) => p.payload(block),
            None => &[],
        }
    }

    fn tx_done(&mut self, tx: u8, token: Option<Token>, outcome: TxOutcome) {
        if let Some(p) = self.tx_port(tx) {
            p.tx_done(token.map(|t| split(t).1), outcome);
        }
    }

    fn deliver(&mut self, rx: u8, payload: &[u8], sof: Nanos) {
        match self.rx.get(usize::from(rx)) {
            Some(p) => p.deliver(payload, sof),
            None => self.bad_index = self.bad_index.saturating_add(1),
        }
    }

    fn event(&mut self, event: Event) {
        self.status.event(event);
    }

    fn module_state(&self) -> u8 {
        module_state(self.nodes).as_u8()
    }
}
