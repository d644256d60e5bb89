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
