//! `engine_rx`: a receive table and a sequence of frames, times, polls, overruns and
//! mailbox completions, all drawn from the fuzz input, fed to `rtcan_core::Engine`; the
//! same frames go to the protocol model of `oracle.rs`. After every step the engine's
//! deliveries (topic, exact bytes, first SOF), heartbeat events and receive counters must
//! equal the model's. On the transmit side (§3, §9) every frame the engine loads must be
//! a well-formed sync (master-capable roles only) or this module's own heartbeat, and a
//! plain slave loads nothing before it has heard two well-formed syncs (§5.3: offset and
//! rate).
use rtcan_core::driver::{Event, Mailbox, Token, TxOutcome, TxResult};
use rtcan_core::engine::Engine;
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::{BusConfig, CanId, Controller, Frame, Host, MsgId, NodeTables, RxTopic};

use crate::bytes::Bytes;
use crate::oracle::{dlc_of, frames_of, Delivery, HeartbeatSeen, ModelTopic, Oracle, RxCounts};

/// Receive topics at most (engine `RX`).
const RX: usize = 8;
/// Reassembly arena (engine `ARENA`): 8 topics of up to 299 bytes.
const ARENA: usize = 8 * 300;
/// Robot fingerprint of the bus under test.
const FINGERPRINT: u32 = 0xDEAD_BEEF;
/// Operations per input at most (bounds the run time of one input).
const MAX_OPS: usize = 4096;

/// Which engine role the input selects.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    Slave,
    Backup,
    Master,
    RestartedMaster,
}

/// Records what the engine hands to the host.
#[derive(Default)]
struct RecHost {
    deliveries: Vec<Delivery>,
    heartbeats: Vec<HeartbeatSeen>,
}

impl Host for RecHost {
    fn hrt_sample(&mut self, _tx: u8) -> Option<Token> {
        None // no transmit topics in this harness
    }
    fn payload(&self, _token: Token) -> &[u8] {
        &[]
    }
    fn tx_done(&mut self, _tx: u8, _token: Option<Token>, _outcome: TxOutcome) {}
    fn deliver(&mut self, rx: u8, payload: &[u8], sof: u64) {
        self.deliveries
            .push((usize::from(rx), payload.to_vec(), sof));
    }
    fn event(&mut self, event: Event) {
        match event {
            Event::Heartbeat { module, state } => {
                self.heartbeats.push(HeartbeatSeen::Alive { module, state })
            }
            Event::FingerprintMismatch {
                module,
                fingerprint,
            } => self.heartbeats.push(HeartbeatSeen::Mismatch {
                module,
                fingerprint,
            }),
            Event::Synced | Event::SyncLost | Event::CycleStart => {}
        }
    }
}

/// A controller with three mailboxes that checks what the engine loads.
struct RecCan {
    role: Role,
    module: u8,
    slots: u8,
    /// Frame in each mailbox and whether its abort was requested.
    boxes: [Option<(Frame, bool)>; 3],
    /// Loads seen so far.
    loads: u32,
    /// Well-formed syncs heard so far (set by the harness before each engine call).
    syncs_heard: u32,
}

impl Controller for RecCan {
    fn load(&mut self, mailbox: Mailbox, frame: &Frame) {
        let slot = self.boxes.get_mut(usize::from(mailbox.0));
        assert!(
            matches!(slot, Some(None)),
            "load into mailbox {mailbox:?}, not a free one"
        );
        if let Some(s) = slot {
            *s = Some((*frame, false));
        }
        self.loads += 1;
        let raw = frame.id().raw();
        let (laxity, msg, field) = ((raw >> 23) & 0x3F, (raw >> 7) & 0xFFFF, raw & 0x7F);
        if laxity == 0 && msg < 0x100 {
            assert_ne!(self.role, Role::Slave, "a plain slave sent a sync");
            let mut mask = 0u64;
            for (i, b) in frame.data().iter().enumerate() {
                mask |= u64::from(*b) << (8 * i);
            }
            assert_eq!(
                usize::from(frame.dlc()),
                usize::from(self.slots).div_ceil(8)
            );
            assert_eq!(mask & 1, 1, "sync without slot 0 reserved");
            if self.slots < 64 {
                assert_eq!(mask >> self.slots, 0, "sync mask beyond the cycle");
            }
        } else {
            assert_eq!(
                (laxity, msg, field, frame.dlc()),
                (63, 0x100 + u32::from(self.module), 0, 5),
                "only its own heartbeat: {frame:?}"
            );
            assert_eq!(frame.data().get(..4), Some(&FINGERPRINT.to_le_bytes()[..]));
            if self.role == Role::Slave {
                assert!(
                    self.syncs_heard >= 2,
                    "a slave transmitted after {} syncs",
                    self.syncs_heard
                );
            }
        }
    }
    fn abort(&mut self, mailbox: Mailbox) {
        match self.boxes.get_mut(usize::from(mailbox.0)) {
            Some(Some((_, requested))) => *requested = true,
            _ => panic!("abort of an empty mailbox {mailbox:?}"),
        }
    }
}

/// The receive table drawn from the input: 1..=8 topics, ascending message IDs from
/// 0x0140, sizes 0..=299 (above 256: §7.2 rule 1, every frame dropped as `BadSize`),
/// buffers laid out back to back.
fn topics(input: &mut Bytes<'_>) -> Vec<RxTopic> {
    let n = 1 + usize::from(input.u8()) % RX;
    let mut out = Vec::with_capacity(n);
    let mut msg = 0x0140u16;
    let mut offset = 0u16;
    for _ in 0..n {
        let size = input.u16() % 300;
        out.push(RxTopic {
            msg_id: MsgId(msg),
            size,
            arena_offset: offset,
        });
        offset += size;
        msg = msg.saturating_add(1 + u16::from(input.u8() % 8));
    }
    out
}

/// What one run exercised (for the corpus coverage test): the model's counters, the
/// heartbeat events, deliveries of multi-frame topics, frames the engine loaded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    pub counts: RxCounts,
    pub heartbeats: usize,
    pub multi_frame_deliveries: usize,
    pub loads: u32,
}

/// One fuzz run. Panics (assert) on a mismatch between engine and model.
pub fn run(data: &[u8]) {
    let _ = run_stats(data);
}

/// [`run`], returning what it exercised.
pub fn run_stats(data: &[u8]) -> Stats {
    let mut input = Bytes::new(data);
    let role = match input.u8() % 4 {
        0 => Role::Slave,
        1 => Role::Backup,
        2 => Role::Master,
        _ => Role::RestartedMaster,
    };
    let slots = 2 + input.u8() % 63;
    let module = input.u8() % 64;
    let rx = topics(&mut input);
    let masks = [input.u64(), input.u64(), input.u64()];
    let bus = BusConfig {
        bitrate: 1_000_000,
        slots_per_cycle: slots,
        slot_ns: 200_000,
        hyperperiod_cycles: 3,
        cycle_counter_wrap: 32_766,
        laxity: LaxityEncoding::Linear { unit_ns: 100_000 },
        guard_ns: 10_000,
        fingerprint: FINGERPRINT,
    };
    let master_masks: &[u64] = if matches!(role, Role::Master | Role::RestartedMaster) {
        &masks
    } else {
        &[]
    };
    let tables = NodeTables {
        bus,
        module,
        tx: &[],
        rx: &rx,
        calendar: &[],
        master_masks,
    };
    let mut now: u64 = u64::from(input.u32());
    let mut engine: Engine<'_, RX, ARENA, 4> = Engine::new(tables, now);
    match role {
        Role::Backup => engine.set_backup(1 + input.u8() % 3, &masks),
        Role::RestartedMaster => engine.listen_first(),
        Role::Slave | Role::Master => {}
    }
    let mut oracle = Oracle::new(
        slots,
        FINGERPRINT,
        rx.iter()
            .map(|t| ModelTopic {
                msg_id: t.msg_id.0,
                size: usize::from(t.size),
            })
            .collect(),
    );
    let mut host = RecHost::default();
    let mut can = RecCan {
        role,
        module,
        slots,
        boxes: [None; 3],
        loads: 0,
        syncs_heard: 0,
    };
    let mut wake = engine.poll(now, &mut can, &mut host);
    let mut ops = 0;
    while !input.is_empty() && ops < MAX_OPS {
        ops += 1;
        now = now.saturating_add(u64::from(input.u8()) * 1_000);
        let mut frames: Vec<Frame> = Vec::new();
        match input.u8() % 10 {
            0 => frames.push(raw_frame(&mut input)),
            1 | 2 => frames.push(topic_frame(&mut input, &rx)),
            3 => frames.extend(transfer(&mut input, &rx)),
            4 => frames.push(sync(&mut input, slots)),
            5 => frames.push(heartbeat(&mut input)),
            6 => {
                engine.on_rx_overrun();
                oracle.overrun();
            }
            7 => {
                // A clock jump: far ahead, or back.
                let d = u64::from(input.u32()) * 1_000;
                now = if input.u8() & 1 == 0 {
                    now.saturating_add(d)
                } else {
                    now.saturating_sub(d)
                };
                wake = engine.poll(now, &mut can, &mut host);
            }
            8 => complete_mailbox(&mut input, &mut engine, &mut can, &mut host, now),
            _ => wake = engine.poll(now, &mut can, &mut host),
        }
        for f in frames {
            // Polls due before the frame's SOF run first, as a driver's timer would.
            if wake <= now {
                wake = engine.poll(now, &mut can, &mut host);
            }
            oracle.frame(f.id().raw(), f.data(), now);
            engine.on_rx(&f, now, &mut can, &mut host);
            can.syncs_heard = oracle.valid_syncs;
            now = now.saturating_add(130_000);
        }
        compare(&engine, &oracle, &host);
    }
    Stats {
        counts: oracle.counts,
        heartbeats: oracle.heartbeats.len(),
        multi_frame_deliveries: oracle
            .deliveries
            .iter()
            .filter(|(i, ..)| rx.get(*i).is_some_and(|t| t.size > 8))
            .count(),
        loads: can.loads,
    }
}

/// The engine's receive counters as the model names them.
fn engine_counts<const R: usize, const A: usize, const Q: usize>(
    e: &Engine<'_, R, A, Q>,
) -> RxCounts {
    let c = e.counters();
    RxCounts {
        unknown_id: c.rx_unknown_id,
        bad_dlc: c.rx_bad_dlc,
        out_of_order: c.rx_out_of_order,
        other_transfer: c.rx_other_transfer,
        incomplete: c.rx_incomplete,
        bad_size: c.rx_bad_size,
        bad_sync: c.rx_bad_sync,
        bad_heartbeat: c.rx_bad_heartbeat,
        overrun: c.rx_overrun,
        delivered: c.rx_delivered,
    }
}

fn compare<const R: usize, const A: usize, const Q: usize>(
    engine: &Engine<'_, R, A, Q>,
    oracle: &Oracle,
    host: &RecHost,
) {
    assert_eq!(
        host.deliveries, oracle.deliveries,
        "deliveries differ from the model"
    );
    assert_eq!(
        host.heartbeats, oracle.heartbeats,
        "heartbeat events differ from the model"
    );
    assert_eq!(
        engine_counts(engine),
        oracle.counts,
        "counters differ from the model"
    );
}

/// Any identifier, DLC and data.
fn raw_frame(input: &mut Bytes<'_>) -> Frame {
    let raw = input.u32() & CanId::MAX_RAW;
    let dlc = input.u8() % 9;
    let data = input.array8(usize::from(dlc));
    make(raw, dlc, data)
}

fn make(raw: u32, dlc: u8, data: [u8; 8]) -> Frame {
    CanId::from_raw(raw & CanId::MAX_RAW)
        .and_then(|id| Frame::from_parts(id, dlc.min(8), data))
        .expect("a 29-bit identifier and a DLC <= 8 always make a frame")
}

/// A frame of a receive topic (or a message ID just past the table): any laxity, any
/// fragment field; the DLC right for its counter or any.
fn topic_frame(input: &mut Bytes<'_>, rx: &[RxTopic]) -> Frame {
    let pick = usize::from(input.u8());
    let (msg, size) = match rx.get(pick % (rx.len() + 1)) {
        Some(t) => (u32::from(t.msg_id.0), usize::from(t.size)),
        None => (0x0140 + (pick as u32 % 0x40), 8),
    };
    let laxity = u32::from(input.u8() % 64);
    let field = u32::from(input.u8() & 0x7F);
    let count = frames_of(size);
    let k = if count <= 1 {
        0
    } else {
        32 - (count - 1).leading_zeros()
    };
    let counter = if count == 1 {
        field
    } else {
        field & ((1 << k) - 1)
    };
    let how = input.u8();
    let dlc = match dlc_of(size, counter) {
        Some(d) if how & 0x80 == 0 => d as u8,
        _ => how % 9,
    };
    let data = input.array8(usize::from(dlc));
    make(laxity << 23 | msg << 7 | field, dlc, data)
}

/// All fragments of one transfer of a receive topic with a transfer ID, minus those the
/// loss mask removes (and, rarely, one duplicated).
fn transfer(input: &mut Bytes<'_>, rx: &[RxTopic]) -> Vec<Frame> {
    let Some(t) = rx.get(usize::from(input.u8()) % rx.len().max(1)) else {
        return Vec::new();
    };
    let size = usize::from(t.size).min(256);
    let tid = u32::from(input.u8());
    let laxity = u32::from(input.u8() % 64);
    let lose = if input.u8() & 1 == 0 { 0 } else { input.u32() };
    let dup = input.u8();
    let fill = input.u8();
    let count = frames_of(size);
    let k = if count <= 1 {
        0
    } else {
        32 - (count - 1).leading_zeros()
    };
    let mut out = Vec::new();
    for i in 0..count {
        let c = count - 1 - i;
        let field = if count == 1 {
            0
        } else {
            ((tid << k) | c) & 0x7F
        };
        let dlc = dlc_of(size, c).unwrap_or(0) as u8;
        let mut data = [0u8; 8];
        for (j, b) in data.iter_mut().enumerate().take(usize::from(dlc)) {
            *b = fill.wrapping_add((8 * i as usize + j) as u8);
        }
        let f = make(laxity << 23 | u32::from(t.msg_id.0) << 7 | field, dlc, data);
        if lose & (1 << (i % 32)) == 0 {
            out.push(f);
        }
        if u32::from(dup) == i + 1 {
            out.push(f);
        }
    }
    out
}

/// A sync frame: well-formed (counter, mask with bit 0 set and no bit past the cycle,
/// DLC `ceil(slots / 8)`) or with any DLC and mask bits.
fn sync(input: &mut Bytes<'_>, slots: u8) -> Frame {
    let counter = u32::from(input.u16() & 0x7FFF);
    let mask = input.u64();
    let how = input.u8();
    if how & 0x80 == 0 {
        let within = if slots >= 64 {
            u64::MAX
        } else {
            (1u64 << slots) - 1
        };
        make(
            counter,
            slots.div_ceil(8),
            ((mask | 1) & within).to_le_bytes(),
        )
    } else {
        let dlc = how % 9;
        let mut data = mask.to_le_bytes();
        for b in data.iter_mut().skip(usize::from(dlc)) {
            *b = 0;
        }
        make(counter, dlc, data)
    }
}

/// A heartbeat: well-formed with this robot's or another fingerprint, or with a wrong
/// laxity, fragment or DLC.
fn heartbeat(input: &mut Bytes<'_>) -> Frame {
    let module = u32::from(input.u8() % 64);
    let how = input.u8();
    let fp = if how & 1 == 0 {
        FINGERPRINT
    } else {
        input.u32()
    };
    let state = input.u8();
    let (laxity, field, dlc) = if how & 2 == 0 {
        (63, 0, 5)
    } else {
        (
            u32::from(input.u8() % 64),
            u32::from(input.u8() & 0x7F),
            input.u8() % 9,
        )
    };
    let [a, b, c, d] = fp.to_le_bytes();
    make(
        laxity << 23 | (0x100 + module) << 7 | field,
        dlc,
        [a, b, c, d, state, 0, 0, 0],
    )
}

/// Reports a loaded mailbox done, as the driver would: aborted only after an abort
/// request, else sent or failed.
fn complete_mailbox<const R: usize, const A: usize, const Q: usize>(
    input: &mut Bytes<'_>,
    engine: &mut Engine<'_, R, A, Q>,
    can: &mut RecCan,
    host: &mut RecHost,
    now: u64,
) {
    let pick = input.u8();
    let i = usize::from(pick % 3);
    let Some(Some((_, requested))) = can.boxes.get(i).copied() else {
        return;
    };
    let result = if requested && pick & 0x40 == 0 {
        TxResult::Aborted
    } else if pick & 0x80 != 0 {
        TxResult::Failed
    } else {
        TxResult::Sent
    };
    if let Some(b) = can.boxes.get_mut(i) {
        *b = None;
    }
    engine.on_tx_done(Mailbox(i as u8), result, now, can, host);
}
