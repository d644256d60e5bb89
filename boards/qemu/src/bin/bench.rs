//! Instruction-count benchmarks on the Cortex-M3 (run under QEMU with
//! `-icount shift=10,sleep=off`, see boards/run-qemu.sh). Prints one `BENCH` line per
//! figure: worst case (max) and mean instructions over every call in a 3-node, 60-cycle
//! run with HRT, fragmented HRT, SRT, fragmented SRT, NRT and heartbeat traffic: the
//! modules of robots/qemu-test.toml with their generated tables and filters, and the
//! traffic of the `bus_exchange` test.
#![no_std]
#![no_main]

use core::hint::black_box;
use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use lm3s6965 as _;
use rtcan_board_common::WideClock;
use rtcan_board_qemu::meter::{report, KindMeter, Stat, SysTickMeter};
use rtcan_board_qemu::robot::{self, master, slave1, slave2};
use rtcan_board_qemu::test_host::TestHost;
use rtcan_board_qemu::{check, pass, Node, SoftBus, SoftCan, Station};
use rtcan_core::driver::{Controller, Mailbox};
use rtcan_core::fragment::{crc16, fragment_data};
use rtcan_core::frame::Frame;
use rtcan_core::id::{CanId, MsgId};

#[entry]
fn main() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        rtcan_board_qemu::fail()
    };
    let mut meter = SysTickMeter::new(cp.SYST);
    hprintln!(
        "CALIB ticks_per_1000_instructions {}",
        meter.ticks_per_kinsn()
    );

    // Sanity of the method: a known block of 100 NOPs.
    let nops = meter.instructions(&mut || unsafe {
        core::arch::asm!(
            ".rept 100",
            "nop",
            ".endr",
            options(nomem, nostack, preserves_flags)
        );
    });
    hprintln!("BENCH nop100 max {} mean {} samples 1", nops, nops);
    check!((97..=105).contains(&nops), "100 NOPs measured as {}", nops);

    // Trivial board-side function: extending the 16-bit timer reading.
    let clk = WideClock::new();
    let mut s = Stat::default();
    for c in [0u16, 0x7FFF, 0x8000, 0xFFFF] {
        s.add(meter.instructions(&mut || {
            black_box(clk.ticks(black_box(c)));
        }));
    }
    report("wide_clock_ticks", &s);

    // TTCM stamp to local SOF time (protocol task, every received frame): frames ~1 ms
    // apart with varying latency, across counter wraps.
    let mut sof = rtcan_board_common::SofClock::new(1_000, 200);
    let mut s = Stat::default();
    for k in 1..200u64 {
        let bits = k * 997;
        let now = 3_000_000_000 + (bits + 127) * 1_000 + (k % 7) * 1_300;
        s.add(meter.instructions(&mut || {
            black_box(sof.sof(black_box(bits as u16), black_box(127), black_box(now)));
        }));
    }
    report("sof_clock_sof", &s);

    // Loading one TX frame: fragment bytes + identifier + frame + mailbox write, for
    // every fragment of a 30-byte message (the engine's per-frame transmit work).
    let payload = [0x5Au8; 30];
    let crc = crc16(&payload);
    let mut can = SoftCan::new();
    let mut load = Stat::default();
    for counter in (0..4u8).rev() {
        load.add(meter.instructions(&mut || {
            let mut out = [0u8; 8];
            let dlc = fragment_data(black_box(&payload), crc, counter, &mut out);
            if let Some(f) =
                CanId::new(17, MsgId(0x143), counter).and_then(|id| Frame::from_parts(id, dlc, out))
            {
                can.load(Mailbox(1), &f);
            }
        }));
        can.abort(Mailbox(1));
        let _ = can.take_completion();
    }
    report("load_tx_frame", &load);

    // The engine in a running system.
    let mut km = KindMeter {
        meter,
        poll: Stat::default(),
        rx: Stat::default(),
        tx_done: Stat::default(),
    };
    let (mut hm, mut h1, mut h2) = (
        TestHost::<{ master::TX.len() }, { master::RX_COUNT }>::new(&master::TABLES),
        TestHost::<{ slave1::TX.len() }, { slave1::RX_COUNT }>::new(&slave1::TABLES),
        TestHost::<{ slave2::TX.len() }, { slave2::RX_COUNT }>::new(&slave2::TABLES),
    );
    hm.verify = false;
    h1.verify = false;
    h2.verify = false;
    let mut m = Station::new(master::engine(0), hm, 0).filtered(master::FILTERS);
    let mut s1 = Station::new(slave1::engine(1_000_001), h1, 1_000_001).filtered(slave1::FILTERS);
    let mut s2 = Station::new(slave2::engine(777_777), h2, 777_777).filtered(slave2::FILTERS);
    let (m_cmd, s1_log, s2_diag) = (
        master::topics::tx::CMD,
        slave1::topics::tx::LOG,
        slave2::topics::tx::DIAG,
    );
    let cycle = robot::BUS.cycle_ns();
    let mut bus = SoftBus::new(robot::BUS.bitrate);
    let mut t = 0;
    while t < 60 * cycle {
        t += cycle / 2;
        bus.run_until(&mut [&mut m as &mut dyn Node, &mut s1, &mut s2], t, &mut km);
        if !(s1.engine.is_synced() && s2.engine.is_synced()) {
            continue;
        }
        if let Some(tok) = m.host.next_message(m_cmd) {
            let _ = m.submit(t, m_cmd, tok);
        }
        if t.is_multiple_of(2 * cycle) {
            if let Some(tok) = s1.host.next_message(s1_log) {
                let _ = s1.submit(t, s1_log, tok);
            }
        }
        if t.is_multiple_of(5 * cycle) {
            if let Some(tok) = s2.host.next_message(s2_diag) {
                let _ = s2.submit(t, s2_diag, tok);
            }
        }
    }
    let scan = m.host.rx_log(master::topics::rx::SCAN).count;
    check!(scan >= 55, "scan received {}", scan);
    report("engine_poll_slot_boundary", &km.poll);
    report("engine_on_rx", &km.rx);
    report("engine_on_tx_done", &km.tx_done);
    pass()
}
