//! Instruction-count benchmark of R2P local delivery on the Cortex-M3 (QEMU `-icount`,
//! see boards/run-qemu.sh): one local publish (alloc + fill + publish, critical
//! sections included) of an 8-byte message delivered to 1, 2, 4 and 8 subscribers,
//! and taking one message from a subscriber queue (try_recv + release). Every publish
//! is checked to reach every subscriber with the right value.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use lm3s6965 as _;
use rtcan_board_qemu::meter::{Stat, SysTickMeter};
use rtcan_board_qemu::{check, pass};
use rtcan_pubsub::bench::bench_publish_local;
use rtcan_pubsub::{pool_blocks, Remote, Topic, TopicCells};

/// Publishes per subscriber count.
const ROUNDS: u32 = 32;

macro_rules! bench_fanout {
    ($meter:expr, $s:literal) => {{
        static CELLS: TopicCells<u64, { pool_blocks($s, 1, 0, 1) }, $s, 1> = TopicCells::new();
        static TOPIC: Topic<u64, { pool_blocks($s, 1, 0, 1) }, $s, 1> =
            Topic::new(&CELLS, Remote::None, None);
        let (mut publish, mut recv) = (Stat::default(), Stat::default());
        for round in 0..ROUNDS {
            let value = 0x0123_4567_89AB_0000 | u64::from(round);
            let mut ok = false;
            publish.add($meter.instructions(&mut || {
                ok = bench_publish_local(&TOPIC, value, u64::from(round));
            }));
            check!(ok, "publish {} to {} subscribers failed", round, $s);
            for i in 0..$s {
                let Some(sub) = TOPIC.subscriber_at(i) else {
                    rtcan_board_qemu::fail()
                };
                let mut got = None;
                recv.add($meter.instructions(&mut || {
                    got = sub.try_recv().map(|m| *m);
                }));
                check!(got == Some(value), "subscriber {} got {:?}", i, got);
            }
        }
        // Every block came back: nothing leaked.
        check!(
            TOPIC.free_blocks() == pool_blocks($s, 1, 0, 1),
            "free blocks {}",
            TOPIC.free_blocks()
        );
        hprintln!(
            "BENCH pubsub_publish_to_{} max {} mean {} samples {}",
            $s,
            publish.max,
            publish.mean(),
            publish.n
        );
        recv
    }};
}

#[entry]
fn main() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        rtcan_board_qemu::fail()
    };
    let mut meter = SysTickMeter::new(cp.SYST);
    let mut recv = Stat::default();
    for s in [
        bench_fanout!(meter, 1),
        bench_fanout!(meter, 2),
        bench_fanout!(meter, 4),
        bench_fanout!(meter, 8),
    ] {
        recv.max = recv.max.max(s.max);
        recv.sum += s.sum;
        recv.n += s.n;
    }
    hprintln!(
        "BENCH pubsub_try_recv max {} mean {} samples {}",
        recv.max,
        recv.mean(),
        recv.n
    );
    pass()
}
