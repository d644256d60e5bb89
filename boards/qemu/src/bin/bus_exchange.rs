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
        if t.is_multiple_of(2 * cycle) {
            if let Some(tok) = s1.host.next_message(s1_log) {
                if s1.submit(t, s1_log, tok).is_ok() {
                    log_submitted += 1
                } else {
                    refused += 1
                }
            }
        }
        if t.is_multiple_of(5 * cycle) {
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

    let (odom, scan) = (s1.host.tx_log(s1_odom), s2.host.tx_log(s2_scan));
    let (m_odom, m_scan, m_log, m_diag) = (
        m.host.rx_log(master::topics::rx::ODOM),
        m.host.rx_log(master::topics::rx::SCAN),
        m.host.rx_log(master::topics::rx::LOG),
        m.host.rx_log(master::topics::rx::DIAG),
    );
    let s1_cmd = s1.host.rx_log(slave1::topics::rx::CMD);
    let (s2_odom, s2_cmd) = (
        s2.host.rx_log(slave2::topics::rx::ODOM),
        s2.host.rx_log(slave2::topics::rx::CMD),
    );
    hprintln!(
        "frames {} busy {} us; odom sent {} scan sent {} cmd {} log {} diag {} refused {}",
        bus.stats.frames,
        bus.stats.busy_ns / 1000,
        odom.sent,
        scan.sent,
        cmd_submitted,
        log_submitted,
        diag_submitted,
        refused
    );
    hprintln!(
        "master rx odom {} scan {} log {} diag {}; slave1 rx cmd {}; slave2 rx odom {} cmd {}",
        m_odom.count,
        m_scan.count,
        m_log.count,
        m_diag.count,
        s1_cmd.count,
        s2_odom.count,
        s2_cmd.count
    );
    hprintln!(
        "filtered out: master {} slave1 {} slave2 {}",
        m.can.rejected,
        s1.can.rejected,
        s2.can.rejected
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
        odom.sent >= (CYCLES - 3) as u32 && odom.sent <= CYCLES as u32 + 2,
        "odom sent {}",
        odom.sent
    );
    check!(
        scan.sent >= (CYCLES - 3) as u32 && scan.sent <= CYCLES as u32 + 2,
        "scan sent {}",
        scan.sent
    );
    check!(
        m_odom.count == odom.sent && s2_odom.count == odom.sent,
        "odom rx {} {} of {}",
        m_odom.count,
        s2_odom.count,
        odom.sent
    );
    check!(
        m_scan.count == scan.sent,
        "scan rx {} of {}",
        m_scan.count,
        scan.sent
    );
    // SRT and NRT: every submitted message sent once and delivered, none late.
    check!(refused == 0, "refused {}", refused);
    check!(cmd_submitted >= 150, "cmd submitted {}", cmd_submitted);
    check!(
        s1_cmd.count == cmd_submitted && s2_cmd.count == cmd_submitted,
        "cmd rx {} {} of {}",
        s1_cmd.count,
        s2_cmd.count,
        cmd_submitted
    );
    let (cmd, log, diag) = (
        m.host.tx_log(m_cmd),
        s1.host.tx_log(s1_log),
        s2.host.tx_log(s2_diag),
    );
    for (name, tx, submitted) in [
        ("cmd", cmd, cmd_submitted),
        ("log", log, log_submitted),
        ("diag", diag, diag_submitted),
    ] {
        check!(
            tx.sent == submitted && tx.missed == 0 && !tx.busy,
            "{} sent {} missed {} of {}",
            name,
            tx.sent,
            tx.missed,
            submitted
        );
    }
    check!(
        m_log.count == log_submitted && log_submitted >= 40,
        "log rx {} of {}",
        m_log.count,
        log_submitted
    );
    check!(
        m_diag.count == diag_submitted && diag_submitted >= 15,
        "diag rx {} of {}",
        m_diag.count,
        diag_submitted
    );
    // Contents and order of every delivered message.
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
    // No protocol-level loss anywhere, and the generated filters kept every frame a
    // module does not subscribe to away from its engine.
    for c in [
        m.engine.counters(),
        s1.engine.counters(),
        s2.engine.counters(),
    ] {
        check!(
            c.rx_other_transfer == 0
                && c.rx_out_of_order == 0
                && c.rx_bad_dlc == 0
                && c.deadline_missed == 0,
            "{:?}",
            c
        );
        check!(
            c.hrt_late == 0 && c.queue_full == 0 && c.tx_failed == 0 && c.rx_unknown_id == 0,
            "{:?}",
            c
        );
        check!(c.rx_incomplete == 0 && c.rx_bad_size == 0, "{:?}", c);
    }
    // The filters rejected exactly the frames of topics a module does not receive: the
    // master receives every topic it does not send; slave1 neither scan (3 frames) nor
    // diag; slave2 not log (4 frames).
    check!(m.can.rejected == 0, "master rejected {}", m.can.rejected);
    check!(
        s1.can.rejected == 3 * scan.sent + diag.sent,
        "slave1 rejected {}",
        s1.can.rejected
    );
    check!(
        s2.can.rejected == 4 * log.sent,
        "slave2 rejected {}",
        s2.can.rejected
    );
    // Heartbeats (every 10 cycles per module): each module hears the other two.
    check!(
        m.host.heartbeats >= 18 && s1.host.heartbeats >= 18 && s2.host.heartbeats >= 18,
        "heartbeats {} {} {}",
        m.host.heartbeats,
        s1.host.heartbeats,
        s2.host.heartbeats
    );
    check!(
        m.host.mismatches == 0 && s1.host.mismatches == 0 && s2.host.mismatches == 0,
        "fingerprint mismatch"
    );
    hprintln!("PASS bus_exchange");
    pass()
}
