//! The Triskar2 release images (built by `cd examples/triskar2 && cargo build --release`)
//! boot on the emulated STM32F103 and run RTCAN on the emulated bus.
use rtcan_emu::bus::Bus;
use rtcan_emu::bxcan::Mode;
use rtcan_emu::mcu::{Mcu, Timing};
use std::path::PathBuf;

const MODULES: [&str; 6] = ["gateway", "motor1", "motor2", "motor3", "proximity", "psu"];
const MS: u64 = 1_000_000_000;

fn image(name: &str) -> Vec<u8> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../examples/triskar2/target/thumbv7m-none-eabi/release")
        .join(name);
    std::fs::read(&p).unwrap_or_else(|e| {
        panic!("{}: {e} (build the images: cd examples/triskar2 && cargo build --release)", p.display())
    })
}

#[test]
fn gateway_boots_clocks_and_can() {
    let mut m = Mcu::new("gateway", &image("gateway"), Timing::default()).unwrap();
    m.run_until(20 * MS).unwrap();
    assert_eq!(m.st.unknown, vec![], "unknown register accesses");
    assert_eq!(m.st.rcc.sysclk(), 72_000_000);
    assert_eq!(m.st.rcc.pclk1(), 36_000_000);
    assert_eq!(m.st.can.mode(), Mode::Normal);
    assert_eq!(m.st.bit_ps, 1_000_000, "1 Mbit/s");
}

#[test]
fn debug_gateway() {
    let mut m = Mcu::new("gateway", &image("gateway"), Timing::default()).unwrap();
    for i in 0..10 {
        let r = m.run_until((i + 1) * MS);
        eprintln!("t={}ms instr={} can={:?} unk={:?} active={:?} r={:?} taken={:?} asleep={}", i + 1, m.st.instructions, m.st.can.mode(), m.st.unknown.len(), m.st.scs.active, r, m.st.taken, m.st.asleep_ps / 1000_000);
    }
}

#[test]
fn debug_six() {
    let mcus: Vec<Mcu> = MODULES.iter().map(|n| Mcu::new(n, &image(n), Timing::default()).unwrap()).collect();
    let mut bus = Bus::new(mcus, 1_000_000);
    let t0 = std::time::Instant::now();
    for i in 0..10 {
        let r = bus.run_until((i + 1) * 10 * MS);
        eprintln!("t={}ms frames={} r={:?} wall={:?}", (i + 1) * 10, bus.log.len(), r, t0.elapsed());
        for m in &bus.mcus {
            eprintln!("  {} instr={} can={:?} unk={:x?} tec={} taken={:?}", m.name, m.st.instructions, m.st.can.mode(), m.st.unknown.iter().map(|u| (u.addr, u.pc, u.write)).collect::<Vec<_>>(), m.st.can.tec, m.st.taken);
        }
    }
    for (n, f, sof) in bus.log.iter().take(20) {
        eprintln!("{sof} node {n} id {:#x} dlc {}", f.id, f.dlc);
    }
}

#[test]
fn debug_pc() {
    let mut m = Mcu::new("proximity", &image("proximity"), Timing::default()).unwrap();
    for i in 0..8u64 {
        m.run_until(20 * MS + i * 13_000_000).unwrap();
        eprintln!("pc {:#x} active {:?}", m.pc(), m.st.scs.active);
    }
}
