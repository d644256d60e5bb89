use rtcan_emu::mcu::{Mcu, Timing};
#[test]
fn dbg() {
    let img = std::fs::read("../examples/triskar2/target/thumbv7m-none-eabi/release/motor3").unwrap();
    let mut m = Mcu::new("m3", &img, Timing::default()).unwrap();
    m.run_until(50_000_000_000).unwrap();
    eprintln!("before: pc {:#x} mode {:?} instr {}", m.pc(), m.st.can.mode(), m.st.instructions);
    m.reset().unwrap();
    for i in 0..5u64 {
        let r = m.run_until(50_000_000_000 + (i + 1) * 2_000_000_000);
        eprintln!("after: r {:?} pc {:#x} mode {:?} instr {} active {:?} unk {:?} wfi asleep {}", r, m.pc(), m.st.can.mode(), m.st.instructions, m.st.scs.active, m.st.unknown, m.st.asleep_ps);
    }
}
