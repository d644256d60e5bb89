//! bxCAN model against RM0008 §24 (section cited per test).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
use super::*;

fn ext(id: u32) -> RawFrame {
    RawFrame {
        id,
        ide: true,
        rtr: false,
        dlc: 8,
        data: [1, 2, 3, 4, 5, 6, 7, 8],
    }
}

fn std_frame(id: u32) -> RawFrame {
    RawFrame {
        id,
        ide: false,
        rtr: false,
        dlc: 2,
        data: [9, 8, 0, 0, 0, 0, 0, 0],
    }
}

/// Normal mode with TTCM, filters as given by `setup` (written in filter init mode).
fn running(setup: impl FnOnce(&mut BxCan)) -> BxCan {
    let mut c = BxCan::default();
    c.write(0x000, 1 | (1 << 7), 0).unwrap(); // INRQ, TTCM
    c.write(0x200, 1, 0).unwrap(); // FINIT
    setup(&mut c);
    c.write(0x200, 0, 0).unwrap();
    c.write(0x000, 1 << 7, 0).unwrap(); // leave init
    c.tick(11);
    assert_eq!(c.mode(), Mode::Normal);
    c
}

fn accept_all(c: &mut BxCan) {
    c.write(0x20C, 1, 0).unwrap(); // bank 0: 32-bit
    c.write(0x240, 0, 0).unwrap();
    c.write(0x244, 0, 0).unwrap(); // mask 0: everything
    c.write(0x21C, 1, 0).unwrap();
}

// §24.4: reset state is sleep (MSR.SLAK = 1, INAK = 0); INRQ enters init (INAK) at once;
// clearing INRQ and SLEEP leaves init only after 11 recessive bits.
#[test]
fn init_and_sleep_handshakes_24_4() {
    let mut c = BxCan::default();
    assert_eq!(c.read(0x004).unwrap() & 3, 0b10, "sleep after reset");
    assert_eq!(
        c.read(0x000).unwrap(),
        0x0001_0002,
        "MCR reset value §24.9.2"
    );
    c.write(0x000, 1, 100).unwrap();
    assert_eq!(c.read(0x004).unwrap() & 3, 0b01, "INAK set, SLAK clear");
    c.write(0x000, 0, 100).unwrap();
    c.tick(110);
    assert_eq!(c.read(0x004).unwrap() & 1, 1, "still INAK before 11 bits");
    c.tick(111);
    assert_eq!(
        c.read(0x004).unwrap() & 3,
        0,
        "normal mode after 11 recessive bits"
    );
    c.write(0x000, 2, 200).unwrap();
    assert_eq!(c.read(0x004).unwrap() & 3, 0b10, "SLEEP request: SLAK");
    // MCR.RESET forces a master reset back to sleep with reset values (§24.9.2).
    c.write(0x01C, 0x001e_0001, 0).unwrap_or(0);
    c.write(0x000, 1 << 15, 300).unwrap();
    assert_eq!(c.read(0x000).unwrap(), 0x0001_0002);
    assert_eq!(
        c.read(0x01C).unwrap(),
        0x0123_0000,
        "BTR back to reset value"
    );
}

// §24.9.2 CAN_BTR: writable in initialisation mode only.
#[test]
fn btr_only_in_init_24_9_2() {
    let mut c = BxCan::default();
    c.write(0x01C, 0x001e_0001, 0).unwrap();
    assert_eq!(c.read(0x01C).unwrap(), 0x0123_0000, "sleep mode: ignored");
    c.write(0x000, 1, 0).unwrap();
    c.write(0x01C, 0x001e_0001, 0).unwrap();
    assert_eq!(c.read(0x01C).unwrap(), 0x001e_0001);
    // §24.7.7: tq = (BRP+1) PCLK1 cycles; bit = 1 + (TS1+1) + (TS2+1) quanta: BRP 1, TS1 14, TS2 1.
    assert_eq!(c.bit_pclk_cycles(), 2 * (1 + 15 + 2));
}

// §24.7.4 figure 229: 32-bit mask mode compares STID/EXID/IDE/RTR under the mask.
#[test]
fn filter_32bit_mask_24_7_4() {
    let c = running(|c| {
        c.write(0x20C, 1, 0).unwrap();
        c.write(0x240, (0xA200 << 3) | 4, 0).unwrap(); // ID 0xA200, IDE
        c.write(0x244, (0x1FFF_FF00 << 3) | 4, 0).unwrap(); // low 8 bits don't care, IDE must match
        c.write(0x21C, 1, 0).unwrap();
    });
    assert_eq!(c.filter(&ext(0xA2FF)), Some((0, 0)));
    assert_eq!(c.filter(&ext(0xA300)), None);
    assert_eq!(c.filter(&std_frame(0)), None, "IDE is under the mask");
}

// §24.7.4: 32-bit identifier list: two exact IDs per bank, filter numbers 0 and 1.
#[test]
fn filter_32bit_list_24_7_4() {
    let c = running(|c| {
        c.write(0x204, 1, 0).unwrap(); // list mode
        c.write(0x20C, 1, 0).unwrap();
        c.write(0x240, (0x123 << 3) | 4, 0).unwrap();
        c.write(0x244, (0x456 << 3) | 4, 0).unwrap();
        c.write(0x21C, 1, 0).unwrap();
    });
    assert_eq!(c.filter(&ext(0x123)), Some((0, 0)));
    assert_eq!(c.filter(&ext(0x456)), Some((0, 1)));
    assert_eq!(c.filter(&ext(0x457)), None);
}

// §24.7.4 figure 229: 16-bit scale, STID[10:0] RTR IDE EXID[17:15]; mask mode has two
// (id, mask) pairs per bank, list mode four IDs.
#[test]
fn filter_16bit_mask_and_list_24_7_4() {
    let c = running(|c| {
        // Bank 0: 16-bit mask: pair 0 = STID 0x100 exact; pair 1 = STID 0x2xx.
        c.write(0x240, (0xFFE0 << 16) | (0x100 << 5), 0).unwrap();
        c.write(0x244, (0xE000 << 16) | (0x200 << 5), 0).unwrap();
        // Bank 1: 16-bit list of four STIDs, to FIFO 1.
        c.write(0x204, 0b10, 0).unwrap();
        c.write(0x214, 0b10, 0).unwrap();
        c.write(0x248, (0x311 << 5 << 16) | (0x310 << 5), 0)
            .unwrap();
        c.write(0x24C, (0x313 << 5 << 16) | (0x312 << 5), 0)
            .unwrap();
        c.write(0x21C, 0b11, 0).unwrap();
    });
    assert_eq!(c.filter(&std_frame(0x100)), Some((0, 0)));
    assert_eq!(c.filter(&std_frame(0x101)), None);
    assert_eq!(c.filter(&std_frame(0x2AB)), Some((0, 1)));
    // FIFO 1 numbering starts at 0 for its own banks.
    assert_eq!(c.filter(&std_frame(0x310)), Some((1, 0)));
    assert_eq!(c.filter(&std_frame(0x313)), Some((1, 3)));
    // Pair 0's mask 0xFFE0 covers STID only: an extended frame with base ID 0x100 matches too.
    assert_eq!(c.filter(&ext(0x100 << 18)), Some((0, 0)));
}

// §24.7.4 "filter match priority": 32-bit before 16-bit, list before mask, then the
// lower filter number; inactive banks still count in the numbering.
#[test]
fn filter_priority_and_numbering_24_7_4() {
    let c = running(|c| {
        // Bank 0 inactive 32-bit mask (number 0), bank 1 16-bit mask accept-all (numbers 1, 2),
        // bank 2 32-bit mask accept-all (number 3), bank 3 32-bit list with 0x55 (numbers 4, 5).
        c.write(0x20C, 0b1101, 0).unwrap();
        c.write(0x204, 0b1000, 0).unwrap();
        c.write(0x248, 0, 0).unwrap();
        c.write(0x24C, 0, 0).unwrap();
        c.write(0x250, 0, 0).unwrap();
        c.write(0x254, 0, 0).unwrap();
        c.write(0x258, (0x55 << 3) | 4, 0).unwrap();
        c.write(0x25C, (0x66 << 3) | 4, 0).unwrap();
        c.write(0x21C, 0b1110, 0).unwrap();
    });
    assert_eq!(c.filter(&ext(0x55)), Some((0, 4)), "32-bit list wins");
    assert_eq!(c.filter(&ext(0x66)), Some((0, 5)));
    assert_eq!(
        c.filter(&ext(0x77)),
        Some((0, 3)),
        "32-bit mask before 16-bit"
    );
    assert_eq!(c.filter(&std_frame(0x7)), Some((0, 3)));
}

// §24.7.4: no active bank, no frame; filter registers are read-only for an active
// bank outside filter init mode.
#[test]
fn filter_registers_protected_24_7_4() {
    let mut c = running(accept_all);
    c.write(0x240, 0x1234_5678, 0).unwrap();
    assert_eq!(
        c.read(0x240).unwrap(),
        0,
        "active bank, FINIT clear: write ignored"
    );
    c.write(0x21C, 0, 0).unwrap();
    c.write(0x240, 0x1234_5678, 0).unwrap();
    assert_eq!(
        c.read(0x240).unwrap(),
        0x1234_5678,
        "inactive bank: writable"
    );
    assert_eq!(c.filter(&ext(1)), None);
}

fn load(c: &mut BxCan, m: u32, f: &RawFrame) {
    let base = 0x180 + 16 * m;
    c.write(base + 4, u32::from(f.dlc), 0).unwrap();
    c.write(
        base + 8,
        u32::from_le_bytes([f.data[0], f.data[1], f.data[2], f.data[3]]),
        0,
    )
    .unwrap();
    c.write(
        base + 12,
        u32::from_le_bytes([f.data[4], f.data[5], f.data[6], f.data[7]]),
        0,
    )
    .unwrap();
    c.write(base, f.ir() | 1, 0).unwrap();
}

// §24.7.3: with TXFP = 0 the pending mailbox with the lowest identifier goes first
// (equal: lower mailbox number); TSR.TME/CODE/LOW follow (§24.9.2).
#[test]
fn mailbox_priority_by_identifier_24_7_3() {
    let mut c = running(accept_all);
    assert_eq!(c.read(0x008).unwrap() >> 26 & 7, 0b111, "all empty");
    load(&mut c, 0, &ext(0x300));
    load(&mut c, 1, &ext(0x100));
    load(&mut c, 2, &ext(0x200));
    let tsr = c.read(0x008).unwrap();
    assert_eq!(tsr >> 26 & 7, 0, "none empty");
    assert_eq!(
        tsr >> 29 & 7,
        0b001,
        "LOW: mailbox 0 has the lowest priority"
    );
    assert_eq!(c.tx_candidate().map(|(m, f)| (m, f.id)), Some((1, 0x100)));
    c.tx_started(1, 500);
    c.tx_finished(1, true, 640);
    let tsr = c.read(0x008).unwrap();
    assert_eq!(tsr >> 8 & 3, 0b11, "RQCP1, TXOK1");
    assert_eq!(tsr >> 24 & 3, 1, "CODE: mailbox 1 empty");
    // TTCM: TDT1R.TIME is the SOF bit time (§24.7.2).
    assert_eq!(c.read(0x194).unwrap() >> 16, 500);
    assert_eq!(c.tx_candidate().map(|(m, _)| m), Some(2));
    // A standard frame beats an extended one with the same base ID (arbitration).
    assert!(std_frame(0x1).arbitration_key() < ext(0x1 << 18).arbitration_key());
    assert!(!irq(&c, 0), "TMEIE off: no TX interrupt");
    c.write(0x014, 1, 0).unwrap();
    assert!(irq(&c, 0), "TMEIE and RQCP: TX interrupt line");
    c.write(0x008, 1 << 8, 0).unwrap();
    assert_eq!(
        c.read(0x008).unwrap() >> 8 & 0xF,
        0,
        "RQCP write clears RQCP/TXOK/ALST/TERR"
    );
    assert!(!irq(&c, 0));
}

fn irq(c: &BxCan, line: usize) -> bool {
    c.irq_lines().get(line).copied().unwrap_or(false)
}

// §24.7.3 "transmit priority by request order" (TXFP = 1).
#[test]
fn mailbox_priority_fifo_24_7_3() {
    let mut c = running(accept_all);
    let mcr = c.read(0).unwrap();
    c.write(0, mcr | 4, 0).unwrap();
    load(&mut c, 2, &ext(0x300));
    load(&mut c, 0, &ext(0x100));
    assert_eq!(c.tx_candidate().map(|(m, _)| m), Some(2));
}

// §24.7.3 "abort": a pending mailbox empties at once (RQCP, TXOK clear); one being
// transmitted completes first and then reports success.
#[test]
fn mailbox_abort_24_7_3() {
    let mut c = running(accept_all);
    load(&mut c, 0, &ext(0x10));
    load(&mut c, 1, &ext(0x20));
    c.write(0x008, 1 << 15, 0).unwrap(); // ABRQ1
    let tsr = c.read(0x008).unwrap();
    assert_eq!(tsr >> 8 & 3, 0b01, "RQCP1 without TXOK1");
    assert_eq!(tsr >> 27 & 1, 1, "TME1");
    c.tx_started(0, 10);
    c.write(0x008, 1 << 7, 20).unwrap(); // ABRQ0 while on the wire
    assert_eq!(c.read(0x008).unwrap() >> 26 & 1, 0, "still pending");
    c.tx_finished(0, true, 150);
    assert_eq!(c.read(0x008).unwrap() & 3, 0b11, "completed: TXOK0");
    // Writes to a pending mailbox are ignored (§24.7.3).
    load(&mut c, 2, &ext(0x30));
    c.write(0x1A0, ext(0x31).ir() | 1, 0).unwrap();
    assert_eq!(c.tx_candidate().map(|(_, f)| f.id), Some(0x30));
}

// §24.7.5: three-message FIFO; FMP counts, FULL at three, the fourth is an overrun:
// RFLM = 0 overwrites the last message, RFLM = 1 discards the new one. RFOM releases.
#[test]
fn fifo_overrun_per_rflm_24_7_5() {
    for rflm in [false, true] {
        let mut c = running(accept_all);
        if rflm {
            let mcr = c.read(0).unwrap();
            c.write(0, mcr | 8, 0).unwrap();
        }
        c.write(0x014, (1 << 1) | (1 << 3), 0).unwrap(); // FMPIE0, FOVIE0
        for (i, id) in [0x1, 0x2, 0x3].iter().enumerate() {
            c.receive(&ext(*id), 1000 * i as u64);
        }
        assert_eq!(c.read(0x00C).unwrap(), 3 | (1 << 3), "FMP 3, FULL");
        c.receive(&ext(0x4), 4000);
        assert_eq!(c.read(0x00C).unwrap() >> 4 & 1, 1, "FOVR");
        assert!(irq(&c, 1));
        let mut ids = vec![];
        while c.read(0x00C).unwrap() & 3 != 0 {
            ids.push(c.read(0x1B0).unwrap() >> 3);
            c.write(0x00C, 1 << 5, 0).unwrap();
        }
        assert_eq!(ids, if rflm { vec![1, 2, 3] } else { vec![1, 2, 4] });
        c.write(0x00C, 1 << 4, 0).unwrap();
        assert_eq!(c.read(0x00C).unwrap(), 0);
        assert!(!irq(&c, 1));
    }
}

// §24.7.2 TTCM: RDTxR.TIME holds the 16-bit bit timer at SOF; FMI and DLC alongside.
#[test]
fn ttcm_stamp_at_sof_24_7_2() {
    let mut c = running(accept_all);
    c.receive(&ext(0xA200), 0x1_2345);
    let rdtr = c.read(0x1B4).unwrap();
    assert_eq!(rdtr >> 16, 0x2345, "wraps at 16 bits");
    assert_eq!(rdtr & 0xF, 8);
    assert_eq!(rdtr >> 8 & 0xFF, 0, "FMI");
    assert_eq!(c.read(0x1B8).unwrap(), 0x0403_0201);
    assert_eq!(c.read(0x1B0).unwrap(), (0xA200 << 3) | 4);
    // Without TTCM the TIME field stays 0.
    let mut c = BxCan::default();
    c.write(0, 1, 0).unwrap();
    accept_all(&mut c);
    c.write(0, 0, 0).unwrap();
    c.tick(11);
    c.receive(&ext(1), 77);
    assert_eq!(c.read(0x1B4).unwrap() >> 16, 0);
}

// §24.7.6: TEC > 255 is bus-off (ESR.BOFF, ERRI); with ABOM recovery after 128 × 11
// recessive bits resets the counters; without ABOM it stays off.
#[test]
fn bus_off_and_automatic_recovery_24_7_6() {
    let mut c = running(accept_all);
    let mcr = c.read(0).unwrap();
    c.write(0, mcr | (1 << 6), 0).unwrap(); // ABOM
    c.write(0x014, 1 << 15 | 1 << 10, 0).unwrap();
    load(&mut c, 0, &ext(0x5));
    c.inject_tx_errors(32, 1000);
    assert_eq!(c.read(0x018).unwrap() & 7, 0b111, "EWGF, EPVF, BOFF");
    assert_eq!(c.read(0x018).unwrap() >> 16 & 0xFF, 255);
    assert!(irq(&c, 3), "SCE line: ERRIE and ERRI");
    assert_eq!(c.tx_candidate(), None, "bus-off sends nothing");
    c.tick(1000 + 128 * 11 - 1);
    assert!(c.is_bus_off());
    c.tick(1000 + 128 * 11);
    assert!(!c.is_bus_off());
    assert_eq!(c.read(0x018).unwrap(), 0);
    assert!(
        c.tx_candidate().is_some(),
        "pending mailbox goes out after recovery"
    );
    let mut c = running(accept_all);
    c.inject_tx_errors(32, 0);
    c.tick(100_000);
    assert!(c.is_bus_off(), "no ABOM: stays bus-off");
}

// Unknown registers are errors, not silent zeros.
#[test]
fn unknown_registers_are_errors() {
    let mut c = BxCan::default();
    assert_eq!(c.read(0x020), Err(0x020));
    assert_eq!(c.write(0x100, 1, 0), Err(0x100));
    assert_eq!(
        c.read(0x2B0),
        Err(0x2B0),
        "bank 14 does not exist on the F103"
    );
}
