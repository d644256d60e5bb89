//! A host for the engine that publishes patterned messages and checks every byte it
//! receives. Topic sizes come from the module's tables (generated from
//! robots/qemu-test.toml, see `crate::robot`), the pattern from the message ID, so a
//! message delivered under the wrong topic, with a wrong size or with mixed-up bytes or
//! fragments is counted as bad.
use crate::bus::Pump;
use crate::robot;
use rtcan_core::driver::{Event, Host, Token, TxOutcome};
use rtcan_core::id::MsgId;
use rtcan_core::tables::{NodeTables, TxTopic};
use rtcan_core::time::Nanos;
use rtcan_pubsub::Message;

/// Largest payload a `TestHost` handles (the test robot's largest topic is 30 bytes).
pub const MAX_PAYLOAD: usize = 32;

/// Whether every topic of `topics` fits a `TestHost` buffer.
const fn fits(mut topics: &[TxTopic]) -> bool {
    while let [t, rest @ ..] = topics {
        if t.size as usize > MAX_PAYLOAD {
            return false;
        }
        topics = rest;
    }
    true
}

// Every topic on the bus is some module's tx topic: a larger topic in robots/qemu-test.toml
// must fail the build, not make `next_message` silently send nothing.
const _: () = assert!(
    fits(&robot::master::TX) && fits(&robot::slave1::TX) && fits(&robot::slave2::TX),
    "a topic of robots/qemu-test.toml is larger than test_host::MAX_PAYLOAD"
);

/// Payload of message number `seq` of topic `id`: sequence number (LE u16) then a
/// pattern of both, so any mix-up of bytes, fragments or messages is detected.
pub fn pattern(id: u16, seq: u16, out: &mut [u8]) {
    for (i, b) in out.iter_mut().enumerate() {
        *b = match i {
            0 => seq as u8,
            1 => (seq >> 8) as u8,
            _ => (seq as usize * 3 + i * 7 + id as usize * 31) as u8,
        };
    }
}

/// Message number `seq` of topic `id` as a typed (generated) message: its wire bytes
/// are `pattern(id, seq)`. `None` only if `T` is larger than `MAX_PAYLOAD`.
pub fn patterned<T: Message>(id: MsgId, seq: u16) -> Option<T> {
    let mut buf = [0u8; MAX_PAYLOAD];
    let bytes = buf.get_mut(..T::SIZE)?;
    pattern(id.0, seq, bytes);
    T::decode(bytes)
}

/// Checks a received typed message of topic `id` byte for byte against the pattern of
/// its sequence number (the first two wire bytes); returns that sequence number, or
/// `None` if any byte differs.
pub fn check_patterned<T: Message>(id: MsgId, msg: &T) -> Option<u16> {
    let (mut got, mut expect) = ([0u8; MAX_PAYLOAD], [0u8; MAX_PAYLOAD]);
    let (got, expect) = (got.get_mut(..T::SIZE)?, expect.get_mut(..T::SIZE)?);
    msg.encode(got);
    let seq = match got {
        [a, b, ..] => u16::from_le_bytes([*a, *b]),
        _ => 0,
    };
    pattern(id.0, seq, expect);
    (got == expect).then_some(seq)
}

/// Per receive topic: what arrived.
#[derive(Clone, Copy, Debug, Default)]
pub struct RxLog {
    /// Messages delivered.
    pub count: u32,
    /// Messages whose bytes did not match the pattern or whose size was wrong.
    pub bad: u32,
    /// Messages whose sequence number did not increase.
    pub out_of_order: u32,
    /// Sequence number of the last message.
    pub last_seq: Option<u16>,
    /// SOF time of the last message (local).
    pub last_sof: Nanos,
}

/// Per transmit topic: what was sent.
#[derive(Clone, Copy, Debug, Default)]
pub struct TxLog {
    /// Next sequence number.
    pub seq: u16,
    /// Message latched by the engine (HRT sample or submit), until `tx_done`.
    pub busy: bool,
    /// Outcomes.
    pub sent: u32,
    /// Deadline missed.
    pub missed: u32,
    /// HRT slots with nothing to send.
    pub empty: u32,
    buf: [u8; MAX_PAYLOAD],
}

/// A host that publishes patterned messages and checks what it receives.
pub struct TestHost<const TX: usize, const RX: usize> {
    /// (message ID, size) of each tx topic, by tx index.
    tx_topics: [(u16, usize); TX],
    /// (message ID, size) of each rx topic, by rx index.
    rx_topics: [(u16, usize); RX],
    /// Transmit logs, by tx index.
    pub tx: [TxLog; TX],
    /// Receive logs, by rx index.
    pub rx: [RxLog; RX],
    /// Events seen: synced, sync lost, heartbeats, fingerprint mismatches.
    pub synced: u32,
    /// Sync lost events.
    pub sync_lost: u32,
    /// Heartbeats received.
    pub heartbeats: u32,
    /// Fingerprint mismatches.
    pub mismatches: u32,
    /// Check payload contents on delivery (off in benchmarks: only the engine is timed).
    pub verify: bool,
}

impl<const TX: usize, const RX: usize> TestHost<TX, RX> {
    /// A host for `tables`.
    pub fn new(tables: &NodeTables<'_>) -> Self {
        let mut tx_topics = [(0, 0); TX];
        for (d, s) in tx_topics.iter_mut().zip(tables.tx) {
            *d = (s.msg_id.0, usize::from(s.size));
        }
        let mut rx_topics = [(0, 0); RX];
        for (d, s) in rx_topics.iter_mut().zip(tables.rx) {
            *d = (s.msg_id.0, usize::from(s.size));
        }
        TestHost {
            tx_topics,
            rx_topics,
            tx: [TxLog::default(); TX],
            rx: [RxLog::default(); RX],
            synced: 0,
            sync_lost: 0,
            heartbeats: 0,
            mismatches: 0,
            verify: true,
        }
    }
    /// The receive log of rx topic `rx` (an empty log for an index outside the tables).
    pub fn rx_log(&self, rx: u8) -> RxLog {
        self.rx.get(usize::from(rx)).copied().unwrap_or_default()
    }
    /// The transmit log of tx topic `tx` (an empty log for an index outside the tables).
    pub fn tx_log(&self, tx: u8) -> TxLog {
        self.tx.get(usize::from(tx)).copied().unwrap_or_default()
    }
    /// Latches the next message of tx topic `tx` and returns its token, or `None` while
    /// the previous one is still with the engine.
    pub fn next_message(&mut self, tx: u8) -> Option<Token> {
        let (id, size) = *self.tx_topics.get(tx as usize)?;
        let log = self.tx.get_mut(tx as usize)?;
        if log.busy {
            return None;
        }
        pattern(id, log.seq, log.buf.get_mut(..size)?);
        log.busy = true;
        log.seq = log.seq.wrapping_add(1);
        Some(Token(tx as u16))
    }
}

// Submits itself (`Station::submit`): nothing queued above the engine.
impl<const TX: usize, const RX: usize> Pump for TestHost<TX, RX> {}

impl<const TX: usize, const RX: usize> Host for TestHost<TX, RX> {
    fn hrt_sample(&mut self, tx: u8) -> Option<Token> {
        self.next_message(tx)
    }
    fn payload(&self, token: Token) -> &[u8] {
        let i = token.0 as usize;
        match (self.tx.get(i), self.tx_topics.get(i)) {
            (Some(log), Some(&(_, size))) => log.buf.get(..size).unwrap_or(&[]),
            _ => &[],
        }
    }
    fn tx_done(&mut self, tx: u8, _token: Option<Token>, outcome: TxOutcome) {
        if let Some(log) = self.tx.get_mut(tx as usize) {
            log.busy = false;
            match outcome {
                TxOutcome::Sent => log.sent += 1,
                TxOutcome::DeadlineMissed => log.missed += 1,
                TxOutcome::NothingToSend => log.empty += 1,
            }
        }
    }
    fn deliver(&mut self, rx: u8, payload: &[u8], sof: Nanos) {
        let (Some(log), Some(&(id, size))) = (
            self.rx.get_mut(rx as usize),
            self.rx_topics.get(rx as usize),
        ) else {
            return;
        };
        log.count += 1;
        log.last_sof = sof;
        if !self.verify {
            return;
        }
        let seq = match payload {
            [a, b, ..] => u16::from_le_bytes([*a, *b]),
            _ => 0,
        };
        let mut expect = [0u8; MAX_PAYLOAD];
        let ok = payload.len() == size
            && expect.get_mut(..payload.len()).is_some_and(|e| {
                pattern(id, seq, e);
                *e == *payload
            });
        if !ok {
            log.bad += 1;
        }
        if log.last_seq.is_some_and(|l| seq <= l) {
            log.out_of_order += 1;
        }
        log.last_seq = Some(seq);
    }
    fn event(&mut self, event: Event) {
        match event {
            Event::Synced => self.synced += 1,
            Event::CycleStart => {}
            Event::SyncLost => self.sync_lost += 1,
            Event::Heartbeat { .. } => self.heartbeats += 1,
            Event::FingerprintMismatch { .. } => self.mismatches += 1,
        }
    }
}
