//! On-target test: the three modules of robots/qemu-test.toml — a master and two slaves,
//! each with its generated `TABLES`, engine sizes and acceptance `FILTERS` — on the
//! software bus exchange HRT (single and fragmented), SRT (single and fragmented) and NRT
//! messages for 100 cycles; counts and every delivered byte are asserted. Exit code 0 =
//! pass.
//!
//! | topic | class | from → to | bytes (frames) |
//! |---|---|---|---|
//! | odom | HRT | slave1 → master, slave2 | 6 (1) |
//! | scan | HRT | slave2 → master | 20 (3) |
//! | cmd  | SRT 2 ms | master → slave1, slave2 | 8 (1) |
//! | log  | SRT 5 ms | slave1 → master | 30 (4) |
//! | diag | NRT | slave2 → master | 3 (1) |
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use lm3s6965 as _;
use rtcan_board_qemu::meter::NoMeter;
use rtcan_board_qemu::robot::{self, master, slave1, slave2};
use rtcan_board_qemu::test_host::TestHost;
use rtcan_board_qemu::{check, pass, Node, SoftBus, Station};

const CYCLES: u64 = 100;

#[entry]
fn main() -> ! {
    let cycle = robot::BUS.cycle_ns();
    // Local clocks: the slaves' are offset from the master's (which is bus time).
    let mut m = Station::new(
        master::engine(0),
        TestHost::<{ master::TX.len() }, { master::RX_COUNT }>::new(&master::TABLES),
        0,
    )
    .filtered(master::FILTERS);
    let mut s1 = Station::new(
        slave1::engine(3_141_593),
        TestHost::<{ slave1::TX.len() }, { slave1::RX_COUNT }>::new(&slave1::TABLES),
        3_141_593,
    )
    .filtered(slave1::FILTERS);
    let mut s2 = Station::new(
        slave2::engine(2_718_282),
        TestHost::<{ slave2::TX.len() }, { slave2::RX_COUNT }>::new(&slave2::TABLES),
        2_718_282,
    )
    .filtered(slave2::FILTERS);
    // Engine indices of every topic, from the generated tables.
    let (m_cmd, s1_log, s1_odom) = (
        master::topics::tx::CMD,
        slave1::topics::tx::LOG,
        slave1::topics::tx::ODOM,
    );
    let (s2_scan, s2_diag) = (slave2::topics::tx::SCAN, slave2::topics::tx::DIAG);
    let m_rx = |i: u8| m_rx_count(&m.host, i);
    let _ = m_rx;

    let mut bus = SoftBus::new(robot::BUS.bitrate);
    let (mut cmd_submitted, mut log_submitted, mut diag_submitted) = (0u32, 0u32, 0u32);
    let mut refused = 0u32;
    // Every half cycle (1 ms) the master publishes cmd; every 2 cycles slave 1 publishes
    // log; every 5 cycles slave 2 publishes diag. Only once the slaves are synced (a
    // slave must not transmit before, so a message would only wait).
    let mut t = 0;
    while t < CYCLES * cycle {
        t += cycle / 2;
        bus.run_until(
            &mut [&mut m as &mut dyn Node, &mut s1, &mut s2],
            t,
            &mut NoMeter,
        );
        if !(s1.engine.is_synced() && s2.engine.is_synced()) || t > (CYCLES - 5) * cycle {
            continue;
        }
        if let Some(tok) = m.host.next_message(m_cmd) {
            if m.submit(t, m_cmd, tok).is_ok() {
                cmd_submitted += 1
            } else {
                refused += 1
            }
        }
        if t % (2 * cycle) == 0 {
            if let Some(tok) = s1.host.next_message(s1_log) {
                if s1.submit(t, s1_log, tok).is_ok() {
                    log_submitted += 1
                } else {
                    refused += 1
                }
            }
        }
        if t % (5 * cycle) == 0 {
            if let Some(tok) = s2.host.next_message(s2_diag) {
                if s2.submit(t, s2_diag, tok).is_ok() {
                    diag_submitted += 1
                } else {
                    refused += 1
                }
            }
        }
    }
    // Let the last messages drain.
    bus.run_until(
        &mut [&mut m as &mut dyn Node, &mut s1, &mut s2],
        (CYCLES + 2) * cycle,
        &mut NoMeter,
    );
    check!(false, "unfinished");
    pass()
}
