//! `rtcan sim`: parses the command line, runs `rtcan_sim::session::run` and prints its
//! report (docs/SIM.md).
use std::io::Write as _;
use std::path::{Path, PathBuf};

use rtcan_sim::plot::{self, Plot};
use rtcan_sim::policy::PolicyKind;
use rtcan_sim::run::{Run, Scenario, SimConfig};
use rtcan_sim::session::{self, Report, Request, Speed, Which};
use rtcan_sim::triskar::report as triskar_report;
use rtcan_sim::{candump, report};

/// `rtcan sim`: the workspace robot runs triskar2, any other robot its generic traffic
/// scenario. `--emulate` runs the Triskar2 release images on emulated STM32F103s instead
/// (options --seconds, --seed, --cpi, --ber, --fault, --json, --images; docs/EMULATOR.md); `--campaign`
/// runs the fault campaign on triskar2 and rtcan-paper, N s per case (default 10).
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The robot (default ./robot.toml)
    #[arg(value_name = "robot.toml")]
    robot: Vec<PathBuf>,
    /// A built-in scenario or a scenario file (docs/SIM.md)
    #[arg(long, value_name = "NAME")]
    scenario: Option<String>,
    /// Simulated time, 0 < N <= 100000 (triskar2 default 10, others 1)
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    seconds: Option<f64>,
    /// Seed of every random stream
    #[arg(long, value_name = "S")]
    seed: Option<u64>,
    /// SRT event-rate scale, 0 < X <= 100
    #[arg(long, value_name = "X", allow_hyphen_values = true)]
    load: Option<f64>,
    /// Bit error rate, 0 <= P < 1
    #[arg(long, value_name = "P", allow_hyphen_values = true)]
    ber: Option<f64>,
    /// The report as JSON on stdout
    #[arg(long)]
    json: bool,
    /// Write candump log, SVG plots and report.json to DIR
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Stamp DIR/can0.log from this epoch, seconds since 1970 or `now`, for tools that
    /// read candump logs (log2asc); default 0, the simulated timeline
    #[arg(long, value_name = "SECONDS|now", requires = "out", value_parser = crate::log_epoch::parse)]
    log_epoch: Option<u64>,
    /// rtcan-paper: add the load sweep 0.5..1.2
    #[arg(long)]
    sweep: bool,
    /// triskar2: the bus master stops at S seconds (S >= 0)
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    master_dies_at: Option<String>,
    /// triskar2, repeatable: MODULE:KIND@T, KIND one of dies, returns, reset, babble,
    /// stuck, release, partition, rejoin, stall=D, step=+D or step=-D (T, D with unit s,
    /// ms or us), e.g. --fault gateway:dies@2s (docs/SIM.md, Faults)
    #[arg(long, value_name = "F")]
    fault: Vec<String>,
    /// The fault campaign on triskar2 and rtcan-paper: one table, or JSON with --json
    #[arg(long)]
    campaign: bool,
    /// Run every module's handlers on the modelled CPU
    #[arg(long, value_name = "on|off", default_value = "on")]
    cpu: String,
    /// prioritised (new, default) or single-priority (old) interrupt design
    #[arg(long, value_name = "D")]
    cpu_design: Option<String>,
    /// Cycles per instruction of the CPU model at 72 MHz (default 1.25)
    #[arg(long, value_name = "X")]
    cpi: Option<f64>,
    /// Every handler at its longest (max, default) or mean measured path
    #[arg(long, value_name = "max|mean")]
    cpu_cost: Option<String>,
    /// Run the release images on the emulator (rtcan-emu)
    #[arg(long)]
    emulate: bool,
    /// --emulate: the directory of the release images
    #[arg(long, value_name = "DIR", requires = "emulate")]
    images: Option<PathBuf>,
}

/// Parsed and checked command line.
#[derive(Debug)]
struct Parsed {
    req: Request,
    json: bool,
    out: Option<PathBuf>,
    log_epoch: Option<u64>,
}

fn parse(a: Args) -> Result<Parsed, String> {
    let mut cfg = SimConfig::default();
    let seconds_given = a.seconds.is_some();
    cfg.seconds = a.seconds.unwrap_or(cfg.seconds);
    cfg.seed = a.seed.unwrap_or(cfg.seed);
    cfg.load = a.load.unwrap_or(cfg.load);
    cfg.bit_error_rate = a.ber.unwrap_or(cfg.bit_error_rate);
    let (json, sweep, out, faults, campaign) = (a.json, a.sweep, a.out, a.fault, a.campaign);
    let log_epoch = a.log_epoch;
    let master_dies_at = match a.master_dies_at {
        None => None,
        Some(t) => match t.parse::<f64>() {
            Ok(v) if v.is_finite() && v >= 0.0 => Some(v),
            _ => {
                return Err(format!(
                    "--master-dies-at must be a time in seconds >= 0, not {t}"
                ))
            }
        },
    };
    let robot = match a.robot.as_slice() {
        [] => None,
        [one] => Some(one.clone()),
        [first, second, ..] => {
            return Err(format!(
                "two robot paths, `{}` and `{}`: give one",
                first.display(),
                second.display()
            ))
        }
    };
    let scenario = a.scenario;
    // The CPU model (rtcan_sim::cpu): on by default, prioritised design, CPI 1.25.
    let cpu_on = match a.cpu.as_str() {
        "on" => true,
        "off" => false,
        v => return Err(format!("--cpu must be `on` or `off`, not `{v}`")),
    };
    let design = match a.cpu_design {
        None => rtcan_model::costs::Design::Prioritised,
        Some(v) => rtcan_model::costs::Design::from_name(&v).ok_or(format!(
            "unknown --cpu-design `{v}` (prioritised or single-priority; new / old)"
        ))?,
    };
    let cpi = a.cpi.unwrap_or(1.25);
    let cost = match a.cpu_cost {
        None => rtcan_sim::cpu::Cost::Max,
        Some(v) => rtcan_sim::cpu::Cost::from_name(&v)
            .ok_or(format!("--cpu-cost must be `max` or `mean`, not `{v}`"))?,
    };
    if !(cfg.seconds > 0.0 && cfg.seconds <= 100_000.0) {
        return Err("--seconds must be in (0, 100000]".into());
    }
    if !(cfg.load > 0.0 && cfg.load <= 100.0) {
        return Err("--load must be in (0, 100]".into());
    }
    if !(0.0..1.0).contains(&cfg.bit_error_rate) {
        return Err("--ber must be in [0, 1)".into());
    }
    // The wire log goes straight to DIR/can0.log while running: memory stays bounded by
    // the robot, whatever the length of the run (triskar2 keeps its own, docs/SIM.md).
    cfg.record_wire = false;
    cfg.wire_log = out.as_ref().map(|d| d.join("can0.log"));
    let which = session::resolve(robot, scenario.as_deref())?;
    if master_dies_at.is_some() && !matches!(which, Which::Triskar { .. }) {
        return Err("--master-dies-at is supported by the triskar2 scenario only".into());
    }
    if sweep && which != Which::Paper {
        return Err("--sweep is supported by the rtcan-paper scenario only".into());
    }
    if !faults.is_empty() && !matches!(which, Which::Triskar { .. }) {
        return Err("--fault is supported by the triskar2 scenario only".into());
    }
    for f in &faults {
        rtcan_sim::fault::parse(f, &rtcan_sim::triskar::MODULES)?;
    }
    if campaign {
        if out.is_some() {
            return Err("--campaign writes no files: drop --out".into());
        }
        if !seconds_given {
            cfg.seconds = 10.0;
        }
    }
    cfg.cpu = if cpu_on {
        Some(rtcan_sim::cpu::CpuModel::new(design, cpi)?.with_cost(cost))
    } else {
        None
    };
    Ok(Parsed {
        req: Request {
            which,
            cfg,
            seconds_given,
            sweep,
            master_dies_at,
            faults,
            campaign,
        },
        json,
        out,
        log_epoch,
    })
}

/// `--emulate`: the options that apply to rtcan-emu, in its syntax; any other is an error.
fn emulate_args(a: Args) -> Result<Vec<String>, String> {
    let other = [
        ("--scenario", a.scenario.is_some()),
        ("--load", a.load.is_some()),
        ("--out", a.out.is_some()),
        ("--log-epoch", a.log_epoch.is_some()),
        ("--sweep", a.sweep),
        ("--master-dies-at", a.master_dies_at.is_some()),
        ("--campaign", a.campaign),
        ("--cpu", a.cpu != "on"),
        ("--cpu-design", a.cpu_design.is_some()),
        ("--cpu-cost", a.cpu_cost.is_some()),
    ];
    if let Some((flag, _)) = other.iter().find(|(_, set)| *set) {
        return Err(format!(
            "`{flag}` does not apply with --emulate (options: --seconds, --seed, --cpi, --ber, --fault, --json, --images)"
        ));
    }
    let mut forward = Vec::new();
    for robot in &a.robot {
        // The images are built from the workspace robot: another file cannot run.
        if !crate::emulate::same_file(robot, Path::new("robot.toml")) {
            return Err(format!(
                "--emulate runs the images of the workspace robot (./robot.toml), not `{}`",
                robot.display()
            ));
        }
    }
    if let Some(ber) = a.ber {
        if !(0.0..1.0).contains(&ber) {
            return Err("--ber must be in [0, 1)".into());
        }
    }
    // rtcan-emu applies rtcan-sim's bus faults and resets to the emulated MCUs; the kinds
    // that need a power switch or the module's software to cooperate are refused here,
    // before the emulator starts (docs/EMULATOR.md).
    for f in &a.fault {
        let fault = rtcan_sim::fault::parse(f, &rtcan_sim::triskar::MODULES)?;
        if !emulated_fault(fault.kind) {
            let kind = f
                .split_once(':')
                .and_then(|(_, r)| r.split(['@', '=']).next())
                .unwrap_or(f);
            return Err(format!(
                "--fault `{f}`: `{kind}` cannot be emulated (it needs the module's power switched or its software to cooperate); the emulated faults are stuck, release, partition, rejoin and reset"
            ));
        }
    }
    if a.json {
        forward.push("--json".to_string());
    }
    let pairs = [
        ("--seconds", a.seconds.map(|v| v.to_string())),
        ("--seed", a.seed.map(|v| v.to_string())),
        ("--cpi", a.cpi.map(|v| v.to_string())),
        ("--images", a.images.map(|v| v.display().to_string())),
        ("--ber", a.ber.map(|v| v.to_string())),
    ];
    for (flag, v) in pairs {
        if let Some(v) = v {
            forward.push(flag.to_string());
            forward.push(v);
        }
    }
    for f in a.fault {
        forward.push("--fault".to_string());
        forward.push(f);
    }
    Ok(forward)
}

/// Whether rtcan-emu models fault `kind` (its `bus::Bus::schedule`): faults of the bus
/// and a module reset.
fn emulated_fault(kind: rtcan_sim::fault::FaultKind) -> bool {
    use rtcan_sim::fault::FaultKind as K;
    matches!(
        kind,
        K::Stuck | K::Release | K::Partition | K::Rejoin | K::Reset
    )
}

/// Writes to stdout; a closed pipe (`| head`) ends the output quietly.
fn emit(text: &str) {
    let mut o = std::io::stdout().lock();
    let _ = o.write_all(text.as_bytes()).and_then(|()| o.flush());
}

/// Creates `dir` and proves it writable before the run, so a bad `--out` fails at once.
fn prepare_out(dir: &Path) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("--out {}: {e}", dir.display()))?;
    let probe = dir.join(".rtcan-sim-write-test");
    std::fs::write(&probe, b"").map_err(|e| format!("--out {}: {e}", dir.display()))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Runs `rtcan sim`; returns the exit code.
pub fn run(a: Args) -> i32 {
    if a.emulate {
        return match emulate_args(a) {
            Ok(forward) => crate::emulate::run(&forward),
            Err(e) => crate::usage_error("sim", &e),
        };
    }
    let a = match parse(a) {
        Ok(a) => a,
        Err(e) => return crate::usage_error("sim", &e),
    };
    if let Some(dir) = &a.out {
        if let Err(e) = prepare_out(dir) {
            eprintln!("error: {e}");
            return 2;
        }
    }
    let rep = match session::run(&a.req, &mut progress) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 1;
        }
    };
    let written = print_and_write(&a, &rep).and_then(|()| match (&a.out, a.log_epoch) {
        (Some(dir), Some(e)) => crate::log_epoch::shift_file(&dir.join("can0.log"), e),
        _ => Ok(()),
    });
    match written {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}

fn write(dir: &Path, name: &str, text: &str) -> Result<(), String> {
    let p = dir.join(name);
    std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))
}

/// A plot as `STEM.svg` with its numbers beside it in `STEM.csv`.
fn write_plot(dir: &Path, stem: &str, plot: &Result<Plot, String>) -> Result<(), String> {
    let plot = plot.as_ref().map_err(|e| format!("{stem}.svg: {e}"))?;
    write(dir, &format!("{stem}.svg"), &plot.svg)?;
    write(dir, &format!("{stem}.csv"), &plot.csv)
}

fn progress(done: usize, total: usize) {
    let width = 30;
    let filled = done * width / total.max(1);
    eprint!(
        "\r[{}{}] {done}/{total}",
        "#".repeat(filled),
        " ".repeat(width - filled)
    );
    if done == total {
        eprintln!();
    }
}

fn speed_line(s: &Speed) -> String {
    let mut t = format!(
        "speed: {:.1} s simulated in {:.3} s wall = {:.0}x real time",
        s.sim_s,
        s.wall_s,
        s.sim_s / s.wall_s.max(1e-9)
    );
    if let Some(cpu) = s.cpu_s {
        t.push_str(&format!(
            "; {cpu:.3} s on CPU = {:.0}x real time per core",
            s.sim_s / cpu.max(1e-9)
        ));
    }
    t
}

/// The plots (and `can0.log` when the run kept its whole wire instead of streaming it;
/// without `record_wire` it keeps only the chains' frames, `SimConfig::keep_msg_ids`).
fn outputs(dir: &Path, sc: &Scenario, run: &Run, record_wire: bool) -> Result<(), String> {
    if record_wire && !run.wire.is_empty() {
        write(dir, "can0.log", &candump::log(&run.wire, "can0"))?;
    }
    write_plot(
        dir,
        &format!("hrt-jitter-{}", run.policy),
        &plot::hrt_jitter(run),
    )?;
    write_plot(
        dir,
        &format!("srt-latency-{}", run.policy),
        &plot::srt_latency(run),
    )?;
    if let Some(bus) = sc.bus() {
        write_plot(
            dir,
            "calendar",
            &plot::calendar(
                bus.slots_per_cycle,
                sc.masks().first().copied().unwrap_or(1),
                &plot::calendar_rows(sc),
            ),
        )?;
    }
    Ok(())
}

/// The triskar2 JSON object with a `services` member added (per service: calls,
/// replies, timeouts, late, busy, server_absent, latency_max_ns, latency_mean_ns).
/// `json` (an object's text) with `key: value` appended (`value`: JSON text).
fn with_field(json: &str, key: &str, value: &str) -> String {
    let body = json.trim_end().strip_suffix('}').unwrap_or(json);
    format!("{body},\"{key}\":{value}}}")
}

fn print_and_write(a: &Parsed, rep: &Report) -> Result<(), String> {
    let cfg = &a.req.cfg;
    match rep {
        Report::Paper {
            comparison,
            sweep,
            scenario,
            speed,
            all_wall_s,
        } => {
            if a.json {
                let pts: Vec<_> = sweep.iter().map(report::comparison_value).collect();
                let v = serde_json::json!({
                    "scenario": "rtcan-paper",
                    "seconds": cfg.seconds,
                    "seed": cfg.seed,
                    "comparison": report::comparison_value(comparison),
                    "sweep": pts,
                    "speed_x_real_time": speed.x_real_time(),
                });
                emit(&format!("{v}\n"));
            } else {
                let mut t = format!(
                    "rtcan-paper: {} s simulated, seed {}\n\n",
                    cfg.seconds, cfg.seed
                );
                t.push_str(&report::comparison_text(comparison));
                for r in &comparison.runs {
                    t.push('\n');
                    t.push_str(&report::text(r));
                }
                for c in sweep {
                    t.push('\n');
                    t.push_str(&report::comparison_text(c));
                }
                t.push_str(&format!(
                    "\n{}\n(all four policies: {all_wall_s:.3} s wall)\n",
                    speed_line(speed)
                ));
                emit(&t);
            }
            if let Some(dir) = &a.out {
                let runs = &comparison.runs;
                if let Some(ours) = runs.iter().find(|r| r.policy == PolicyKind::Ours.name()) {
                    outputs(dir, scenario, ours, cfg.record_wire)?;
                }
                for r in runs.iter().filter(|r| r.policy != PolicyKind::Ours.name()) {
                    write_plot(
                        dir,
                        &format!("srt-latency-{}", r.policy),
                        &plot::srt_latency(r),
                    )?;
                }
                if let Some(r) = runs
                    .iter()
                    .find(|r| r.policy == PolicyKind::FixedPriority.name())
                {
                    write_plot(
                        dir,
                        &format!("hrt-jitter-{}", r.policy),
                        &plot::hrt_jitter(r),
                    )?;
                }
                if !sweep.is_empty() {
                    let (miss, lat) = plot::sweep(sweep)?;
                    write_plot(dir, "sweep-miss", &Ok(miss))?;
                    write_plot(dir, "sweep-latency", &Ok(lat))?;
                }
                write(dir, "report.json", &report::comparison_json(comparison))?;
            }
        }
        Report::Robot {
            file,
            scenario,
            run,
            speed,
            notes,
            chains,
        } => {
            for n in notes {
                eprintln!("note: {}", n.replace('\n', "\nnote: "));
            }
            if a.json {
                let v = serde_json::json!({
                    "robot": file,
                    "seconds": cfg.seconds,
                    "seed": cfg.seed,
                    "run": report::run_value(run),
                    "chains": rtcan_sim::chains::json(chains),
                    "speed_x_real_time": speed.x_real_time(),
                });
                emit(&format!("{v}\n"));
            } else {
                emit(&format!(
                    "{file}: {} s simulated, seed {}\n\n{}{}{}\n",
                    cfg.seconds,
                    cfg.seed,
                    report::text(run),
                    rtcan_sim::chains::text(chains),
                    speed_line(speed)
                ));
            }
            if let Some(dir) = &a.out {
                outputs(dir, scenario, run, cfg.record_wire)?;
                write(dir, "report.json", &report::run_json(run))?;
            }
        }
        Report::Triskar {
            file,
            result,
            scenario,
            cfg,
            speed,
            services,
            chains,
        } => {
            let x = speed.x_real_time();
            let json = with_field(
                &with_field(
                    &triskar_report::triskar_json(result, x),
                    "services",
                    &rtcan_sim::triskar::services::json(services),
                ),
                "chains",
                &rtcan_sim::chains::json(chains).to_string(),
            );
            if a.json {
                emit(&format!("{json}\n"));
            } else {
                emit(&format!(
                    "triskar2 on {file}: {} s simulated, seed {}, 6 modules on one bus (generated engines, ModuleHosts and node code)\n\n{}\n{}\n{}{}\n",
                    cfg.seconds,
                    cfg.seed,
                    triskar_report::triskar_text(result),
                    rtcan_sim::triskar::services::text(services),
                    rtcan_sim::chains::text(chains),
                    speed_line(speed)
                ));
            }
            if let Some(dir) = &a.out {
                outputs(dir, scenario, &result.run, cfg.record_wire)?;
                write_plot(dir, "path", &triskar_report::path_plot(result))?;
                write(dir, "report.json", &json)?;
            }
        }
        Report::Campaign { rows, speed } => {
            if a.json {
                emit(&rtcan_sim::campaign::json(rows));
            } else {
                emit(&format!(
                    "fault campaign: {} s simulated per case, seed {}\n\n{}\n{}\n",
                    cfg.seconds,
                    cfg.seed,
                    rtcan_sim::campaign::table(rows),
                    speed_line(speed)
                ));
            }
            // A goal missed fails the command (CI runs it, scripts/test.sh).
            let missed: Vec<String> = rows
                .iter()
                .filter(|r| !r.goals().is_empty())
                .map(|r| format!("{}: {}", r.case.name, r.goals().join("; ")))
                .collect();
            if !missed.is_empty() {
                return Err(format!(
                    "fault campaign: goals missed in {} case(s):\n  {}",
                    missed.len(),
                    missed.join("\n  ")
                ));
            }
        }
    }
    if let (Some(dir), false) = (&a.out, a.json) {
        emit(&format!("wrote {}\n", dir.display()));
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic)]
mod tests {
    use super::*;

    /// `rtcan sim S` through clap and `parse`; `Ok(None)`: help was asked for.
    fn parse_line(s: &str) -> Result<Option<Parsed>, String> {
        let argv = ["rtcan", "sim"].into_iter().chain(s.split_whitespace());
        let m = match crate::command().try_get_matches_from(argv) {
            Err(e) if e.kind() == clap::error::ErrorKind::DisplayHelp => return Ok(None),
            Err(e) => return Err(e.to_string()),
            Ok(m) => m,
        };
        match <crate::Cli as clap::FromArgMatches>::from_arg_matches(&m)
            .map_err(|e| e.to_string())?
            .cmd
        {
            crate::Cmd::Sim(a) => parse(*a).map(Some),
            _ => Err("not sim".into()),
        }
    }

    #[test]
    fn parse_rejects_what_it_cannot_honour() {
        assert!(parse_line("--help").unwrap().is_none());
        assert!(parse_line("robot.toml -h").unwrap().is_none());
        let e = parse_line("a.toml b.toml").unwrap_err();
        assert!(e.contains("two robot paths"), "{e}");
        for v in ["-1", "NaN", "inf"] {
            let e = parse_line(&format!("--master-dies-at {v}")).unwrap_err();
            assert!(e.contains("--master-dies-at"), "{v}: {e}");
        }
        let e = parse_line("--scenario rtcan_paper").unwrap_err();
        assert!(
            e.contains("unknown scenario") && e.contains("rtcan-paper"),
            "{e}"
        );
        let e = parse_line("--scenario rtcan-paper --master-dies-at 1").unwrap_err();
        assert!(e.contains("triskar2 scenario only"), "{e}");
        let e = parse_line("robot.toml --sweep").unwrap_err();
        assert!(e.contains("rtcan-paper scenario only"), "{e}");
        let ok = parse_line("--scenario rtcan-paper --seconds 2")
            .unwrap()
            .unwrap();
        assert_eq!(ok.req.which, Which::Paper);
        assert!(ok.req.seconds_given);
    }

    /// `rtcan sim S` through clap and `emulate_args`: what `rtcan-emu` is given.
    fn emulate_line(s: &str) -> Result<Vec<String>, String> {
        let argv = ["rtcan", "sim"].into_iter().chain(s.split_whitespace());
        let m = crate::command()
            .try_get_matches_from(argv)
            .map_err(|e| e.to_string())?;
        match <crate::Cli as clap::FromArgMatches>::from_arg_matches(&m)
            .map_err(|e| e.to_string())?
            .cmd
        {
            crate::Cmd::Sim(a) => emulate_args(*a),
            _ => Err("not sim".into()),
        }
    }

    #[test]
    fn emulate_forwards_ber_and_faults() {
        let fwd = emulate_line(
            "--emulate --seconds 2 --ber 0.0001 --fault motor1:stuck@1s --fault motor1:release@1100ms --fault psu:reset@1.5s --json",
        )
        .unwrap();
        assert_eq!(
            fwd,
            [
                "--json",
                "--seconds",
                "2",
                "--ber",
                "0.0001",
                "--fault",
                "motor1:stuck@1s",
                "--fault",
                "motor1:release@1100ms",
                "--fault",
                "psu:reset@1.5s"
            ]
        );
        let fwd = emulate_line("--emulate --fault gateway:partition@1s --fault gateway:rejoin@2s")
            .unwrap();
        assert_eq!(
            fwd,
            [
                "--fault",
                "gateway:partition@1s",
                "--fault",
                "gateway:rejoin@2s"
            ]
        );
        assert_eq!(emulate_line("--emulate").unwrap(), Vec::<String>::new());
        // Faults the emulator cannot model are refused before it starts, with the kind.
        for (bad, kind) in [
            ("motor1:dies@1s", "dies"),
            ("motor1:returns@2s", "returns"),
            ("gateway:babble@1s", "babble"),
            ("motor2:stall=5ms@1s", "stall"),
            ("motor2:step=+1ms@1s", "step"),
        ] {
            let e = emulate_line(&format!("--emulate --fault {bad}")).unwrap_err();
            assert!(
                e.contains(&format!("`{bad}`: `{kind}` cannot be emulated"))
                    && e.contains("stuck, release, partition, rejoin and reset"),
                "{bad}: {e}"
            );
        }
        // A malformed fault is rtcan-sim's parse error; a bad rate is refused.
        let e = emulate_line("--emulate --fault motor9:stuck@1s").unwrap_err();
        assert!(e.contains("motor9") && e.contains("accepted"), "{e}");
        for v in ["1", "-0.1", "2"] {
            let e = emulate_line(&format!("--emulate --ber {v}")).unwrap_err();
            assert!(e.contains("--ber must be in [0, 1)"), "{v}: {e}");
        }
        // Still refused: options of the simulator only.
        let e = emulate_line("--emulate --campaign").unwrap_err();
        assert!(
            e.contains("`--campaign` does not apply with --emulate"),
            "{e}"
        );
    }

    #[test]
    fn fault_and_campaign_flags() {
        let ok = parse_line("robot.toml --fault gateway:dies@2s --fault gateway:returns@5000ms")
            .unwrap()
            .unwrap();
        assert_eq!(ok.req.faults, ["gateway:dies@2s", "gateway:returns@5000ms"]);
        for bad in ["motor9:dies@1s", "gateway:explodes@1s", "gateway:dies@1"] {
            let e = parse_line(&format!("--fault {bad}")).unwrap_err();
            assert!(e.contains(bad) && e.contains("accepted"), "{bad}: {e}");
        }
        let e = parse_line("--scenario rtcan-paper --fault gateway:dies@1s").unwrap_err();
        assert!(e.contains("triskar2 scenario only"), "{e}");
        let c = parse_line("--campaign").unwrap().unwrap();
        assert!(c.req.campaign);
        assert_eq!(c.req.cfg.seconds, 10.0);
        let c = parse_line("--campaign --seconds 1000 --json")
            .unwrap()
            .unwrap();
        assert_eq!((c.req.cfg.seconds, c.json), (1000.0, true));
        let e = parse_line("--campaign --out /tmp/x").unwrap_err();
        assert!(e.contains("--out"), "{e}");
        let robot = concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml");
        let short = parse_line(&format!("{robot} --campaign --seconds 2"))
            .unwrap()
            .unwrap();
        let e = session::run(&short.req, &mut |_, _| {}).unwrap_err();
        assert!(e.contains("--seconds >= 7"), "{e}");
        // What the campaign cannot honour is refused by the session, not ignored.
        for extra in [
            "--ber 1e-4",
            "--load 0.5",
            "--master-dies-at 1",
            "--fault motor1:dies@1s",
        ] {
            let a = parse_line(&format!("--campaign {extra}")).unwrap().unwrap();
            let e = session::run(&a.req, &mut |_, _| {}).unwrap_err();
            assert!(e.contains("--campaign"), "{extra}: {e}");
        }
    }
}
