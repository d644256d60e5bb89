//! Instruction counts of the engine's per-event work on a Cortex-M3, each kind of event
//! measured on its own (QEMU `-icount`, see meter.rs): a slot boundary that only
//! advances the schedule, a boundary that loads this module's HRT frame, a boundary that
//! opens a free window and fills the mailboxes, one received frame (single-frame topic,
//! middle and last fragment of a 20-byte message, sync), and a TX completion.
//! The host side is trivial (fixed payloads, deliveries only counted) so the figures are
//! the engine's own.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use lm3s6965 as _;
use rtcan_board_qemu::meter::{report, Stat, SysTickMeter};
use rtcan_board_qemu::{check, pass};
use rtcan_core::driver::{Controller, Event, Host, Mailbox, Token, TxOutcome, TxResult};
use rtcan_core::engine::Engine;
use rtcan_core::fragment::fragment_data;
use rtcan_core::frame::Frame;
use rtcan_core::id::{CanId, Class, MsgId};
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::sync::{sync_frame, Sync};
use rtcan_core::tables::{BusConfig, CalEntry, NodeTables, RxTopic, TxTopic};

const SLOT_NS: u64 = 166_666;
const BUS: BusConfig = BusConfig {
    bitrate: 1_000_000,
    slots_per_cycle: 60,
    slot_ns: SLOT_NS,
    hyperperiod_cycles: 1,
    cycle_counter_wrap: 1 << 15,
    laxity: LaxityEncoding::Linear {
        unit_ns: SLOT_NS as u32,
    },
    guard_ns: 2_000,
    fingerprint: 0x1234_5678,
};
/// The RTCAN paper's benchmark mask (Fig. 3): 40 of 60 slots reserved.
const MASK: u64 = 0x038E_38FF_8E38_FFFF;
const MASKS: [u64; 1] = [MASK];
/// Node A of the paper: H_A every 6 slots from 1, H_B every 30 from 4, H_C at 10.
const TX: [TxTopic; 5] = [
    TxTopic {
        msg_id: MsgId(0x140),
        class: Class::Hrt,
        size: 8,
        deadline_ns: 0,
    },
    TxTopic {
        msg_id: MsgId(0x141),
        class: Class::Hrt,
        size: 8,
        deadline_ns: 0,
    },
    TxTopic {
        msg_id: MsgId(0x142),
        class: Class::Hrt,
        size: 8,
        deadline_ns: 0,
    },
    TxTopic {
        msg_id: MsgId(0x143),
        class: Class::Srt,
        size: 8,
        deadline_ns: 10_000_000,
    },
    TxTopic {
        msg_id: MsgId(0x144),
        class: Class::Srt,
        size: 20,
        deadline_ns: 10_000_000,
    },
];
const CAL: [CalEntry; 13] = [
    CalEntry {
        slot: 1,
        tx: 0,
        fragment: 0,
    },
    CalEntry {
        slot: 4,
        tx: 1,
        fragment: 0,
    },
    CalEntry {
        slot: 7,
        tx: 0,
        fragment: 0,
    },
    CalEntry {
        slot: 10,
        tx: 2,
        fragment: 0,
    },
    CalEntry {
        slot: 13,
        tx: 0,
        fragment: 0,
    },
    CalEntry {
        slot: 19,
        tx: 0,
        fragment: 0,
    },
    CalEntry {
        slot: 25,
        tx: 0,
        fragment: 0,
    },
    CalEntry {
        slot: 31,
        tx: 0,
        fragment: 0,
    },
    CalEntry {
        slot: 34,
        tx: 1,
        fragment: 0,
    },
    CalEntry {
        slot: 37,
        tx: 0,
        fragment: 0,
    },
    CalEntry {
        slot: 43,
        tx: 0,
        fragment: 0,
    },
    CalEntry {
        slot: 49,
        tx: 0,
        fragment: 0,
    },
    CalEntry {
        slot: 55,
        tx: 0,
        fragment: 0,
    },
];
const RX: [RxTopic; 2] = [
    RxTopic {
        msg_id: MsgId(0x150),
        size: 8,
        arena_offset: 0,
    },
    RxTopic {
        msg_id: MsgId(0x151),
        size: 20,
        arena_offset: 8,
    },
];
const MASTER: NodeTables<'static> = NodeTables {
    bus: BUS,
    module: 0,
    tx: &TX,
    rx: &[],
    calendar: &CAL,
    master_masks: &MASKS,
};
const SLAVE: NodeTables<'static> = NodeTables {
    bus: BUS,
    module: 1,
    tx: &[],
    rx: &RX,
    calendar: &[],
    master_masks: &[],
};

/// Records loads; completions are fed back by the benchmark loop.
struct Can {
    loaded: [Option<Frame>; 3],
    loads: u32,
}

impl Controller for Can {
    fn load(&mut self, mailbox: Mailbox, frame: &Frame) {
        if let Some(m) = self.loaded.get_mut(mailbox.0 as usize) {
            *m = Some(*frame);
        }
        self.loads += 1;
    }
    fn abort(&mut self, _mailbox: Mailbox) {}
}

struct Bench {
    hrt: [u8; 8],
    srt8: [u8; 8],
    srt20: [u8; 20],
    delivered: u32,
}

impl Host for Bench {
    fn hrt_sample(&mut self, _tx: u8) -> Option<Token> {
        Some(Token(0))
    }
    fn payload(&self, token: Token) -> &[u8] {
        match token.0 {
            0 => &self.hrt,
            1 => &self.srt8,
            _ => &self.srt20,
        }
    }
    fn tx_done(&mut self, _tx: u8, _token: Option<Token>, _outcome: TxOutcome) {}
    fn deliver(&mut self, _rx: u8, payload: &[u8], _sof: u64) {
        self.delivered += payload.len() as u32;
    }
    fn event(&mut self, _event: Event) {}
}

#[entry]
fn main() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        rtcan_board_qemu::fail()
    };
    let mut meter = SysTickMeter::new(cp.SYST);
    let mut host = Bench {
        hrt: [1; 8],
        srt8: [2; 8],
        srt20: [3; 20],
        delivered: 0,
    };

    // --- Master: every slot boundary of 3 cycles, classified by what it did. ---
    let mut can = Can {
        loaded: [None; 3],
        loads: 0,
    };
    let mut m = Engine::<'static, 1, 8, 8>::new(MASTER, 0);
    let (mut idle, mut free_idle, mut hrt, mut window, mut sync, mut done) = (
        Stat::default(),
        Stat::default(),
        Stat::default(),
        Stat::default(),
        Stat::default(),
        Stat::default(),
    );
    let mut now = m.next_wakeup();
    let mut closes = Stat::default();
    let mut boundaries = 0u32;
    while boundaries < 180 {
        // The master's slot k starts at (k + 1) slots (it starts one slot after `new(0)`);
        // a wake-up between boundaries is a window-close abort check.
        let since = now - SLOT_NS;
        let boundary = since
            .is_multiple_of(SLOT_NS)
            .then_some((since / SLOT_NS) as u32);
        // Keep SRT traffic queued so free windows have something to load.
        if boundary.is_some_and(|b| b % 20 == 3) {
            let _ = m.submit(now, 3, Token(1), &mut can, &mut host);
            let _ = m.submit(now, 4, Token(2), &mut can, &mut host);
        }
        let before = can.loads;
        let n = meter.instructions(&mut || {
            now = m.poll(now, &mut can, &mut host);
        });
        let loaded = can.loads - before;
        match boundary.map(|b| b % 60) {
            None => closes.add(n),
            Some(0) => sync.add(n),
            Some(slot) if MASK >> slot & 1 == 1 && loaded == 0 => idle.add(n),
            Some(slot) if MASK >> slot & 1 == 1 => hrt.add(n),
            Some(_) if loaded == 0 => free_idle.add(n),
            Some(_) => window.add(n),
        }
        boundaries += u32::from(boundary.is_some());
        // Everything loaded is sent before the next boundary.
        for i in 0..3u8 {
            if can
                .loaded
                .get_mut(i as usize)
                .and_then(Option::take)
                .is_some()
            {
                let n = meter.instructions(&mut || {
                    m.on_tx_done(Mailbox(i), TxResult::Sent, now, &mut can, &mut host);
                });
                done.add(n);
            }
        }
    }
    check!(
        m.counters().tx_frames >= 75,
        "frames sent {}",
        m.counters().tx_frames
    );
    report("slot_boundary_other_module", &idle);
    report("slot_boundary_free_nothing_queued", &free_idle);
    report("slot_boundary_sync_master", &sync);
    report("slot_boundary_hrt_load", &hrt);
    report("slot_boundary_window_fill", &window);
    report("tx_done_and_refill", &done);
    report("window_close_check", &closes);

    // --- Slave receive path. ---
    let mut s = Engine::<'static, 2, 32, 8>::new(SLAVE, 5_000);
    let mut scan = Can {
        loaded: [None; 3],
        loads: 0,
    };
    let (mut rx1, mut rx_mid, mut rx_last, mut rx_sync) = (
        Stat::default(),
        Stat::default(),
        Stat::default(),
        Stat::default(),
    );
    let payload20 = [0xA5u8; 20];
    let mut t = 10_000u64;
    for cycle in 0..20u16 {
        let sf = sync_frame(Sync { cycle, mask: MASK }, 60);
        rx_sync.add(meter.instructions(&mut || s.on_rx(&sf, t, &mut scan, &mut host)));
        let Some(f) = CanId::new(0, MsgId(0x150), 0).and_then(|id| Frame::new(id, &[7; 8])) else {
            rtcan_board_qemu::fail()
        };
        rx1.add(meter.instructions(&mut || s.on_rx(&f, t + 300_000, &mut scan, &mut host)));
        for counter in (0..3u8).rev() {
            let mut data = [0u8; 8];
            let dlc = fragment_data(&payload20, counter, &mut data);
            let Some(f) = CanId::new(9, MsgId(0x151), counter)
                .and_then(|id| Frame::from_parts(id, dlc, data))
            else {
                rtcan_board_qemu::fail()
            };
            let n = meter.instructions(&mut || s.on_rx(&f, t + 400_000, &mut scan, &mut host));
            if counter == 0 {
                rx_last.add(n)
            } else {
                rx_mid.add(n)
            }
        }
        t += 60 * SLOT_NS;
    }
    check!(
        host.delivered == 20 * 28,
        "delivered {} bytes",
        host.delivered
    );
    check!(s.is_synced(), "slave synced");
    report("rx_single_frame_topic", &rx1);
    report("rx_fragment_middle", &rx_mid);
    report("rx_fragment_last_crc_deliver", &rx_last);
    report("rx_sync_slave", &rx_sync);
    pass()
}
