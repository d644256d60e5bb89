//! On-target test of the generated R2P layer: the three modules of robots/qemu-test.toml,
//! each an engine driving its generated `host()` (`ModuleHost` over the module's topic
//! statics) behind its generated `FILTERS`, exchange typed messages through the
//! generated publishers and subscribers of their nodes: HRT `odom` (1 frame) and `scan`
//! (3 frames) once per cycle, SRT `cmd` (1 frame) every half cycle, SRT `log` (4
//! frames) every 2 cycles, NRT `diag` every 5 cycles, for 100 cycles. Every message is
//! checked byte for byte and in sequence at every subscriber; topic statistics and
//! engine counters must show nothing lost, late or replaced. Exit code 0 = pass.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use lm3s6965 as _;
use rtcan::pubsub::{Message, Subscriber, TopicStats};
use rtcan::TopicInfo;
use rtcan_board_qemu::meter::NoMeter;
use rtcan_board_qemu::robot::{self, master, slave1, slave2, topics};
use rtcan_board_qemu::test_host::{check_patterned, patterned};
use rtcan_board_qemu::{check, pass, Node, SoftBus, Station};

const CYCLES: u64 = 100;

/// What one subscriber received.
#[derive(Clone, Copy, Debug, Default)]
struct SubLog {
    count: u32,
    /// Messages whose bytes are not the pattern of their sequence number.
    bad: u32,
    /// Messages whose sequence number is not the previous one plus 1 (0 first).
    gaps: u32,
    last: Option<u16>,
}

/// Takes every queued message of `sub` (a subscriber of topic `info`) and checks it.
fn drain<T: Message, const N: usize, const S: usize, const Q: usize>(
    sub: &Subscriber<'static, T, N, S, Q>,
    info: &TopicInfo,
    log: &mut SubLog,
) {
    while let Some(msg) = sub.try_recv() {
        log.count += 1;
        match check_patterned(info.msg_id, &*msg) {
            Some(seq) => {
                if seq != log.last.map_or(0, |l| l.wrapping_add(1)) {
                    log.gaps += 1;
                }
                log.last = Some(seq);
            }
            None => log.bad += 1,
        }
    }
}

/// A publishing topic's counters: everything published was sent, nothing dropped,
/// replaced, late or refused.
fn sent_all(name: &str, s: TopicStats, published: u32) -> bool {
    let ok = s.published == published
        && s.sent == published
        && s.pool_exhausted == 0
        && s.remote_overflows == 0
        && s.hrt_replaced == 0
        && s.deadline_misses == 0
        && s.not_submittable == 0;
    if !ok {
        hprintln!("{}: published {} {:?}", name, published, s);
    }
    ok
}

/// A receiving topic's counters: every bus payload decoded and queued.
fn received_all(s: TopicStats) -> bool {
    s.rx_decode_errors == 0 && s.rx_dropped == 0 && s.pool_exhausted == 0
}

#[entry]
fn main() -> ! {
    let cycle = robot::BUS.cycle_ns();
    let mut m = Station::new(master::engine(0), master::host(), 0).filtered(master::FILTERS);
    let mut s1 = Station::new(slave1::engine(3_141_593), slave1::host(), 3_141_593)
        .filtered(slave1::FILTERS);
    let mut s2 = Station::new(slave2::engine(2_718_282), slave2::host(), 2_718_282)
        .filtered(slave2::FILTERS);

    // The nodes' generated handles: a publisher only where robot.toml declares it.
    let odom_pub = slave1::nodes::odometry::odom_pub();
    let log_pub = slave1::nodes::odometry::log_pub();
    let scan_pub = slave2::nodes::ranger::scan_pub();
    let diag_pub = slave2::nodes::ranger::diag_pub();
    let cmd_pub = master::nodes::control::cmd_pub();
    let (m_odom, m_scan, m_log, m_diag) = (
        master::nodes::control::odom_sub(),
        master::nodes::control::scan_sub(),
        master::nodes::control::log_sub(),
        master::nodes::control::diag_sub(),
    );
    let s1_cmd = slave1::nodes::odometry::cmd_sub();
    let (s2_odom, s2_cmd) = (
        slave2::nodes::ranger::odom_sub(),
        slave2::nodes::ranger::cmd_sub(),
    );
    // Receive logs: master odom, scan, log, diag; slave1 cmd; slave2 odom, cmd.
    let mut rx = [SubLog::default(); 7];
    let drain_all = |rx: &mut [SubLog; 7]| {
        let [a, b, c, d, e, f, g] = rx;
        drain(&m_odom, &topics::ODOM, a);
        drain(&m_scan, &topics::SCAN, b);
        drain(&m_log, &topics::LOG, c);
        drain(&m_diag, &topics::DIAG, d);
        drain(&s1_cmd, &topics::CMD, e);
        drain(&s2_odom, &topics::ODOM, f);
        drain(&s2_cmd, &topics::CMD, g);
    };

    let mut bus = SoftBus::new(robot::BUS.bitrate);
    let (mut odom, mut scan, mut cmd, mut log, mut diag) = (0u16, 0u16, 0u16, 0u16, 0u16);
    let (mut refused, mut cmd_waits) = (0u32, 0u32);
    let mut t = 0;
    while t < CYCLES * cycle {
        t += cycle / 2;
        bus.run_until(
            &mut [&mut m as &mut dyn Node, &mut s1, &mut s2],
            t,
            &mut NoMeter,
        );
        drain_all(&mut rx);
        if !(s1.engine.is_synced() && s2.engine.is_synced()) || t > (CYCLES - 5) * cycle {
            continue;
        }
        // HRT: a new value once per cycle, latched for the next reserved slot.
        if t.is_multiple_of(cycle) {
            let (now1, now2) = (s1.local(t), s2.local(t));
            match patterned(topics::ODOM.msg_id, odom).map(|v| odom_pub.send(v, now1)) {
                Some(Ok(())) => odom += 1,
                _ => refused += 1,
            }
            match patterned(topics::SCAN.msg_id, scan).map(|v| scan_pub.send(v, now2)) {
                Some(Ok(())) => scan += 1,
                _ => refused += 1,
            }
        }
        // SRT cmd every half cycle, like a controller that sends its next command once
        // the previous one has left (the engine holds one cmd: its queue is 1 deep).
        if cmd_pub.stats().sent == u32::from(cmd) {
            match patterned(topics::CMD.msg_id, cmd).map(|v| cmd_pub.send(v, m.local(t))) {
                Some(Ok(())) => cmd += 1,
                _ => refused += 1,
            }
            m.pump(t);
        } else {
            cmd_waits += 1;
        }
        if t.is_multiple_of(2 * cycle) {
            match patterned(topics::LOG.msg_id, log).map(|v| log_pub.send(v, s1.local(t))) {
                Some(Ok(())) => log += 1,
                _ => refused += 1,
            }
            s1.pump(t);
        }
        if t.is_multiple_of(5 * cycle) {
            match patterned(topics::DIAG.msg_id, diag).map(|v| diag_pub.send(v, s2.local(t))) {
                Some(Ok(())) => diag += 1,
                _ => refused += 1,
            }
            s2.pump(t);
        }
    }
    // Let the last messages drain.
    bus.run_until(
        &mut [&mut m as &mut dyn Node, &mut s1, &mut s2],
        (CYCLES + 2) * cycle,
        &mut NoMeter,
    );
    drain_all(&mut rx);

    let [m_odom, m_scan, m_log, m_diag, s1_cmd, s2_odom, s2_cmd] = rx;
    hprintln!(
        "frames {}; published odom {} scan {} cmd {} log {} diag {}; refused {}, cmd waits {}",
        bus.stats.frames,
        odom,
        scan,
        cmd,
        log,
        diag,
        refused,
        cmd_waits
    );
    hprintln!(
        "received: master odom {} scan {} log {} diag {}; slave1 cmd {}; slave2 odom {} cmd {}",
        m_odom.count,
        m_scan.count,
        m_log.count,
        m_diag.count,
        s1_cmd.count,
        s2_odom.count,
        s2_cmd.count
    );
    hprintln!("counters M {:?}", m.engine.counters());
    hprintln!("counters S1 {:?}", s1.engine.counters());
    hprintln!("counters S2 {:?}", s2.engine.counters());

    check!(refused == 0, "refused {}", refused);
    // Enough traffic of every kind (publishing runs from sync to 5 cycles before the end).
    check!(
        odom >= 90 && scan >= 90 && cmd >= 150 && log >= 40 && diag >= 15,
        "published odom {} scan {} cmd {} log {} diag {}",
        odom,
        scan,
        cmd,
        log,
        diag
    );
    // Publishers: each message sent exactly once, none replaced, late or dropped.
    check!(
        sent_all("odom", odom_pub.stats(), u32::from(odom))
            && sent_all("scan", scan_pub.stats(), u32::from(scan))
            && sent_all("cmd", cmd_pub.stats(), u32::from(cmd))
            && sent_all("log", log_pub.stats(), u32::from(log))
            && sent_all("diag", diag_pub.stats(), u32::from(diag)),
        "publisher statistics"
    );
    // HRT slots before the first and after the last value found nothing to send: the
    // engine and the topic count the same slots.
    check!(
        odom_pub.stats().nothing_to_send == s1.engine.counters().hrt_empty
            && scan_pub.stats().nothing_to_send == s2.engine.counters().hrt_empty,
        "empty HRT slots: odom {} of {}, scan {} of {}",
        odom_pub.stats().nothing_to_send,
        s1.engine.counters().hrt_empty,
        scan_pub.stats().nothing_to_send,
        s2.engine.counters().hrt_empty
    );
    // Subscribers: every message, in order, every byte as published.
    for (name, got, published) in [
        ("master odom", m_odom, odom),
        ("master scan", m_scan, scan),
        ("master log", m_log, log),
        ("master diag", m_diag, diag),
        ("slave1 cmd", s1_cmd, cmd),
        ("slave2 odom", s2_odom, odom),
        ("slave2 cmd", s2_cmd, cmd),
    ] {
        check!(
            got.count == u32::from(published) && got.bad == 0 && got.gaps == 0,
            "{}: {:?} of {}",
            name,
            got,
            published
        );
    }
    check!(
        received_all(master::topics::ODOM.stats())
            && received_all(master::topics::SCAN.stats())
            && received_all(master::topics::LOG.stats())
            && received_all(master::topics::DIAG.stats())
            && received_all(slave1::topics::CMD.stats())
            && received_all(slave2::topics::ODOM.stats())
            && received_all(slave2::topics::CMD.stats()),
        "receiving topic statistics"
    );
    // The engines called the hosts with indices of their tables only.
    check!(
        m.host.bad_index() == 0 && s1.host.bad_index() == 0 && s2.host.bad_index() == 0,
        "bad index {} {} {}",
        m.host.bad_index(),
        s1.host.bad_index(),
        s2.host.bad_index()
    );
    // Both slaves locked once and never lost sync.
    check!(
        slave1::STATUS.sync_losses() == 0 && slave2::STATUS.sync_losses() == 0,
        "sync losses {} {}",
        slave1::STATUS.sync_losses(),
        slave2::STATUS.sync_losses()
    );
    for c in [
        m.engine.counters(),
        s1.engine.counters(),
        s2.engine.counters(),
    ] {
        check!(
            c.rx_other_transfer == 0
                && c.rx_out_of_order == 0
                && c.rx_bad_dlc == 0
                && c.rx_incomplete == 0
                && c.rx_bad_size == 0
                && c.rx_unknown_id == 0,
            "{:?}",
            c
        );
        check!(
            c.deadline_missed == 0
                && c.hrt_late == 0
                && c.queue_full == 0
                && c.tx_failed == 0
                && c.sync_missed == 0,
            "{:?}",
            c
        );
    }
    hprintln!("PASS pubsub_exchange");
    pass()
}
