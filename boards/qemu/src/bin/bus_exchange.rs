//! On-target test: a master and two slaves on the software bus exchange HRT (single and
//! fragmented), SRT (single and fragmented) and NRT messages for 100 cycles; counts and
//! contents are asserted. Exit code 0 = pass.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use lm3s6965 as _;
use rtcan_board_qemu::fixtures::{TestHost, MASTER, M_ARENA, SLAVE1, SLAVE2};
use rtcan_board_qemu::meter::NoMeter;
use rtcan_board_qemu::{check, pass, Node, SoftBus, Station};
use rtcan_core::engine::Engine;

const CYCLE: u64 = 2_000_000;
const CYCLES: u64 = 100;

#[entry]
fn main() -> ! {
    // Local clocks: the slaves' are offset from the master's (which is bus time).
    let mut m = Station::new(
        Engine::<4, M_ARENA, 8>::new(MASTER, 0),
        TestHost::<1, 4>::new(&MASTER),
        0,
    );
    let mut s1 = Station::new(
        Engine::<1, 8, 8>::new(SLAVE1, 3_141_593),
        TestHost::<2, 1>::new(&SLAVE1),
        3_141_593,
    );
    let mut s2 = Station::new(
        Engine::<2, 14, 8>::new(SLAVE2, 2_718_282),
        TestHost::<2, 2>::new(&SLAVE2),
        2_718_282,
    );
    let mut bus = SoftBus::new(1_000_000);
    let (mut cmd_submitted, mut log_submitted, mut diag_submitted) = (0u32, 0u32, 0u32);
    let mut refused = 0u32;
    // Every 1 ms the master publishes cmd; every 4 ms slave 1 publishes log; every
    // 10 ms slave 2 publishes diag. Only once the slaves are synced (a slave must not
    // transmit before, so a message would only wait).
    let mut t = 0;
    while t < CYCLES * CYCLE {
        t += CYCLE / 2;
        bus.run_until(
            &mut [&mut m as &mut dyn Node, &mut s1, &mut s2],
            t,
            &mut NoMeter,
        );
        if !(s1.engine.is_synced() && s2.engine.is_synced()) || t > (CYCLES - 5) * CYCLE {
            continue;
        }
        if let Some(tok) = m.host.next_message(0) {
            if m.submit(t, 0, tok).is_ok() {
                cmd_submitted += 1
            } else {
                refused += 1
            }
        }
        if t % (2 * CYCLE) == 0 {
            if let Some(tok) = s1.host.next_message(1) {
                if s1.submit(t, 1, tok).is_ok() {
                    log_submitted += 1
                } else {
                    refused += 1
                }
            }
        }
        if t % (5 * CYCLE) == 0 {
            if let Some(tok) = s2.host.next_message(1) {
                if s2.submit(t, 1, tok).is_ok() {
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
        (CYCLES + 2) * CYCLE,
        &mut NoMeter,
    );

    let odom_sent = s1.host.tx[0].sent;
    let scan_sent = s2.host.tx[0].sent;
    hprintln!(
        "frames {} busy {} us; odom sent {} scan sent {} cmd {} log {} diag {} refused {}",
        bus.stats.frames,
        bus.stats.busy_ns / 1000,
        odom_sent,
        scan_sent,
        cmd_submitted,
        log_submitted,
        diag_submitted,
        refused
    );
    hprintln!(
        "master rx counts {:?} {:?} {:?} {:?}",
        m.host.rx[0].count,
        m.host.rx[1].count,
        m.host.rx[2].count,
        m.host.rx[3].count
    );
    hprintln!("counters M {:?}", m.engine.counters());
    hprintln!("counters S1 {:?}", s1.engine.counters());
    hprintln!("counters S2 {:?}", s2.engine.counters());

    // Slaves locked once and stayed locked.
    check!(
        s1.host.synced == 1 && s2.host.synced == 1,
        "synced {} {}",
        s1.host.synced,
        s2.host.synced
    );
    check!(
        s1.host.sync_lost == 0 && s2.host.sync_lost == 0,
        "sync lost"
    );
    // HRT: one odom and one 3-frame scan per cycle once synced (the first cycle or two
    // go to locking), each received exactly as often as sent, all bytes intact.
    check!(
        odom_sent >= (CYCLES - 3) as u32 && odom_sent <= CYCLES as u32 + 2,
        "odom sent {}",
        odom_sent
    );
    check!(
        scan_sent >= (CYCLES - 3) as u32 && scan_sent <= CYCLES as u32 + 2,
        "scan sent {}",
        scan_sent
    );
    check!(
        m.host.rx[0].count == odom_sent && s2.host.rx[0].count == odom_sent,
        "odom rx {} {}",
        m.host.rx[0].count,
        s2.host.rx[0].count
    );
    check!(
        m.host.rx[1].count == scan_sent,
        "scan rx {}",
        m.host.rx[1].count
    );
    // SRT and NRT: every submitted message delivered, none late.
    check!(refused == 0, "refused {}", refused);
    check!(cmd_submitted >= 150, "cmd submitted {}", cmd_submitted);
    check!(
        s1.host.rx[0].count == cmd_submitted && s2.host.rx[1].count == cmd_submitted,
        "cmd rx {} {}",
        s1.host.rx[0].count,
        s2.host.rx[1].count
    );
    check!(
        m.host.tx[0].sent == cmd_submitted && m.host.tx[0].missed == 0,
        "cmd outcomes"
    );
    check!(
        m.host.rx[2].count == log_submitted && log_submitted >= 40,
        "log rx {} of {}",
        m.host.rx[2].count,
        log_submitted
    );
    check!(
        m.host.rx[3].count == diag_submitted && diag_submitted >= 15,
        "diag rx {} of {}",
        m.host.rx[3].count,
        diag_submitted
    );
    // Contents and order.
    for log in m
        .host
        .rx
        .iter()
        .chain(s1.host.rx.iter())
        .chain(s2.host.rx.iter())
    {
        check!(
            log.bad == 0 && log.out_of_order == 0,
            "bad {} out of order {}",
            log.bad,
            log.out_of_order
        );
    }
    // No protocol-level loss anywhere.
    for c in [
        m.engine.counters(),
        s1.engine.counters(),
        s2.engine.counters(),
    ] {
        check!(
            c.rx_crc == 0 && c.rx_out_of_order == 0 && c.rx_bad_dlc == 0 && c.deadline_missed == 0,
            "{:?}",
            c
        );
        check!(
            c.hrt_late == 0 && c.queue_full == 0 && c.tx_failed == 0,
            "{:?}",
            c
        );
    }
    // Heartbeats (every 10 cycles per module): each module hears the other two.
    check!(
        m.host.heartbeats >= 18 && s1.host.heartbeats >= 18 && s2.host.heartbeats >= 18,
        "heartbeats {} {} {}",
        m.host.heartbeats,
        s1.host.heartbeats,
        s2.host.heartbeats
    );
    check!(m.host.mismatches == 0, "fingerprint mismatch");
    hprintln!("PASS bus_exchange");
    pass()
}
