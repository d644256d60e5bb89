//! `rtcan-emu`: the Triskar2 release images on six emulated STM32F103 with the
//! simulator's plants (docs/EMULATOR.md); `rtcan sim --emulate` runs this program (a
//! separate process: the GPL-2.0 emulator is not linked into the `rtcan` command).
//! The report is the simulator's (`rtcan_sim::triskar::report`), plus what only the
//! emulator knows (per module: instructions, unknown register accesses, defmt lines).
use rtcan_emu::mcu::{Mcu, Timing};
use rtcan_emu::robot::{EmuRobot, HostScript, MODULES};
use rtcan_emu::sim_report::{triskar_run, RunInfo};
use rtcan_emu::{engine_ram, report, rtt};
use rtcan_sim::triskar::report::{triskar_json, triskar_text};
use std::path::PathBuf;
use std::process::ExitCode;

const USAGE: &str = "usage: rtcan-emu [--images DIR] [--robot FILE] [--seconds N] [--seed N] [--cpi X] [--ber X] [--fault SPEC]... [--json]
  --images DIR  the six Triskar2 ELF files (default examples/triskar2/target/thumbv7m-none-eabi/release)
  --robot FILE  the robot the images were built from (default robot.toml)
  --seconds N   emulated time, 0 < N <= 3600 (default 10, as `rtcan sim` for triskar2)
  --seed N      seed of the plant's sensor noise (default 1)
  --cpi X       core cycles per instruction, wait states included, 0.5 <= X <= 10
                (default: 1.0 + 0.25 per flash wait state = 1.5 at 72 MHz)
  --ber X       bit error rate of the bus, 0 <= X < 1 (rtcan-sim's error frames; default 0)
  --fault SPEC  a fault of rtcan-sim's bus at a time, as `rtcan sim --fault`:
                MODULE:stuck@T, release, partition, rejoin, reset (e.g. motor1:stuck@2s)
  --json        the report as JSON (the fields of `rtcan sim --json`, plus `emulation`)";

fn main() -> ExitCode {
    match run(std::env::args().skip(1).collect()) {
        Ok(()) => ExitCode::SUCCESS,
        Err((code, msg)) => {
            eprintln!("error: {msg}");
            ExitCode::from(code)
        }
    }
}

struct Args {
    dir: PathBuf,
    robot: PathBuf,
    seconds: f64,
    seed: u64,
    timing: Timing,
    faults: Vec<String>,
    ber: f64,
    json: bool,
}

fn parse(args: Vec<String>) -> Result<Option<Args>, (u8, String)> {
    let mut a = Args {
        dir: PathBuf::from("examples/triskar2/target/thumbv7m-none-eabi/release"),
        robot: PathBuf::from("robot.toml"),
        seconds: 10.0,
        seed: 1,
        timing: Timing::default(),
        faults: Vec::new(),
        ber: 0.0,
        json: false,
    };
    let mut it = args.into_iter();
    while let Some(arg) = it.next() {
        let mut value = |name: &str| it.next().ok_or((2, format!("{name} needs a value")));
        match arg.as_str() {
            "--images" => a.dir = PathBuf::from(value("--images")?),
            "--robot" => a.robot = PathBuf::from(value("--robot")?),
            "--seconds" => {
                a.seconds = value("--seconds")?
                    .parse()
                    .map_err(|_| (2, "bad --seconds".to_string()))?
            }
            "--seed" => {
                a.seed = value("--seed")?
                    .parse()
                    .map_err(|_| (2, "bad --seed".to_string()))?
            }
            "--cpi" => {
                let cpi: f64 = value("--cpi")?
                    .parse()
                    .map_err(|_| (2, "bad --cpi".to_string()))?;
                if !(cpi.is_finite() && (0.5..=10.0).contains(&cpi)) {
                    return Err((2, format!("--cpi must be in [0.5, 10], got {cpi}")));
                }
                a.timing = Timing {
                    cpi,
                    per_wait_state: 0.0,
                    ..Timing::default()
                };
            }
            "--fault" => a.faults.push(value("--fault")?),
            "--ber" => {
                let ber: f64 = value("--ber")?
                    .parse()
                    .map_err(|_| (2, "bad --ber".to_string()))?;
                if !(ber.is_finite() && (0.0..1.0).contains(&ber)) {
                    return Err((2, format!("--ber must be in [0, 1), got {ber}")));
                }
                a.ber = ber;
            }
            "--json" => a.json = true,
            "-h" | "--help" => {
                println!("{USAGE}");
                return Ok(None);
            }
            s => return Err((2, format!("unknown argument `{s}`\n{USAGE}"))),
        }
    }
    if !(a.seconds > 0.0 && a.seconds <= 3600.0) {
        return Err((2, "--seconds must be in (0, 3600]".into()));
    }
    Ok(Some(a))
}

fn run(args: Vec<String>) -> Result<(), (u8, String)> {
    let Some(a) = parse(args)? else {
        return Ok(());
    };
    let plan = rtcan_model::Robot::load(&a.robot).map_err(|d| (1, d.render()))?;
    let mut images = Vec::new();
    let mut mcus = Vec::new();
    for name in MODULES {
        let p = a.dir.join(name);
        let elf = std::fs::read(&p).map_err(|e| {
            (
                1,
                format!(
                    "{}: {e} (build the images: cd examples/triskar2 && cargo build --release)",
                    p.display()
                ),
            )
        })?;
        mcus.push(Mcu::new(name, &elf, a.timing).map_err(|e| (1, format!("{name}: {e:?}")))?);
        images.push(elf);
    }
    let wall = 1.5;
    let mut robot =
        EmuRobot::new(&plan, mcus, wall, a.seed, HostScript::default()).map_err(|e| (1, e))?;
    robot.bus.sim.set_bit_error_rate(a.ber);
    for spec in &a.faults {
        let f = rtcan_sim::fault::parse(spec, &MODULES).map_err(|e| (2, e))?;
        robot
            .bus
            .schedule(f)
            .map_err(|e| (2, format!("--fault `{spec}`: {e}")))?;
    }
    // SRT publication instants from the publishers' RAM (docs/EMULATOR.md, "The report").
    robot.watch_publications(&plan, &images);
    let mut raw = vec![Vec::new(); MODULES.len()];
    let t0 = cpu_seconds();
    let end_ns = (a.seconds * 1e9) as u64;
    let mut t = 0;
    while t < end_ns {
        t = (t + 10_000_000).min(end_ns);
        robot.run_until(t).map_err(|e| (1, e))?;
        for (i, m) in robot.bus.mcus.iter_mut().enumerate() {
            if let Some(r) = raw.get_mut(i) {
                r.extend(rtt::drain(m));
            }
        }
    }
    let cpu = cpu_seconds() - t0;
    let speed = if cpu > 0.0 { a.seconds / cpu } else { 0.0 };
    let logs: Vec<Vec<String>> = images
        .iter()
        .zip(&raw)
        .map(|(elf, bytes)| rtt::decode(elf, bytes).unwrap_or_else(|e| vec![format!("<{e}>")]))
        .collect();
    let cpi = a.timing.cpi + 2.0 * a.timing.per_wait_state;
    let info = RunInfo {
        seconds: a.seconds,
        seed: a.seed,
        wall_x_m: wall,
        cpi,
    };
    let emulation = report::json(&robot.bus, a.seconds, cpu, &logs);
    // The engines' counters in RAM, from each image's DWARF (an image without debug info
    // reports its frames counted on the bus).
    let engines: Vec<_> = images
        .iter()
        .map(|elf| engine_ram::locate(elf).ok())
        .collect();
    let run = triskar_run(&mut robot, &plan, info, &logs, &engines).map_err(|e| (1, e))?;
    if a.json {
        let sim = triskar_json(&run, speed);
        let body = sim.strip_suffix('}').unwrap_or(&sim);
        println!("{body},\"emulation\":{emulation}}}");
        return Ok(());
    }
    for (name, lines) in MODULES.iter().zip(&logs) {
        for l in lines {
            println!("[{name}] {l}");
        }
    }
    println!();
    print!("{}", triskar_text(&run));
    println!(
        "\nemulated: {} s of six STM32F103 at CPI {cpi} in {cpu:.2} s CPU of one thread ({speed:.2}x real time)",
        a.seconds
    );
    for m in &robot.bus.mcus {
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

/// CPU time of this thread (Linux `/proc/thread-self/schedstat`, ns).
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns / 1e9)
}
