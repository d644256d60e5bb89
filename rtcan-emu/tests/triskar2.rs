//! The six Triskar2 release images (`cd examples/triskar2 && cargo build --release`) on
//! six emulated STM32F103 on one emulated bus: boot, run, and survive bus faults.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
use rtcan_emu::bus::Bus;
use rtcan_emu::bxcan::{Mode, RawFrame};
use rtcan_emu::mcu::{Mcu, Timing};
use std::path::PathBuf;

const MODULES: [&str; 6] = ["gateway", "motor1", "motor2", "motor3", "proximity", "psu"];
/// Picoseconds per millisecond.
const MS: u64 = 1_000_000_000;
/// Bit time at 1 Mbit/s, ps.
const BIT: u64 = 1_000_000;

/// The image of module `name`: from `$RTCAN_EMU_IMAGES` if set (a directory of ELF files),
/// else from the release build of examples/triskar2.
fn image(name: &str) -> Vec<u8> {
    let dir = std::env::var_os("RTCAN_EMU_IMAGES")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../examples/triskar2/target/thumbv7m-none-eabi/release")
        });
    let p = dir.join(name);
    std::fs::read(&p).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (build the images first: cd examples/triskar2 && cargo build --release)",
            p.display()
        )
    })
}

fn robot() -> Bus {
    let mcus = MODULES
        .iter()
        .map(|n| Mcu::new(n, &image(n), Timing::default()).unwrap())
        .collect();
    Bus::new(mcus, BIT)
}

fn no_unknown(bus: &Bus) {
    for m in &bus.mcus {
        assert_eq!(
            m.st.unknown,
            vec![],
            "{}: unknown register accesses",
            m.name
        );
        assert_eq!(m.st.fault, None, "{}", m.name);
    }
}

/// The gateway's cycle: SOF distance of its first two frames with ID < 0x100 (the
/// cycle-start reference, whose ID counts the cycles).
fn cycle_bits(bus: &Bus) -> u64 {
    let refs: Vec<u64> = bus
        .log
        .iter()
        .filter(|(n, f, _)| *n == 0 && f.id < 0x100)
        .map(|(_, _, s)| *s)
        .collect();
    assert!(refs.len() >= 2, "gateway sends its cycle reference");
    refs[1] - refs[0]
}

/// CPU time of this thread (Linux `/proc/thread-self/schedstat`, ns), so the speed
/// figure does not depend on other jobs sharing the machine.
fn thread_cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns / 1e9)
}

/// First SOF (bit time) of a frame with identifier `id`.
fn first_of(bus: &Bus, id: u32) -> Option<u64> {
    bus.log
        .iter()
        .find(|(_, f, _)| same_frame(f.id, id))
        .map(|(_, _, s)| *s)
}

/// Frames like `id` (same topic and fragment counter, any transfer ID) with SOF in
/// [from, to) bit times.
fn count_of(bus: &Bus, id: u32, from: u64, to: u64) -> u64 {
    bus.log
        .iter()
        .filter(|(_, f, s)| same_frame(f.id, id) && (from..to).contains(s))
        .count() as u64
}

/// True if wire identifier `wire` is the frame `want` names: the same laxity and message
/// ID, and the same fragment counter once the transfer ID (docs/PROTOCOL.md §7.1: the
/// fragment field is `tid << k | counter` for a multi-frame message) is masked off.
/// `want`'s field is its counter with transfer ID 0; the topic's frame count comes from
/// the table below.
fn same_frame(wire: u32, want: u32) -> bool {
    if wire & !0x7F != want & !0x7F {
        return false;
    }
    let count = FRAMES
        .iter()
        .find(|(base, _)| base & !0x7F == want & !0x7F)
        .map_or(1, |(_, n)| *n);
    let counter = |id: u32| rtcan_core::fragment::split_field(count, (id & 0x7F) as u8).1;
    counter(wire) == counter(want)
}

/// Frames per message of the multi-frame HRT topics (robot.toml: wheel_setpoints 12 B,
/// odometry 24 B).
const FRAMES: [(u32, u8); 2] = [(WHEEL_SETPOINTS, 2), (ODOMETRY, 3)];

// Identifiers of the HRT topics as the images send them (checked against robot.toml's
// rates in `five_seconds_of_triskar2`): encoder1 0xA200, wheel_setpoints 0xA380/0xA381,
// encoder3 0xA280, odometry 0xA000..0xA003, proximity 0xA080.
const ENCODER1: u32 = 0xA200;
const WHEEL_SETPOINTS: u32 = 0xA380;
const ENCODER3: u32 = 0xA280;
const ODOMETRY: u32 = 0xA000;
const PROXIMITY: u32 = 0xA080;

#[test]
fn six_images_boot_and_sync_within_three_cycles() {
    let mut bus = robot();
    bus.run_until(200 * MS).unwrap();
    no_unknown(&bus);
    for m in &bus.mcus {
        assert_eq!(m.st.rcc.sysclk(), 72_000_000, "{}", m.name);
        assert_eq!(m.st.rcc.pclk1(), 36_000_000, "{}", m.name);
        assert_eq!(m.st.can.mode(), Mode::Normal, "{}", m.name);
        assert_eq!(m.st.bit_ps, BIT, "{}: 1 Mbit/s", m.name);
    }
    let cycle = cycle_bits(&bus);
    // 10 ms (robot.toml) SOF to SOF; the SOF lands on the bit after the TXRQ.
    assert!(cycle.abs_diff(10_000) <= 1, "cycle of {cycle} bits");
    let first_ref = bus.log.first().map(|(_, _, s)| *s).unwrap();
    assert!(
        first_ref < 1_000,
        "gateway on the bus within 1 ms of power-on: {first_ref}"
    );
    // Each publisher's first HRT frame: within 3 cycles of the first reference, plus its
    // own period for topics slower than the cycle (it is due once per period).
    for (id, period_bits) in [
        (ENCODER1, 0),
        (WHEEL_SETPOINTS, 0),
        (ENCODER3, 0),
        (ODOMETRY, 20_000),
        (PROXIMITY, 40_000),
    ] {
        let at = first_of(&bus, id).unwrap_or(u64::MAX);
        eprintln!("{id:#x}: first frame at bit {at} (first reference at bit {first_ref})");
        assert!(
            at < first_ref + 3 * cycle + period_bits,
            "{id:#x} first at bit {at}"
        );
    }
}

#[test]
fn five_seconds_of_triskar2() {
    let mut bus = robot();
    let t0 = std::time::Instant::now();
    let cpu0 = thread_cpu_seconds();
    bus.run_until(5_000 * MS).unwrap();
    let wall = t0.elapsed().as_secs_f64();
    let cpu = thread_cpu_seconds() - cpu0;
    no_unknown(&bus);
    // Rates of robot.toml over the last four seconds: each HRT message in every one of its
    // periods (±1 at the window edges).
    let (from, to) = (1_000 * MS / BIT, 5_000 * MS / BIT);
    for (id, hz) in [
        (ENCODER1, 200),
        (WHEEL_SETPOINTS, 100),
        (WHEEL_SETPOINTS + 1, 100),
        (ENCODER3, 200),
        (ODOMETRY, 50),
        (ODOMETRY + 2, 50),
        (PROXIMITY, 25),
    ] {
        let n = count_of(&bus, id, from, to);
        assert!(
            n.abs_diff(4 * hz) <= 1,
            "{id:#x}: {n} frames in 4 s, {hz} Hz expected"
        );
    }
    let refs = bus
        .log
        .iter()
        .filter(|(n, f, s)| *n == 0 && f.id < 0x1000 && (from..to).contains(s))
        .count();
    assert!(refs.abs_diff(400) <= 1, "cycle references: {refs}");
    for m in &bus.mcus {
        assert_eq!(m.st.can.tec, 0, "{}: no transmit errors", m.name);
    }
    eprintln!(
        "5 s emulated in {cpu:.2} s CPU of one thread ({:.2}x real time; {wall:.2} s wall)",
        5.0 / cpu
    );
}

/// Frames of `id` in [from, to) ms.
fn count_ms(bus: &Bus, id: u32, from: u64, to: u64) -> u64 {
    count_of(bus, id, from * MS / BIT, to * MS / BIT)
}

/// rtcan-sim's `stuck` fault on the emulated bus: motor1's transceiver holds the bus
/// dominant for 100 µs while motor1 is sending. The simulator's fault confinement
/// (`rtcan_sim::confinement`) puts the transmitter bus-off and every other controller
/// error-passive; the emulated bxCANs show it (ESR, RM0008 §24.9.2) and the board code
/// recovers: motor1 after 128 × 11 recessive bits (ABOM, §24.7.6), the others with
/// their next good frames.
#[test]
fn bus_off_and_recovery() {
    let mut bus = robot();
    bus.run_until(300 * MS).unwrap();
    let mcr = bus.mcus[1].st.can.read(0).unwrap();
    // Step until motor1's frame is on the wire.
    let mut t = 300 * MS;
    loop {
        if let rtcan_sim::bus::Activity::Busy(w) = bus.sim.activity() {
            if w.node == 1 {
                break;
            }
        }
        t += 2 * BIT;
        bus.run_until(t).unwrap();
        assert!(t < 310 * MS, "motor1 never sent");
    }
    let bit = bus.bit();
    let at = bit * 1_000;
    for (kind, when) in [
        (rtcan_sim::fault::FaultKind::Stuck, at),
        (rtcan_sim::fault::FaultKind::Release, at + 100_000),
    ] {
        bus.schedule(rtcan_sim::fault::Fault {
            module: 1,
            kind,
            at: when,
        })
        .unwrap();
    }
    bus.run_until(t + 2 * BIT).unwrap();
    // TEC past 255: bus-off; the others REC 255: error-passive (ESR.EPVF).
    assert!(bus.mcus[1].st.can.is_bus_off(), "motor1 bus-off");
    let esr = |bus: &mut Bus, i: usize| bus.mcus[i].st.can.read(0x018).unwrap();
    assert_eq!(esr(&mut bus, 1) >> 2 & 1, 1, "motor1 ESR.BOFF");
    for i in [0, 2, 3, 4, 5] {
        assert_eq!(esr(&mut bus, i) >> 1 & 1, 1, "{}: ESR.EPVF", MODULES[i]);
        assert_eq!(esr(&mut bus, i) >> 24, 255, "{}: REC", MODULES[i]);
    }
    bus.run_until(600 * MS).unwrap();
    let released = bit + 100;
    assert_eq!(
        count_of(&bus, ENCODER1, bit, released + 128 * 11),
        0,
        "bus-off: motor1 silent"
    );
    let back = bus
        .log
        .iter()
        .find(|(_, f, s)| f.id == ENCODER1 && *s > bit)
        .map(|(_, _, s)| *s);
    let back = back.unwrap_or(u64::MAX);
    let recovered = bus.sim.controller(1).unwrap().conf.bus_off_entries;
    eprintln!("bus-off at bit {bit} (released at {released}), encoder1 back at bit {back}; bus-off entries {recovered}");
    assert_eq!(recovered, 1);
    assert!(
        back < released + 128 * 11 + 3 * 10_000,
        "motor1 back within 3 cycles of its recovery: {back}"
    );
    assert!(count_ms(&bus, ENCODER3, 301, 310) >= 1, "the others go on");
    no_unknown(&bus);
    assert!(
        mcr & (1 << 6) != 0,
        "the board enables automatic bus-off management (ABOM)"
    );
    assert!(
        !bus.mcus[1].st.can.is_bus_off(),
        "recovered after 128 x 11 recessive bits"
    );
    // Error-active again everywhere: good frames brought REC back (127 → 119 and down).
    for (i, name) in MODULES.iter().enumerate() {
        assert_eq!(
            esr(&mut bus, i) & 3,
            0,
            "{}: ESR {:#x}",
            name,
            esr(&mut bus, i)
        );
    }
    // Back at 200 Hz within three cycles of the recovery.
    assert!(
        count_ms(&bus, ENCODER1, 340, 600).abs_diff(52) <= 1,
        "encoder1 after recovery: {}",
        count_ms(&bus, ENCODER1, 340, 600)
    );
}

/// rtcan-sim's bit errors on the emulated bus: frames destroyed at a random bit, an
/// error frame (6 + 8 bits), the transmitter retries (bxCAN automatic retransmission,
/// RM0008 §24.7.3) and its TEC counts +8 / −1 (ISO 11898-1 §12); every HRT topic keeps
/// its rate.
#[test]
fn bit_errors_retransmitted() {
    let mut bus = robot();
    bus.run_until(100 * MS).unwrap();
    bus.sim.set_bit_error_rate(1e-4);
    bus.run_until(1_100 * MS).unwrap();
    no_unknown(&bus);
    let errors = bus.sim.stats.error_frames;
    let destroyed = bus.sim.wire.iter().filter(|w| !w.ok).count() as u64;
    eprintln!(
        "1 s at BER 1e-4: {} good frames, {errors} error frames; TEC {:?}",
        bus.sim.stats.frames_ok,
        bus.mcus.iter().map(|m| m.st.can.tec).collect::<Vec<_>>()
    );
    assert!(errors >= 5, "error frames: {errors}");
    assert_eq!(destroyed, errors, "each error frame on the wire record");
    // Every destroyed frame was sent again: the same identifier follows it.
    for (k, w) in bus.sim.wire.iter().enumerate().filter(|(_, w)| !w.ok) {
        assert!(
            bus.sim.wire[k + 1..]
                .iter()
                .take(8)
                .any(|v| v.ok && v.frame.id() == w.frame.id() && v.node == w.node),
            "{:#x} retransmitted",
            w.frame.id().raw()
        );
    }
    for (id, hz) in [(ENCODER1, 200), (ENCODER3, 200), (PROXIMITY, 25)] {
        let n = count_ms(&bus, id, 100, 1_100);
        assert!(n.abs_diff(hz) <= 2, "{id:#x}: {n} in 1 s");
    }
    // Far from error-passive: a few +8 and many −1.
    for m in &bus.mcus {
        assert!(m.st.can.tec < 96, "{}: TEC {}", m.name, m.st.can.tec);
    }
}

#[test]
fn rx_fifo_overrun() {
    let mut bus = robot();
    bus.run_until(300 * MS).unwrap();
    let bit = bus.bit();
    // Five frames at once into motor3's FIFO 0 (three fit, RM0008 §24.7.5): overrun.
    let f = RawFrame {
        id: WHEEL_SETPOINTS,
        ide: true,
        rtr: false,
        dlc: 8,
        data: [0; 8],
    };
    for i in 0..5 {
        bus.mcus[3].st.can.receive(&f, bit - 200 + i);
    }
    assert_eq!(bus.mcus[3].st.can.read(0x00C).unwrap() >> 4 & 1, 1, "FOVR0");
    bus.run_until(600 * MS).unwrap();
    no_unknown(&bus);
    assert_eq!(
        bus.mcus[3].st.can.read(0x00C).unwrap() >> 4 & 1,
        0,
        "the driver cleared FOVR0"
    );
    assert!(
        count_ms(&bus, ENCODER3, 330, 600).abs_diff(54) <= 1,
        "motor3 keeps its rate"
    );
}

#[test]
fn module_reset_while_the_bus_runs() {
    let mut bus = robot();
    bus.run_until(300 * MS).unwrap();
    bus.reset_node(1).unwrap();
    bus.run_until(305 * MS).unwrap();
    assert_eq!(count_ms(&bus, ENCODER1, 301, 305), 0, "rebooting");
    bus.run_until(600 * MS).unwrap();
    no_unknown(&bus);
    assert!(
        count_ms(&bus, ENCODER3, 300, 600).abs_diff(60) <= 1,
        "motor3 undisturbed"
    );
    // Back within three cycles of its reset: every 5 ms from 340 ms on.
    assert!(
        count_ms(&bus, ENCODER1, 340, 600).abs_diff(52) <= 1,
        "encoder1: {}",
        count_ms(&bus, ENCODER1, 340, 600)
    );
}

#[test]
fn frames_queued_at_boot() {
    let mut bus = robot();
    bus.run_until(300 * MS).unwrap();
    bus.reset_node(3).unwrap();
    // Step until motor3's bxCAN is in normal mode (its start-up code still runs with
    // interrupts off), then queue frames with SOF stamps from before its clock started.
    let mut t = 300 * MS;
    while bus.mcus[3].st.can.mode() != Mode::Normal {
        t += MS / 100;
        bus.run_until(t).unwrap();
        assert!(t < 320 * MS, "motor3 never enabled CAN");
    }
    let bit = bus.bit();
    let f = RawFrame {
        id: WHEEL_SETPOINTS,
        ide: true,
        rtr: false,
        dlc: 8,
        data: [0; 8],
    };
    for i in 0..3u64 {
        bus.mcus[3]
            .st
            .can
            .receive(&f, bit.saturating_sub(60_000 + 1_000 * i));
    }
    bus.run_until(600 * MS).unwrap();
    no_unknown(&bus);
    assert!(
        count_ms(&bus, ENCODER3, 350, 600).abs_diff(50) <= 1,
        "encoder3: {}",
        count_ms(&bus, ENCODER3, 350, 600)
    );
}

#[test]
fn defmt_logs_decoded_per_module() {
    let mut bus = robot();
    let mut raw: Vec<Vec<u8>> = vec![Vec::new(); 6];
    let images: Vec<Vec<u8>> = MODULES.iter().map(|n| image(n)).collect();
    // When each module logged "safe state cleared" (R2P: sync acquired), to 1 ms.
    let mut synced_ms: Vec<Option<u64>> = vec![None; 6];
    for ms in 1..=200 {
        bus.run_until(ms * MS).unwrap();
        for (i, m) in bus.mcus.iter_mut().enumerate() {
            let new = rtcan_emu::rtt::drain(m);
            if !new.is_empty() {
                raw[i].extend(new);
                let lines = rtcan_emu::rtt::decode(&images[i], &raw[i]).unwrap();
                if synced_ms[i].is_none() && lines.iter().any(|l| l == "INFO safe state cleared") {
                    synced_ms[i] = Some(ms);
                }
            }
        }
    }
    eprintln!("synced at (ms): {synced_ms:?}");
    // Boot to synced: the line is logged by the module's lowest-priority node task at its
    // first step after the safe state cleared (synchronised, every module's heartbeat
    // heard: the `on_missing` rules), so the bound is 3 bus cycles (30 ms) plus that
    // node's period, the fastest rate robot.toml gives a topic it publishes (motor1's
    // kinematics 10 ms, motor2's odometry 20 ms, motor3's motor_ctrl3 5 ms, proximity's
    // ir_ranger 40 ms, psu's battery_monitor 1 s; the gateway's ros_bridge has no rate).
    let plan =
        rtcan_model::Robot::load(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../robot.toml"))
            .unwrap();
    for (i, name) in MODULES.iter().enumerate().skip(1) {
        let m = plan.modules.iter().position(|m| m.name == *name).unwrap();
        let lowest = (0..plan.nodes.len())
            .filter(|&n| plan.nodes[n].module == m)
            .min_by_key(|&n| (plan.nodes[n].priority, n))
            .unwrap();
        let period_ms = plan
            .topics
            .iter()
            .filter(|t| t.publisher == lowest)
            .filter_map(|t| t.rate_hz)
            .map(|hz| (1000.0 / hz).ceil() as u64)
            .min()
            .unwrap();
        let at = synced_ms[i].unwrap_or(u64::MAX);
        assert!(
            at <= 30 + period_ms,
            "{name} synced at {at} ms (its logging node's period {period_ms} ms)"
        );
    }
    for (i, name) in MODULES.iter().enumerate() {
        let lines = rtcan_emu::rtt::decode(&image(name), &raw[i]).unwrap();
        for l in &lines {
            eprintln!("[{name}] {l}");
        }
        assert!(lines.iter().all(|l| !l.contains("malformed")), "{name}");
        // module_app.rs logs "<module> up" once the app starts.
        assert!(
            lines.contains(&format!("INFO {name} up")),
            "{name}: {lines:?}"
        );
    }
    // Draining twice gives nothing new: the read offset was written back.
    assert!(rtcan_emu::rtt::drain(&mut bus.mcus[0]).is_empty());
}
