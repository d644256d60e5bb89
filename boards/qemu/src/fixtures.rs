//! Hand-written tables of a three-module robot (a master and two slaves) and a checking
//! host. These stand in for the rtcan-codegen output until the firmware uses it.
//!
//! | msg id | topic | class | from → to | size (frames) | slots |
//! |---|---|---|---|---|---|
//! | 0x140 | odom | HRT | S1 → M, S2 | 6 (1) | 1 |
//! | 0x141 | scan | HRT | S2 → M | 20 (3) | 2, 3, 4 |
//! | 0x142 | cmd  | SRT 2 ms | M → S1, S2 | 8 (1) | free 5..7 |
//! | 0x143 | log  | SRT 5 ms | S1 → M | 30 (4) | free 5..7 |
//! | 0x144 | diag | NRT | S2 → M | 3 (1) | free 5..7 |
//!
//! 1 Mbit/s, 8 slots of 250 µs (2 ms cycle), hyperperiod 1 cycle.
use rtcan_core::driver::{Event, Host, Token, TxOutcome};
use rtcan_core::fragment::wire_len;
use rtcan_core::id::{Class, MsgId};
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::tables::{BusConfig, CalEntry, NodeTables, RxTopic, TxTopic};
use rtcan_core::time::Nanos;

/// Bus parameters.
pub const BUS: BusConfig = BusConfig {
    bitrate: 1_000_000,
    slots_per_cycle: 8,
    slot_ns: 250_000,
    hyperperiod_cycles: 1,
    cycle_counter_wrap: 32_768,
    laxity: LaxityEncoding::Linear { unit_ns: 100_000 },
    guard_ns: 10_000,
    fingerprint: 0x5EED_CAFE,
};

const fn tx(id: u16, class: Class, size: u16, deadline_ns: Nanos) -> TxTopic {
    TxTopic {
        msg_id: MsgId(id),
        class,
        size,
        deadline_ns,
    }
}
const fn rx(id: u16, size: u16, arena_offset: u16) -> RxTopic {
    RxTopic {
        msg_id: MsgId(id),
        size,
        arena_offset,
    }
}

/// Topic sizes by message ID.
pub const fn size_of(id: u16) -> usize {
    match id {
        0x140 => 6,
        0x141 => 20,
        0x142 => 8,
        0x143 => 30,
        0x144 => 3,
        _ => 0,
    }
}

/// Master (module 0): sends cmd; receives odom, scan, log, diag.
pub const M_TX: [TxTopic; 1] = [tx(0x142, Class::Srt, 8, 2_000_000)];
/// Master receive topics (sorted by ID).
pub const M_RX: [RxTopic; 4] = [
    rx(0x140, 6, 0),
    rx(0x141, 20, 6),
    rx(0x143, 30, 6 + wire_len(20) as u16),
    rx(0x144, 3, 6 + wire_len(20) as u16 + wire_len(30) as u16),
];
/// Master reassembly arena bytes.
pub const M_ARENA: usize = 6 + wire_len(20) + wire_len(30) + 3;
/// Reservation mask of every cycle: sync slot 0, odom slot 1, scan slots 2..=4.
pub const MASKS: [u64; 1] = [0b1_1111];
/// Master tables.
pub const MASTER: NodeTables<'static> = NodeTables {
    bus: BUS,
    module: 0,
    tx: &M_TX,
    rx: &M_RX,
    calendar: &[],
    master_masks: &MASKS,
};

/// Slave 1 (module 1): sends odom (HRT) and log (SRT); receives cmd.
pub const S1_TX: [TxTopic; 2] = [
    tx(0x140, Class::Hrt, 6, 0),
    tx(0x143, Class::Srt, 30, 5_000_000),
];
/// Slave 1 receive topics.
pub const S1_RX: [RxTopic; 1] = [rx(0x142, 8, 0)];
/// Slave 1 calendar.
pub const S1_CAL: [CalEntry; 1] = [CalEntry {
    slot: 1,
    tx: 0,
    fragment: 0,
}];
/// Slave 1 tables.
pub const SLAVE1: NodeTables<'static> = NodeTables {
    bus: BUS,
    module: 1,
    tx: &S1_TX,
    rx: &S1_RX,
    calendar: &S1_CAL,
    master_masks: &[],
};

/// Slave 2 (module 2): sends scan (HRT, 3 frames) and diag (NRT); receives odom, cmd.
pub const S2_TX: [TxTopic; 2] = [tx(0x141, Class::Hrt, 20, 0), tx(0x144, Class::Nrt, 3, 0)];
/// Slave 2 receive topics.
pub const S2_RX: [RxTopic; 2] = [rx(0x140, 6, 0), rx(0x142, 8, 6)];
/// Slave 2 calendar: the three fragments of scan in slots 2, 3, 4 (counter counts down).
pub const S2_CAL: [CalEntry; 3] = [
    CalEntry {
        slot: 2,
        tx: 0,
        fragment: 2,
    },
    CalEntry {
        slot: 3,
        tx: 0,
        fragment: 1,
    },
    CalEntry {
        slot: 4,
        tx: 0,
        fragment: 0,
    },
];
/// Slave 2 tables.
pub const SLAVE2: NodeTables<'static> = NodeTables {
    bus: BUS,
    module: 2,
    tx: &S2_TX,
    rx: &S2_RX,
    calendar: &S2_CAL,
    master_masks: &[],
};

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
    buf: [u8; 32],
}

/// A host that publishes patterned messages and checks what it receives.
pub struct TestHost<const TX: usize, const RX: usize> {
    tx_ids: [u16; TX],
    rx_ids: [u16; RX],
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
        let mut tx_ids = [0; TX];
        for (d, s) in tx_ids.iter_mut().zip(tables.tx) {
            *d = s.msg_id.0;
        }
        let mut rx_ids = [0; RX];
        for (d, s) in rx_ids.iter_mut().zip(tables.rx) {
            *d = s.msg_id.0;
        }
        TestHost {
            tx_ids,
            rx_ids,
            tx: [TxLog::default(); TX],
            rx: [RxLog::default(); RX],
            synced: 0,
            sync_lost: 0,
            heartbeats: 0,
            mismatches: 0,
            verify: true,
        }
    }
    /// Latches the next message of tx topic `tx` and returns its token, or `None` while
    /// the previous one is still with the engine.
    pub fn next_message(&mut self, tx: u8) -> Option<Token> {
        let id = *self.tx_ids.get(tx as usize)?;
        let log = self.tx.get_mut(tx as usize)?;
        if log.busy {
            return None;
        }
        log.busy = true;
        let n = size_of(id).min(log.buf.len());
        pattern(id, log.seq, log.buf.get_mut(..n)?);
        log.seq = log.seq.wrapping_add(1);
        Some(Token(tx as u16))
    }
}

impl<const TX: usize, const RX: usize> Host for TestHost<TX, RX> {
    fn hrt_sample(&mut self, tx: u8) -> Option<Token> {
        self.next_message(tx)
    }
    fn payload(&self, token: Token) -> &[u8] {
        let i = token.0 as usize;
        match (self.tx.get(i), self.tx_ids.get(i)) {
            (Some(log), Some(&id)) => log.buf.get(..size_of(id)).unwrap_or(&[]),
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
        let (Some(log), Some(&id)) = (self.rx.get_mut(rx as usize), self.rx_ids.get(rx as usize))
        else {
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
        let mut expect = [0u8; 32];
        let ok = payload.len() == size_of(id)
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
