//! `rtcan-emu`: the Triskar2 release images on six emulated STM32F103 (docs/EMULATOR.md);
//! `rtcan sim --emulate` runs this program (a separate process: the GPL-2.0 emulator is
//! not linked into the `rtcan` command).
use rtcan_emu::bus::Bus;
use rtcan_emu::mcu::{Mcu, Timing};
use rtcan_emu::{report, rtt};
use std::path::PathBuf;
use std::process::ExitCode;

const MODULES: [&str; 6] = ["gateway", "motor1", "motor2", "motor3", "proximity", "psu"];
const USAGE: &str = "usage: rtcan-emu [--images DIR] [--seconds N] [--json]
  --images DIR  the six Triskar2 ELF files (default examples/triskar2/target/thumbv7m-none-eabi/release)
  --seconds N   emulated time, 0 < N <= 3600 (default 5)
  --json        the report as JSON";

fn main() -> ExitCode {
    match run(std::env::args().skip(1).collect()) {
        Ok(()) => ExitCode::SUCCESS,
        Err((code, msg)) => {
            eprintln!("error: {msg}");
            ExitCode::from(code)
        }
    }
}

fn run(args: Vec<String>) -> Result<(), (u8, String)> {
    let mut dir = PathBuf::from("examples/triskar2/target/thumbv7m-none-eabi/release");
    let (mut seconds, mut json) = (5.0f64, false);
    let mut it = args.into_iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--images" => {
                dir = it
                    .next()
                    .map(PathBuf::from)
                    .ok_or((2, "--images needs a value".into()))?
            }
            "--seconds" => {
                seconds = it
                    .next()
                    .and_then(|s| s.parse().ok())
                    .ok_or((2, "bad --seconds".to_string()))?;
            }
            "--json" => json = true,
            "-h" | "--help" => {
                println!("{USAGE}");
                return Ok(());
            }
            s => return Err((2, format!("unknown argument `{s}`\n{USAGE}"))),
        }
    }
    if !(seconds > 0.0 && seconds <= 3600.0) {
        return Err((2, "--seconds must be in (0, 3600]".into()));
    }
    let mut images = Vec::new();
    let mut mcus = Vec::new();
    for name in MODULES {
        let p = dir.join(name);
        let elf = std::fs::read(&p).map_err(|e| {
            (
                1,
                format!(
                    "{}: {e} (build the images: cd examples/triskar2 && cargo build --release)",
                    p.display()
                ),
            )
        })?;
        mcus.push(
            Mcu::new(name, &elf, Timing::default()).map_err(|e| (1, format!("{name}: {e:?}")))?,
        );
        images.push(elf);
    }
    let mut bus = Bus::new(mcus, 1_000_000);
    let mut raw = vec![Vec::new(); MODULES.len()];
    let t0 = cpu_seconds();
    let end_ms = (seconds * 1000.0) as u64;
    for ms in (10..=end_ms.max(10)).step_by(10) {
        bus.run_until(ms.min(end_ms) * 1_000_000_000)
            .map_err(|e| (1, e))?;
        for (i, m) in bus.mcus.iter_mut().enumerate() {
            if let Some(r) = raw.get_mut(i) {
                r.extend(rtt::drain(m));
            }
        }
    }
    let cpu = cpu_seconds() - t0;
    let logs: Vec<Vec<String>> = images
        .iter()
        .zip(&raw)
        .map(|(elf, bytes)| rtt::decode(elf, bytes).unwrap_or_else(|e| vec![format!("<{e}>")]))
        .collect();
    let rep = report::json(&bus, seconds, cpu, &logs);
    if json {
        println!("{rep:#}");
        return Ok(());
    }
    for (name, lines) in MODULES.iter().zip(&logs) {
        for l in lines {
            println!("[{name}] {l}");
        }
    }
    println!(
        "{seconds} s emulated: {} frames, bus load {:.1} %, {:.2}x real time",
        bus.log.len(),
        100.0 * report::bus_load(&bus, (seconds * 1e6) as u64),
        if cpu > 0.0 { seconds / cpu } else { 0.0 }
    );
    for (id, (n, mean, jit)) in report::id_stats(&bus) {
        if n > 1 && mean < 1_000_000.0 {
            println!(
                "  id {id:#010x}: {n:5} frames, period {mean:9.1} us, max deviation {jit:7.1} us"
            );
        }
    }
    for m in &bus.mcus {
        for u in &m.st.unknown {
            println!(
                "  {}: unknown register {:#010x} ({}) at pc {:#010x}",
                m.name,
                u.addr,
                if u.write { "write" } else { "read" },
                u.pc
            );
        }
    }
    Ok(())
}

/// CPU time of this process (Linux `/proc/self/schedstat`, ns).
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns / 1e9)
}
