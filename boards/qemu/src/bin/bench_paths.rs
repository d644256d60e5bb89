//! The firmware's interrupt paths, by name, as the STM32F103 images run them (split
//! architecture of boards/common `protocol`: slot timer commits prepared plans, CAN
//! RX/TX interrupts only queue, the protocol task runs the engine), measured in
//! instructions under QEMU `-icount` over the 3-module robot of robots/qemu-test.toml
//! with the traffic of `bus_exchange` (HRT 1 and 3 frames, SRT 1 and 4 frames, NRT,
//! heartbeats, sync on two slaves).
//!
//! First a checked run: payloads verified byte for byte at every receiver, slaves synced
//! once, HRT sent every cycle and received as often, no late HRT, no wake-up the
//! protocol task reached late. Then the measured run (no payload checks, so the rows
//! count the protocol's work). Prints `BENCH <row> max <n> mean <n> samples <n>`;
//! `slot_boundary_to_txrq` is the longest path from the slot-timer interrupt's first
//! instruction to the TXRQ store plus the longest critical section a lower priority holds
//! on the slot-timer resource (its worst blocking); its mean is the path alone.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use lm3s6965 as _;
use rtcan_board_qemu::meter::{report, Kind, PathMeter, Stat, SysTickMeter};
use rtcan_board_qemu::robot::{self, master, slave1, slave2};
use rtcan_board_qemu::split::SplitStation;
use rtcan_board_qemu::test_host::TestHost;
use rtcan_board_qemu::{check, pass, Node, SoftBus};

#[entry]
fn main() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        rtcan_board_qemu::fail()
    };
    let meter = PathMeter::new(SysTickMeter::new(cp.SYST));
    run(&meter, true);
    meter.reset();
    run(&meter, false);
    let rows = [
        ("isr_slot_timer", Kind::IsrSlotTimer),
        ("isr_can_rx", Kind::IsrCanRx),
        ("isr_can_tx", Kind::IsrCanTx),
        ("task_rx_process", Kind::TaskRxProcess),
        ("task_sync_slave", Kind::TaskSyncSlave),
        ("task_prepare_slot", Kind::TaskPrepareSlot),
        ("task_tx_done", Kind::TaskTxDone),
        ("critical_section_slot", Kind::CriticalSection),
    ];
    for (name, kind) in rows {
        report(name, &meter.stat(kind));
    }
    let path = meter.to_txrq();
    let blocking = meter.stat(Kind::CriticalSection).max;
    let worst = Stat {
        max: path.max + blocking,
        sum: path.sum,
        n: path.n,
    };
    report("slot_boundary_to_txrq", &worst);
    pass()
}

/// 100 cycles of the tests' traffic; with `verify`, checks every delivery and the HRT
/// counts.
fn run(meter: &PathMeter, verify: bool) {
    let (mut hm, mut h1, mut h2) = (
        TestHost::<{ master::TX.len() }, { master::RX_COUNT }>::new(&master::TABLES),
        TestHost::<{ slave1::TX.len() }, { slave1::RX_COUNT }>::new(&slave1::TABLES),
        TestHost::<{ slave2::TX.len() }, { slave2::RX_COUNT }>::new(&slave2::TABLES),
    );
    hm.verify = verify;
    h1.verify = verify;
    h2.verify = verify;
    let bus_cfg = robot::BUS;
    // Prepare half a slot ahead (above the protocol task's worst response, see README).
    let lead = bus_cfg.slot_ns / 2;
    let rate = bus_cfg.bitrate;
    let mut m = SplitStation::new(
        master::engine(0),
        hm,
        0,
        0,
        rate,
        lead,
        master::FILTERS,
        meter,
    );
    let mut s1 = SplitStation::new(
        slave1::engine(1_000_001),
        h1,
        1_000_001,
        40_000,
        rate,
        lead,
        slave1::FILTERS,
        meter,
    );
    let mut s2 = SplitStation::new(
        slave2::engine(777_777),
        h2,
        777_777,
        65_000,
        rate,
        lead,
        slave2::FILTERS,
        meter,
    );
    let (m_cmd, s1_log, s2_diag) = (
        master::topics::tx::CMD,
        slave1::topics::tx::LOG,
        slave2::topics::tx::DIAG,
    );
    let cycle = bus_cfg.cycle_ns();
    let mut bus = SoftBus::new(rate);
    let mut none = rtcan_board_qemu::meter::NoMeter;
    let cycles = 100;
    let mut t = 0;
    // Kick-off: every module's protocol task runs once at start-up (arms its first wake-up).
    bus.run_until(
        &mut [&mut m as &mut dyn Node, &mut s1, &mut s2],
        0,
        &mut none,
    );
    m.start(0);
    s1.start(0);
    s2.start(0);
    while t < cycles * cycle {
        t += cycle / 2;
        bus.run_until(
            &mut [&mut m as &mut dyn Node, &mut s1, &mut s2],
            t,
            &mut none,
        );
        if !(s1.engine.is_synced() && s2.engine.is_synced()) {
            continue;
        }
        if let Some(tok) = m.host.next_message(m_cmd) {
            m.publish(t, m_cmd, tok);
        }
        if t.is_multiple_of(2 * cycle) {
            if let Some(tok) = s1.host.next_message(s1_log) {
                s1.publish(t, s1_log, tok);
            }
        }
        if t.is_multiple_of(5 * cycle) {
            if let Some(tok) = s2.host.next_message(s2_diag) {
                s2.publish(t, s2_diag, tok);
            }
        }
    }
    let odom_sent = s1.host.tx_log(slave1::topics::tx::ODOM).sent;
    let scan_sent = s2.host.tx_log(slave2::topics::tx::SCAN).sent;
    let odom_m = m.host.rx_log(master::topics::rx::ODOM);
    let odom_2 = s2.host.rx_log(slave2::topics::rx::ODOM);
    let scan_m = m.host.rx_log(master::topics::rx::SCAN);
    let cmd_1 = s1.host.rx_log(slave1::topics::rx::CMD);
    let log_m = m.host.rx_log(master::topics::rx::LOG);
    let diag_m = m.host.rx_log(master::topics::rx::DIAG);
    hprintln!(
        "split run (verify {}): timer interrupts {} {} {}; odom {} sent, {} / {} received; scan {} sent, {} received; cmd {}, log {}, diag {}; late prepares {} {} {}",
        verify,
        m.timer_interrupts,
        s1.timer_interrupts,
        s2.timer_interrupts,
        odom_sent,
        odom_m.count,
        odom_2.count,
        scan_sent,
        scan_m.count,
        cmd_1.count,
        log_m.count,
        diag_m.count,
        m.proto.stats().late_prepares,
        s1.proto.stats().late_prepares,
        s2.proto.stats().late_prepares
    );
    check!(
        s1.host.synced == 1 && s2.host.synced == 1,
        "slaves synced once"
    );
    check!(
        s1.host.sync_lost == 0 && s2.host.sync_lost == 0,
        "no sync loss"
    );
    check!(odom_sent >= cycles as u32 - 5, "odom sent {}", odom_sent);
    check!(scan_sent >= cycles as u32 - 5, "scan sent {}", scan_sent);
    check!(
        odom_m.count == odom_sent && odom_2.count == odom_sent && scan_m.count == scan_sent,
        "HRT received as often as sent"
    );
    check!(
        cmd_1.count > 100 && log_m.count > 40 && diag_m.count > 15,
        "SRT/NRT delivered"
    );
    for l in [odom_m, odom_2, scan_m, cmd_1, log_m, diag_m] {
        check!(
            l.bad == 0 && l.out_of_order == 0,
            "bad or out-of-order delivery"
        );
    }
    for c in [
        m.engine.counters(),
        s1.engine.counters(),
        s2.engine.counters(),
    ] {
        check!(c.hrt_late == 0, "late HRT {}", c.hrt_late);
        check!(
            c.rx_crc == 0 && c.rx_out_of_order == 0 && c.rx_incomplete == 0,
            "receive errors"
        );
    }
    for p in [m.proto.stats(), s1.proto.stats(), s2.proto.stats()] {
        check!(p.late_prepares == 0, "late prepares {}", p.late_prepares);
    }
}
