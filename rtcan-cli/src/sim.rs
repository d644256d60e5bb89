//! `rtcan sim`: parses the command line, runs `rtcan_sim::session::run` and prints its
//! report (docs/SIM.md).
use std::io::Write as _;
use std::path::{Path, PathBuf};

use rtcan_sim::policy::PolicyKind;
use rtcan_sim::run::{Run, Scenario, SimConfig};
use rtcan_sim::session::{self, built_in_list, Report, Request, Speed, Which};
use rtcan_sim::triskar::report as triskar_report;
use rtcan_sim::{candump, report, svg};

const SYNOPSIS: &str =
    "usage: rtcan sim [robot.toml] [--scenario rtcan-paper|triskar2|file.toml] [--seconds N]
                 [--seed S] [--load X] [--ber P] [--json] [--out DIR] [--sweep]
                 [--master-dies-at S] [--fault MODULE:KIND[=D]@T]...
                 [--cpu on|off] [--cpu-design prioritised|single-priority] [--cpi X]
                 [--cpu-cost max|mean]
       rtcan sim [robot.toml] --emulate [--seconds N] [--seed N] [--cpi X] [--json] [--images DIR]
       rtcan sim [robot.toml] --campaign [--seconds N] [--seed S] [--json]
       rtcan sim --help";

const OPTIONS: &str =
    "  robot.toml          the robot (default ./robot.toml): the workspace robot runs triskar2,
                      any other robot its generic traffic scenario
  --scenario NAME     a built-in scenario or a scenario file (docs/SIM.md)
  --seconds N         simulated time, 0 < N <= 100000 (triskar2 default 10, others 1)
  --seed S            seed of every random stream
  --load X            SRT event-rate scale, 0 < X <= 100
  --ber P             bit error rate, 0 <= P < 1
  --json              the report as JSON on stdout
  --out DIR           write candump log, SVG plots and report.json to DIR
  --sweep             rtcan-paper: add the load sweep 0.5..1.2
  --master-dies-at S  triskar2: the bus master stops at S seconds (S >= 0)
  --fault F           triskar2, repeatable: MODULE:KIND@T, KIND one of dies, returns,
                      reset, babble, stuck, release, partition, rejoin, stall=D, step=+D
                      or step=-D (T, D with unit s, ms or us), e.g. --fault gateway:dies@2s
                      --fault gateway:returns@5s (docs/SIM.md, Faults)
  --campaign          the fault campaign on triskar2 and rtcan-paper, N s per case
                      (default 10): one table, or JSON with --json
  --cpu on|off        run every module's handlers on the modelled CPU (default on)
  --cpu-design D      prioritised (new, default) or single-priority (old) interrupt design
  --cpi X             cycles per instruction of the CPU model at 72 MHz (default 1.25)
  --cpu-cost max|mean every handler at its longest (default) or mean measured path";

/// Parsed command line.
#[derive(Debug)]
struct Args {
    req: Request,
    json: bool,
    out: Option<PathBuf>,
}

/// `Ok(None)`: help was asked for.
fn parse(args: &[String]) -> Result<Option<Args>, String> {
    let mut robot: Option<PathBuf> = None;
    let mut scenario: Option<String> = None;
    let mut cfg = SimConfig::default();
    let (mut json, mut sweep, mut seconds_given) = (false, false, false);
    let mut out = None;
    let mut master_dies_at = None;
    let mut faults = Vec::new();
    let mut campaign = false;
    // The CPU model (rtcan_sim::cpu): on by default, prioritised design, CPI 1.25.
    let (mut cpu_on, mut design, mut cpi) = (true, rtcan_model::costs::Design::Prioritised, 1.25);
    let mut cost = rtcan_sim::cpu::Cost::Max;
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let mut value = |name: &str| it.next().cloned().ok_or(format!("{name} needs a value"));
        match arg.as_str() {
            "-h" | "--help" => return Ok(None),
            "--scenario" => scenario = Some(value("--scenario")?),
            "--seconds" => {
                cfg.seconds = value("--seconds")?.parse().map_err(|_| "bad --seconds")?;
                seconds_given = true;
            }
            "--master-dies-at" => {
                let v: f64 = value("--master-dies-at")?
                    .parse()
                    .map_err(|_| "bad --master-dies-at")?;
                if !(v.is_finite() && v >= 0.0) {
                    return Err(format!(
                        "--master-dies-at must be a time in seconds >= 0, not {v}"
                    ));
                }
                master_dies_at = Some(v);
            }
            "--fault" => faults.push(value("--fault")?),
            "--campaign" => campaign = true,
            "--seed" => cfg.seed = value("--seed")?.parse().map_err(|_| "bad --seed")?,
            "--load" => cfg.load = value("--load")?.parse().map_err(|_| "bad --load")?,
            "--ber" => cfg.bit_error_rate = value("--ber")?.parse().map_err(|_| "bad --ber")?,
            "--out" => out = Some(PathBuf::from(value("--out")?)),
            "--cpu" => {
                cpu_on = match value("--cpu")?.as_str() {
                    "on" => true,
                    "off" => false,
                    v => return Err(format!("--cpu must be `on` or `off`, not `{v}`")),
                }
            }
            "--cpu-design" => {
                let v = value("--cpu-design")?;
                design = rtcan_model::costs::Design::from_name(&v).ok_or(format!(
                    "unknown --cpu-design `{v}` (prioritised or single-priority; new / old)"
                ))?;
            }
            "--cpi" => cpi = value("--cpi")?.parse().map_err(|_| "bad --cpi")?,
            "--cpu-cost" => {
                let v = value("--cpu-cost")?;
                cost = rtcan_sim::cpu::Cost::from_name(&v)
                    .ok_or(format!("--cpu-cost must be `max` or `mean`, not `{v}`"))?;
            }
            "--json" => json = true,
            "--sweep" => sweep = true,
            s if s.starts_with('-') && s.len() > 1 => return Err(format!("unknown option `{s}`")),
            s => {
                if let Some(first) = &robot {
                    return Err(format!(
                        "two robot paths, `{}` and `{s}`: give one",
                        first.display()
                    ));
                }
                robot = Some(PathBuf::from(s));
            }
        }
    }
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
    Ok(Some(Args {
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
    }))
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
pub fn run(args: &[String]) -> i32 {
    if crate::emulate::wanted(args) {
        return crate::emulate::run(args);
    }
    let a = match parse(args) {
        Ok(Some(a)) => a,
        Ok(None) => {
            emit(&format!(
                "{SYNOPSIS}\n\n{OPTIONS}\n\nbuilt-in scenarios:\n{}\n",
                built_in_list()
            ));
            return 0;
        }
        Err(e) => {
            eprintln!("error: {e}\n{SYNOPSIS}");
            return 2;
        }
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
    match print_and_write(&a, &rep) {
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

/// The plots (and `can0.log` when the run kept its wire instead of streaming it).
fn outputs(dir: &Path, sc: &Scenario, run: &Run) -> Result<(), String> {
    if !run.wire.is_empty() {
        write(dir, "can0.log", &candump::log(&run.wire, "can0"))?;
    }
    write(
        dir,
        &format!("hrt-jitter-{}.svg", run.policy),
        &svg::hrt_jitter(run),
    )?;
    write(
        dir,
        &format!("srt-latency-{}.svg", run.policy),
        &svg::srt_latency(run),
    )?;
    if let Some(bus) = sc.bus() {
        let rows: Vec<(String, Vec<(u32, String)>)> = sc
            .tables
            .iter()
            .enumerate()
            .map(|(n, t)| {
                let cells = t
                    .calendar
                    .iter()
                    .filter(|e| e.slot < u32::from(bus.slots_per_cycle))
                    .map(|e| {
                        let label = sc
                            .topics
                            .iter()
                            .find(|i| i.node == n && i.tx == e.tx)
                            .map_or("?", |i| i.label.as_str());
                        (e.slot, label.chars().take(4).collect())
                    })
                    .collect();
                (format!("node {n}"), cells)
            })
            .collect();
        write(
            dir,
            "calendar.svg",
            &svg::calendar(
                bus.slots_per_cycle,
                sc.masks().first().copied().unwrap_or(1),
                &rows,
            ),
        )?;
    }
    Ok(())
}

/// The triskar2 JSON object with a `services` member added (per service: calls,
/// replies, timeouts, late, busy, server_absent, latency_max_ns, latency_mean_ns).
fn with_services(json: &str, log: &rtcan_sim::triskar::services::ServiceLog) -> String {
    let body = json.trim_end().strip_suffix('}').unwrap_or(json);
    format!(
        "{body},\"services\":{}}}",
        rtcan_sim::triskar::services::json(log)
    )
}

fn json_str(s: &str) -> String {
    s.replace('\\', "\\\\").replace('"', "\\\"")
}

fn print_and_write(a: &Args, rep: &Report) -> Result<(), String> {
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
                let pts: Vec<String> = sweep.iter().map(report::comparison_json).collect();
                emit(&format!(
                    "{{\"scenario\":\"rtcan-paper\",\"seconds\":{},\"seed\":{},\"comparison\":{},\"sweep\":[{}],\"speed_x_real_time\":{:.1}}}\n",
                    cfg.seconds,
                    cfg.seed,
                    report::comparison_json(comparison),
                    pts.join(","),
                    speed.x_real_time()
                ));
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
                    outputs(dir, scenario, ours)?;
                }
                for r in runs.iter().filter(|r| r.policy != PolicyKind::Ours.name()) {
                    write(
                        dir,
                        &format!("srt-latency-{}.svg", r.policy),
                        &svg::srt_latency(r),
                    )?;
                }
                if let Some(r) = runs
                    .iter()
                    .find(|r| r.policy == PolicyKind::FixedPriority.name())
                {
                    write(
                        dir,
                        &format!("hrt-jitter-{}.svg", r.policy),
                        &svg::hrt_jitter(r),
                    )?;
                }
                if !sweep.is_empty() {
                    let (miss, lat) = svg::sweep(sweep);
                    write(dir, "sweep-miss.svg", &miss)?;
                    write(dir, "sweep-latency.svg", &lat)?;
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
        } => {
            for n in notes {
                eprintln!("note: {}", n.replace('\n', "\nnote: "));
            }
            if a.json {
                emit(&format!(
                    "{{\"robot\":\"{}\",\"seconds\":{},\"seed\":{},\"run\":{},\"speed_x_real_time\":{:.1}}}\n",
                    json_str(file),
                    cfg.seconds,
                    cfg.seed,
                    report::run_json(run),
                    speed.x_real_time()
                ));
            } else {
                emit(&format!(
                    "{file}: {} s simulated, seed {}\n\n{}{}\n",
                    cfg.seconds,
                    cfg.seed,
                    report::text(run),
                    speed_line(speed)
                ));
            }
            if let Some(dir) = &a.out {
                outputs(dir, scenario, run)?;
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
        } => {
            let x = speed.x_real_time();
            let json = with_services(&triskar_report::triskar_json(result, x), services);
            if a.json {
                emit(&format!("{json}\n"));
            } else {
                emit(&format!(
                    "triskar2 on {file}: {} s simulated, seed {}, 6 modules on one bus (generated engines, ModuleHosts and node code)\n\n{}\n{}\n{}\n",
                    cfg.seconds,
                    cfg.seed,
                    triskar_report::triskar_text(result),
                    rtcan_sim::triskar::services::text(services),
                    speed_line(speed)
                ));
            }
            if let Some(dir) = &a.out {
                outputs(dir, scenario, &result.run)?;
                write(dir, "path.svg", &triskar_report::path_svg(result))?;
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

    fn args(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn parse_rejects_what_it_cannot_honour() {
        assert!(parse(&args("--help")).unwrap().is_none());
        assert!(parse(&args("robot.toml -h")).unwrap().is_none());
        let e = parse(&args("a.toml b.toml")).unwrap_err();
        assert!(e.contains("two robot paths"), "{e}");
        for v in ["-1", "NaN", "inf"] {
            let e = parse(&args(&format!("--master-dies-at {v}"))).unwrap_err();
            assert!(e.contains("--master-dies-at"), "{v}: {e}");
        }
        let e = parse(&args("--scenario rtcan_paper")).unwrap_err();
        assert!(
            e.contains("unknown scenario") && e.contains("rtcan-paper"),
            "{e}"
        );
        let e = parse(&args("--scenario rtcan-paper --master-dies-at 1")).unwrap_err();
        assert!(e.contains("triskar2 scenario only"), "{e}");
        let e = parse(&args("robot.toml --sweep")).unwrap_err();
        assert!(e.contains("rtcan-paper scenario only"), "{e}");
        let ok = parse(&args("--scenario rtcan-paper --seconds 2"))
            .unwrap()
            .unwrap();
        assert_eq!(ok.req.which, Which::Paper);
        assert!(ok.req.seconds_given);
    }

    #[test]
    fn fault_and_campaign_flags() {
        let ok = parse(&args(
            "robot.toml --fault gateway:dies@2s --fault gateway:returns@5000ms",
        ))
        .unwrap()
        .unwrap();
        assert_eq!(ok.req.faults, ["gateway:dies@2s", "gateway:returns@5000ms"]);
        for bad in ["motor9:dies@1s", "gateway:explodes@1s", "gateway:dies@1"] {
            let e = parse(&args(&format!("--fault {bad}"))).unwrap_err();
            assert!(e.contains(bad) && e.contains("accepted"), "{bad}: {e}");
        }
        let e = parse(&args("--scenario rtcan-paper --fault gateway:dies@1s")).unwrap_err();
        assert!(e.contains("triskar2 scenario only"), "{e}");
        let c = parse(&args("--campaign")).unwrap().unwrap();
        assert!(c.req.campaign);
        assert_eq!(c.req.cfg.seconds, 10.0);
        let c = parse(&args("--campaign --seconds 1000 --json"))
            .unwrap()
            .unwrap();
        assert_eq!((c.req.cfg.seconds, c.json), (1000.0, true));
        let e = parse(&args("--campaign --out /tmp/x")).unwrap_err();
        assert!(e.contains("--out"), "{e}");
        let robot = concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml");
        let short = parse(&args(&format!("{robot} --campaign --seconds 2")))
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
            let a = parse(&args(&format!("--campaign {extra}")))
                .unwrap()
                .unwrap();
            let e = session::run(&a.req, &mut |_, _| {}).unwrap_err();
            assert!(e.contains("--campaign"), "{extra}: {e}");
        }
    }
}
