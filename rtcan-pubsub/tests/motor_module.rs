//! Hand-written example of what rtcan-codegen emits for one module (the `generated`
//! module below), and the tests of the engine-facing glue through it: index dispatch,
//! local/remote equivalence, publisher-class signalling, safe state.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

/// What rtcan-codegen generates for module `motor1` (module 1; the master is module 0).
/// robot.toml (excerpt): `speed3` (12 B, gateway → motors, SRT), `encoder1` (6 B, HRT,
/// subscribed locally by `pid` and remotely by the gateway), `motor1_status` (3 B, SRT),
/// `log` (8 B, NRT).
mod generated {
    use rtcan_pubsub::{
        pool_blocks, Message, ModuleHost, Node, Remote, RxPort, SafetyConfig, SystemStatus, Topic,
        TopicCells, TxPort,
    };

    // ---- message types (shared by all modules) ----------------------------
    #[derive(Clone, Copy, Debug, Default, PartialEq)]
    pub struct Speed3 {
        pub w: [f32; 3],
    }
    impl Message for Speed3 {
        const SIZE: usize = 12;
        type Wire = [u8; 12];
        fn encode(&self, out: &mut [u8]) {
            for (chunk, w) in out.chunks_exact_mut(4).zip(self.w) {
                chunk.copy_from_slice(&w.to_le_bytes());
            }
        }
        fn decode(bytes: &[u8]) -> Option<Self> {
            if bytes.len() != Self::SIZE {
                return None;
            }
            let mut w = [0f32; 3];
            for (w, chunk) in w.iter_mut().zip(bytes.chunks_exact(4)) {
                *w = f32::from_le_bytes(chunk.try_into().ok()?);
            }
            Some(Speed3 { w })
        }
    }

    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
    pub struct Encoder {
        pub ticks: i32,
        pub dt_us: u16,
    }
    impl Message for Encoder {
        const SIZE: usize = 6;
        type Wire = [u8; 6];
        fn encode(&self, out: &mut [u8]) {
            if let Some(o) = out.get_mut(..6) {
                o[..4].copy_from_slice(&self.ticks.to_le_bytes());
                o[4..].copy_from_slice(&self.dt_us.to_le_bytes());
            }
        }
        fn decode(bytes: &[u8]) -> Option<Self> {
            let b: &[u8; 6] = bytes.try_into().ok()?;
            Some(Encoder {
                ticks: i32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                dt_us: u16::from_le_bytes([b[4], b[5]]),
            })
        }
    }

    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
    pub struct MotorStatus {
        pub current_ma: u16,
        pub fault: u8,
    }
    impl Message for MotorStatus {
        const SIZE: usize = 3;
        type Wire = [u8; 3];
        fn encode(&self, out: &mut [u8]) {
            if let Some(o) = out.get_mut(..3) {
                o[..2].copy_from_slice(&self.current_ma.to_le_bytes());
                o[2] = self.fault;
            }
        }
        fn decode(bytes: &[u8]) -> Option<Self> {
            match *bytes {
                [a, b, fault] => Some(MotorStatus {
                    current_ma: u16::from_le_bytes([a, b]),
                    fault,
                }),
                _ => None,
            }
        }
    }

    // ---- this module's topics ----------------------------------------------
    // Pools: subscribers × queue + subscribers + engine share + 1 loan.
    pub type Speed3Topic = Topic<Speed3, { pool_blocks(1, 2, 0, 1) }, 1, 2>;
    pub type EncoderTopic = Topic<Encoder, { pool_blocks(1, 4, 2, 1) }, 1, 4>;
    pub type StatusTopic = Topic<MotorStatus, { pool_blocks(0, 2, 3, 1) }, 0, 2>;
    pub type LogTopic = Topic<[u8; 8], { pool_blocks(0, 4, 5, 1) }, 0, 4>;

    pub static SPEED3_CELLS: TopicCells<Speed3, { pool_blocks(1, 2, 0, 1) }, 1, 2> =
        TopicCells::new();
    pub static SPEED3: Speed3Topic = Topic::new(&SPEED3_CELLS, Remote::None, None); // received
    pub static ENCODER1_CELLS: TopicCells<Encoder, { pool_blocks(1, 4, 2, 1) }, 1, 4> =
        TopicCells::new();
    pub static ENCODER1: EncoderTopic = Topic::new(&ENCODER1_CELLS, Remote::Hrt, None);
    pub static MOTOR1_STATUS_CELLS: TopicCells<MotorStatus, { pool_blocks(0, 2, 3, 1) }, 0, 2> =
        TopicCells::new();
    pub static MOTOR1_STATUS: StatusTopic = Topic::new(&MOTOR1_STATUS_CELLS, Remote::Srt, None);
    pub static LOG_CELLS: TopicCells<[u8; 8], { pool_blocks(0, 4, 5, 1) }, 0, 4> =
        TopicCells::new();
    pub static LOG: LogTopic = Topic::new(&LOG_CELLS, Remote::Nrt, None);

    /// Subscriber slots: `SPEED3` slot 0 = pid, `ENCODER1` slot 0 = pid.
    pub const PID_SPEED3: usize = 0;
    pub const PID_ENCODER1: usize = 0;

    // ---- engine glue: table order = NodeTables::tx / NodeTables::rx order -----
    pub static TX_PORTS: [&dyn TxPort; 3] = [&ENCODER1, &MOTOR1_STATUS, &LOG];
    pub static RX_PORTS: [&dyn RxPort; 1] = [&SPEED3];
    pub const TX_ENCODER1: u8 = 0;
    pub const TX_MOTOR1_STATUS: u8 = 1;
    pub const TX_LOG: u8 = 2;
    pub const RX_SPEED3: u8 = 0;

    pub static STATUS: SystemStatus = SystemStatus::new(SafetyConfig {
        module: 1,
        master: 0,
        max_missed_cycles: 3,
    });
    pub static PID: Node = Node::new("pid");
    pub static NODES: [&Node; 1] = [&PID];

    pub fn host() -> ModuleHost<'static> {
        ModuleHost::new(&TX_PORTS, &RX_PORTS, &STATUS, &NODES)
    }
}

use generated::*;
use rtcan_core::driver::{Event, Host, Token, TxOutcome};
use rtcan_pubsub::{
    port, Message, NodeState, Publisher, RecvError, Remote, SafeReason, Subscriber, Topic,
};

/// Node code: knows topics, not whether its input came from this module or the bus.
/// One step: for each speed set point, publish a status whose current is the first
/// wheel's set point in mA, stamped with the input's time.
fn pid_step<const N1: usize, const N2: usize>(
    speed: &Subscriber<'_, Speed3, N1, 1, 2>,
    out: &Publisher<'_, MotorStatus, N2, 1, 2>,
) -> usize {
    let mut n = 0;
    while let Some(cmd) = speed.try_recv() {
        let current_ma = (cmd.w[0] * 1000.0) as u16;
        out.send(
            MotorStatus {
                current_ma,
                fault: u8::from(cmd.w[2] < 0.0),
            },
            cmd.stamp(),
        )
        .unwrap();
        n += 1;
    }
    n
}

fn outputs<const N: usize>(t: &Topic<MotorStatus, N, 1, 2>) -> Vec<(MotorStatus, u64)> {
    let sub = t.subscriber::<0>();
    std::iter::from_fn(|| sub.try_recv().map(|m| (*m, m.stamp()))).collect()
}

#[test]
fn local_and_remote_inputs_give_the_same_node_results() {
    let inputs = [
        (
            Speed3 {
                w: [0.5, 0.0, -1.0],
            },
            1_000u64,
        ),
        (
            Speed3 {
                w: [1.25, 2.0, 3.0],
            },
            2_000,
        ),
    ];

    // Local: the gateway node runs on this module and publishes directly.
    let speed_local = Topic::<Speed3, 4, 1, 2>::new(cells(), Remote::None, None);
    let out_local = Topic::<MotorStatus, 4, 1, 2>::new(cells(), Remote::None, None);
    for (v, t) in inputs {
        speed_local.publisher().send(v, t).unwrap();
    }
    pid_step(&speed_local.subscriber::<0>(), &out_local.publisher());

    // Remote: the same messages arrive as bus payloads through Host::deliver.
    let speed_remote = Topic::<Speed3, 4, 1, 2>::new(cells(), Remote::None, None);
    let out_remote = Topic::<MotorStatus, 4, 1, 2>::new(cells(), Remote::None, None);
    let rx: [&dyn rtcan_pubsub::RxPort; 1] = [&speed_remote];
    let status = rtcan_pubsub::SystemStatus::new(rtcan_pubsub::SafetyConfig {
        module: 1,
        master: 0,
        max_missed_cycles: 3,
    });
    let mut host = rtcan_pubsub::ModuleHost::new(&[], &rx, &status, &[]);
    for (v, t) in inputs {
        let mut bytes = [0u8; 12];
        v.encode(&mut bytes);
        host.deliver(0, &bytes, t);
    }
    pid_step(&speed_remote.subscriber::<0>(), &out_remote.publisher());

    let local = outputs(&out_local);
    assert_eq!(
        local,
        vec![
            (
                MotorStatus {
                    current_ma: 500,
                    fault: 1
                },
                1_000
            ),
            (
                MotorStatus {
                    current_ma: 1250,
                    fault: 0
                },
                2_000
            )
        ]
    );
    assert_eq!(outputs(&out_remote), local);
}

/// The generated module, driven through `Host` the way the engine does.
#[test]
fn generated_module_host_dispatches_by_table_index() {
    let mut host = host();
    let pid_enc = ENCODER1.subscriber::<PID_ENCODER1>();
    let pid_speed = SPEED3.subscriber::<PID_SPEED3>();

    // HRT: the encoder node publishes; the slot samples the latest value.
    ENCODER1
        .publisher()
        .send(
            Encoder {
                ticks: -2,
                dt_us: 1000,
            },
            10,
        )
        .unwrap();
    let tok = host.hrt_sample(TX_ENCODER1).unwrap();
    assert_eq!(port::split(tok).0, TX_ENCODER1);
    assert_eq!(host.payload(tok), &[0xFE, 0xFF, 0xFF, 0xFF, 0xE8, 0x03]);
    host.tx_done(TX_ENCODER1, Some(tok), TxOutcome::Sent);
    assert_eq!(
        pid_enc.try_recv().map(|m| *m),
        Some(Encoder {
            ticks: -2,
            dt_us: 1000
        }),
        "local copy too"
    );
    // Next slot: nothing new -> the publisher is told.
    assert_eq!(host.hrt_sample(TX_ENCODER1), None);
    host.tx_done(TX_ENCODER1, None, TxOutcome::NothingToSend);
    assert!(ENCODER1.publisher().take_nothing_sent());

    // SRT: queued for Engine::submit (ModuleHost::pump does this with the engine).
    MOTOR1_STATUS
        .publisher()
        .send(
            MotorStatus {
                current_ma: 300,
                fault: 0,
            },
            20,
        )
        .unwrap();
    let block = TX_PORTS[usize::from(TX_MOTOR1_STATUS)].pending().unwrap();
    let tok = port::join(TX_MOTOR1_STATUS, block);
    assert_eq!(host.payload(tok), &[0x2C, 0x01, 0x00]);
    TX_PORTS[usize::from(TX_MOTOR1_STATUS)].pending_done(block, true);
    host.tx_done(TX_MOTOR1_STATUS, Some(tok), TxOutcome::DeadlineMissed);
    assert!(MOTOR1_STATUS.publisher().take_deadline_missed());
    assert_eq!(MOTOR1_STATUS.stats().deadline_misses, 1);

    // RX: a speed command from the gateway is republished to the pid node.
    let mut bytes = [0u8; 12];
    Speed3 { w: [1.0, 2.0, 3.0] }.encode(&mut bytes);
    host.deliver(RX_SPEED3, &bytes, 30);
    let m = pid_speed.try_recv().unwrap();
    assert_eq!((*m, m.stamp()), (Speed3 { w: [1.0, 2.0, 3.0] }, 30));

    // Out-of-table indices are counted, never a panic.
    assert_eq!(host.hrt_sample(9), None);
    host.deliver(5, &bytes, 0);
    assert_eq!(host.payload(Token(0x0900)), &[] as &[u8]);
    assert_eq!(host.bad_index(), 2);

    // NRT: four log lines fill the engine queue; the fifth is refused, not dropped.
    for i in 0..4u8 {
        LOG.publisher().send([i; 8], 40).unwrap();
    }
    assert!(LOG.publisher().send([9; 8], 41).is_err());
    let log = TX_PORTS[usize::from(TX_LOG)];
    while let Some(block) = log.pending() {
        let tok = port::join(TX_LOG, block);
        log.pending_done(block, true);
        host.tx_done(TX_LOG, Some(tok), TxOutcome::Sent);
    }
    assert_eq!(LOG.stats().sent, 4);
    assert_eq!(LOG.free_blocks(), 6, "pool_blocks(0, 4, 5, 1): all back");

    // Everything the engine touched went back to the pools.
    drop(m);
    assert_eq!(ENCODER1.free_blocks(), 8);
    assert_eq!(MOTOR1_STATUS.free_blocks(), 4);
    assert_eq!(SPEED3.free_blocks(), 4);

    // Heartbeat state = worst node state; safe state until sync and master heard.
    assert_eq!(host.module_state(), NodeState::Init.as_u8());
    assert!(!PID.start(&STATUS), "no sync yet: start refused");
    host.event(Event::Synced);
    host.event(Event::Heartbeat {
        module: 0,
        state: NodeState::Run.as_u8(),
    });
    assert!(PID.start(&STATUS));
    assert_eq!(host.module_state(), NodeState::Run.as_u8());
    host.event(Event::SyncLost);
    assert!(!PID.run(&STATUS));
    assert_eq!((PID.state(), PID.safe_stopped()), (NodeState::Stop, true));
    assert_eq!(host.module_state(), NodeState::Stop.as_u8());
}

fn status() -> rtcan_pubsub::SystemStatus {
    rtcan_pubsub::SystemStatus::new(rtcan_pubsub::SafetyConfig {
        module: 2,
        master: 0,
        max_missed_cycles: 3,
    })
}

fn running(s: &rtcan_pubsub::SystemStatus) {
    s.event(Event::Synced);
    s.event(Event::Heartbeat {
        module: 0,
        state: 1,
    });
    assert_eq!(s.safe_reason(), None);
}

#[test]
fn safe_state_on_sync_loss_and_stays_stopped_until_restarted() {
    let s = status();
    assert_eq!(s.safe_reason(), Some(SafeReason::NoSync));
    running(&s);
    let node = rtcan_pubsub::Node::new("motor");
    assert!(node.start(&s));
    assert!(node.run(&s));
    s.event(Event::SyncLost);
    assert_eq!(s.safe_reason(), Some(SafeReason::NoSync));
    assert!(!node.run(&s));
    running(&s);
    assert_eq!(node.update(&s), NodeState::Stop, "no automatic restart");
    assert!(node.start(&s));
    assert_eq!(s.sync_losses(), 1);
}

#[test]
fn safe_state_when_master_heartbeat_missing_for_configured_cycles() {
    let s = status();
    running(&s);
    for _ in 0..3 {
        s.on_cycle();
    }
    assert!(!s.safe_state_required(), "3 cycles allowed");
    s.on_cycle();
    assert_eq!(s.safe_reason(), Some(SafeReason::MasterSilent));
    s.event(Event::Heartbeat {
        module: 4,
        state: 1,
    });
    assert!(
        s.safe_state_required(),
        "another module's heartbeat is not the master's"
    );
    s.event(Event::Heartbeat {
        module: 0,
        state: 1,
    });
    assert!(!s.safe_state_required());
    s.event(Event::Heartbeat {
        module: 0,
        state: NodeState::Fail.as_u8(),
    });
    assert_eq!(s.safe_reason(), Some(SafeReason::MasterStopped));
    assert_eq!(s.module_state(4), Some(1));
    assert_eq!(s.module_state(5), None);
}

#[test]
fn safe_state_on_fingerprint_mismatch_is_latched() {
    let s = status();
    running(&s);
    s.event(Event::FingerprintMismatch {
        module: 3,
        fingerprint: 0xDEAD_BEEF,
    });
    s.event(Event::Heartbeat {
        module: 0,
        state: 1,
    });
    assert_eq!(
        s.safe_reason(),
        Some(SafeReason::FingerprintMismatch {
            module: 3,
            fingerprint: 0xDEAD_BEEF
        })
    );
    s.reset();
    assert_eq!(s.safe_reason(), None);
}

#[test]
fn master_module_needs_no_sync_or_own_heartbeat() {
    let s = rtcan_pubsub::SystemStatus::new(rtcan_pubsub::SafetyConfig {
        module: 0,
        master: 0,
        max_missed_cycles: 1,
    });
    for _ in 0..5 {
        s.on_cycle();
    }
    assert!(!s.safe_state_required());
    s.event(Event::FingerprintMismatch {
        module: 1,
        fingerprint: 1,
    });
    assert!(s.safe_state_required());
}

#[test]
fn hrt_stream_loss_is_seen_by_the_subscriber_timeout() {
    let t = Topic::<Encoder, 4, 1, 2>::new(cells(), Remote::None, None);
    let sub = t.subscriber::<0>();
    t.deliver_for_test(Encoder { ticks: 1, dt_us: 1 }, 1_000_000);
    assert!(sub.try_recv_or_stale(1_500_000, 2_000_000).is_ok());
    assert_eq!(
        sub.try_recv_or_stale(3_000_000, 2_000_000).unwrap_err(),
        RecvError::Empty
    );
    assert_eq!(
        sub.try_recv_or_stale(3_000_001, 2_000_000).unwrap_err(),
        RecvError::Stale
    );
}

trait DeliverForTest {
    fn deliver_for_test(&self, v: Encoder, sof: u64);
}
impl<const N: usize> DeliverForTest for Topic<Encoder, N, 1, 2> {
    fn deliver_for_test(&self, v: Encoder, sof: u64) {
        let mut b = [0u8; 6];
        v.encode(&mut b);
        rtcan_pubsub::RxPort::deliver(self, &b, sof);
    }
}

#[test]
fn clear_forgets_sync_heartbeats_and_mismatch() {
    let s = status();
    running(&s);
    assert!(!s.safe_state_required());
    s.event(Event::FingerprintMismatch {
        module: 4,
        fingerprint: 9,
    });
    s.clear();
    assert_eq!(s.safe_reason(), Some(rtcan_pubsub::SafeReason::NoSync));
    assert_eq!(s.module_state(0), None);
    assert_eq!(s.sync_losses(), 0);
}

/// Fresh cells for a topic made inside a test (leaked: a topic's cells are `'static`).
fn cells<T: Message, const N: usize, const S: usize, const Q: usize>(
) -> &'static rtcan_pubsub::TopicCells<T, N, S, Q> {
    Box::leak(Box::new(rtcan_pubsub::TopicCells::new()))
}
