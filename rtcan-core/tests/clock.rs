//! Slot clock: master identity, slave lock, rate estimation with ±1000 ppm crystals,
//! missed syncs, counter wrap and the inverse mapping.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan_core::clock::SlotClock;
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::tables::BusConfig;
use rtcan_core::Nanos;

/// The paper's bus: 1 Mbit/s, 60 slots of 166,666 ns (a 9,999,960 ns cycle).
fn bus(wrap: u32) -> BusConfig {
    BusConfig {
        bitrate: 1_000_000,
        slots_per_cycle: 60,
        slot_ns: 166_666,
        hyperperiod_cycles: 1,
        cycle_counter_wrap: wrap,
        laxity: LaxityEncoding::Linear { unit_ns: 100_000 },
        guard_ns: 0,
        fingerprint: 0,
    }
}

/// A slave's crystal: local = offset + bus · (1 + ppm / 10⁶), exact.
#[derive(Clone, Copy)]
struct Crystal {
    offset: Nanos,
    ppm: i64,
}

impl Crystal {
    fn local(self, bus: Nanos) -> Nanos {
        let drift = i128::from(bus) * i128::from(self.ppm) / 1_000_000;
        (i128::from(self.offset) + i128::from(bus) + drift) as Nanos
    }
}

/// Runs `cycles` cycles from absolute cycle `first`; `heard(c)` says whether the sync of
/// cycle `c` reaches the slave and `jitter(c)` is added to its SOF timestamp. From the
/// third sync heard on, every slot boundary of every cycle must map within one bit time
/// (1000 ns), and `to_bus` must invert `to_local` within 1 ns. Returns the clock.
fn run(
    bus: &BusConfig,
    xtal: Crystal,
    first: u64,
    cycles: u64,
    heard: impl Fn(u64) -> bool,
    jitter: impl Fn(u64) -> i64,
) -> SlotClock {
    let mut clk = SlotClock::slave(bus);
    assert!(!clk.is_locked());
    assert_eq!(clk.cycles_since_sync(123), u64::MAX);
    let cycle_ns = bus.cycle_ns();
    let wrap = u64::from(bus.cycle_counter_wrap);
    let mut syncs = 0;
    let mut worst = 0i64;
    for c in first..first + cycles {
        let start = c * cycle_ns;
        if heard(c) {
            let sof = (xtal.local(start) as i64 + jitter(c)) as Nanos;
            assert!(clk.on_sync(sof, (c % wrap) as u16));
            syncs += 1;
            assert!(clk.is_locked());
            assert_eq!(clk.is_rate_valid(), syncs >= 2);
        }
        if syncs < 3 {
            continue;
        }
        for k in 0..u64::from(bus.slots_per_cycle) {
            let b = start + k * bus.slot_ns;
            let truth = xtal.local(b);
            let got = clk.to_local(b);
            let err = got as i64 - truth as i64;
            worst = worst.max(err.abs());
            assert!(err.abs() <= 1000, "cycle {c} slot {k}: {err} ns off");
            assert!(clk.to_bus(got).abs_diff(b) <= 1, "to_bus(to_local({b}))");
            assert!(clk.to_local(clk.to_bus(truth)).abs_diff(truth) <= 1);
        }
    }
    assert!(syncs >= 3, "test never got going");
    eprintln!("worst slot-boundary error {worst} ns");
    clk
}

#[test]
fn master_local_clock_is_bus_clock() {
    let b = bus(32_760);
    let clk = SlotClock::master(&b, 5_000);
    assert!(clk.is_locked() && clk.is_rate_valid());
    assert_eq!(clk.to_bus(5_000), 0);
    assert_eq!(clk.to_bus(5_000 + 3 * b.cycle_ns()), 3 * b.cycle_ns());
    assert_eq!(clk.to_local(7), 5_007);
    assert_eq!(clk.to_bus(10), 0, "before bus time 0 saturates");
    assert_eq!(clk.rate_ppb(), 0);
    assert_eq!(clk.cycles_since_sync(1 << 40), 0);
    assert_eq!(clk.cycle_counter(32_761), 1);
}

#[test]
fn slave_tracks_fast_and_slow_crystals() {
    for ppm in [1000, -1000] {
        let xtal = Crystal {
            offset: 123_456_789,
            ppm,
        };
        let clk = run(&bus(32_760), xtal, 0, 100, |_| true, |_| 0);
        // Rate measured to the ppb. The crystal model floors to whole ns, so 24 of every
        // 25 cycles (the last 24 included) drift exactly ±10 000 ns per 9 999 960 ns cycle,
        // i.e. ±1 000 004 ppb, and the low-pass filter settles there (the 25th cycle's
        // 9 999 ns pulls it 100 ppb away, 0.1 ppb left after 24 cycles).
        let per_cycle = ppm * 10 * 1_000_000_000 / 9_999_960;
        assert_eq!(per_cycle.abs(), 1_000_004);
        assert!(
            (clk.rate_ppb() - per_cycle).abs() <= 1,
            "{} ppb",
            clk.rate_ppb()
        );
        assert_eq!(clk.last_sync_cycle(), Some(99));
    }
}

#[test]
fn first_sync_locks_offset_second_gives_rate() {
    let b = bus(32_760);
    let xtal = Crystal {
        offset: 1_000_000,
        ppm: 1000,
    };
    let mut clk = SlotClock::slave(&b);
    assert!(clk.on_sync(xtal.local(10 * b.cycle_ns()), 10));
    assert!(clk.is_locked() && !clk.is_rate_valid());
    // Offset exact at the sync itself; rate still nominal.
    assert_eq!(
        clk.to_local(10 * b.cycle_ns()),
        xtal.local(10 * b.cycle_ns())
    );
    assert_eq!(clk.rate_ppb(), 0);
    assert!(clk.on_sync(xtal.local(11 * b.cycle_ns()), 11));
    assert!(clk.is_rate_valid());
    // 1 ns of timestamp rounding over one 10 ms cycle is 100 ppb.
    assert!(
        (clk.rate_ppb() - 1_000_000).abs() <= 100,
        "{}",
        clk.rate_ppb()
    );
    // Sync-loss detection: 2.5 cycles after the last sync, 2 whole cycles have passed.
    let later = xtal.local(11 * b.cycle_ns() + 5 * b.cycle_ns() / 2);
    assert_eq!(clk.cycles_since_sync(later), 2);
    assert_eq!(clk.cycles_since_sync(xtal.local(11 * b.cycle_ns())), 0);
}

#[test]
fn missed_syncs_are_bridged_by_the_rate() {
    let xtal = Crystal {
        offset: 77,
        ppm: -1000,
    };
    // Every third sync lost, then 255 lost in a row, then every other one.
    let heard = |c: u64| match c {
        0..100 => c % 3 != 1,
        100..355 => false,
        _ => c.is_multiple_of(2),
    };
    let clk = run(&bus(32_760), xtal, 0, 500, heard, |_| 0);
    assert_eq!(clk.last_sync_cycle(), Some(498));
}

#[test]
fn longest_gap_with_5000_ppm_before_the_rate_is_known() {
    // Two syncs 256 cycles apart on a ±5000 ppm crystal: the nominal-rate estimate of the
    // gap is 1.3 cycles off, the counter still unwraps it, and the rate comes out exact.
    for ppm in [5000, -5000] {
        let b = bus(32_760);
        let xtal = Crystal { offset: 9, ppm };
        let mut clk = SlotClock::slave(&b);
        clk.on_sync(xtal.local(32_700 * b.cycle_ns()), 32_700);
        clk.on_sync(xtal.local(32_956 * b.cycle_ns()), (32_956 % 32_760) as u16);
        assert_eq!(clk.last_sync_cycle(), Some(32_956));
        assert_eq!(clk.rate_ppb(), ppm * 1000);
    }
}

#[test]
fn counter_wrap_is_unwrapped() {
    // A tiny wrap (16 cycles) starting just before it wraps, gaps longer than the wrap.
    let xtal = Crystal {
        offset: 5_000_000_000,
        ppm: 1000,
    };
    let heard = |c: u64| !(40..80).contains(&c) && c % 5 != 3;
    let clk = run(&bus(16), xtal, 13, 200, heard, |_| 0);
    assert_eq!(clk.last_sync_cycle(), Some(212));
    // And the 15-bit counter's real wrap.
    let clk = run(&bus(32_760), xtal, 32_700, 150, |c| c % 7 != 0, |_| 0);
    assert_eq!(clk.last_sync_cycle(), Some(32_849));
}

#[test]
fn sof_jitter_is_filtered() {
    // ±200 ns of timestamp jitter (pseudo-random but fixed).
    let xtal = Crystal {
        offset: 1_000_031,
        ppm: 1000,
    };
    let jitter = |c: u64| ((c * 2_654_435_761) % 401) as i64 - 200;
    run(&bus(32_760), xtal, 0, 300, |_| true, jitter);
}

#[test]
fn master_restart_relocks() {
    let b = bus(32_760);
    let xtal = Crystal {
        offset: 0,
        ppm: 1000,
    };
    let mut clk = SlotClock::slave(&b);
    for c in 100..105 {
        clk.on_sync(xtal.local(c * b.cycle_ns()), c as u16);
    }
    assert!(
        (clk.rate_ppb() - 1_000_000).abs() <= 100,
        "{}",
        clk.rate_ppb()
    );
    // The master comes back at cycle 0 one cycle later: the counter says "32,656
    // cycles ahead", the local clock says one; the implied rate is absurd, so relock.
    let t = xtal.local(105 * b.cycle_ns());
    assert!(clk.on_sync(t, 0));
    assert_eq!(clk.last_sync_cycle(), Some(0));
    assert!(!clk.is_rate_valid());
    assert_eq!(clk.to_local(0), t);
    // A repeated sync is ignored.
    assert!(clk.on_sync(t, 0));
    assert_eq!(clk.last_sync_cycle(), Some(0));
    clk.unlock();
    assert!(!clk.is_locked());
}
