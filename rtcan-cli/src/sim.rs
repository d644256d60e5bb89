//! `rtcan sim`: runs a scenario on the simulated bus and reports (docs/SIM.md).
use std::path::{Path, PathBuf};
use std::time::Instant;

use rtcan_core::engine::Policy;
use rtcan_sim::compare::{paper_comparison, paper_sweep, Comparison};
use rtcan_sim::policy::PolicyKind;
use rtcan_sim::run::{run_engine, Run, Scenario, SimConfig};
use rtcan_sim::triskar::{self, report as triskar_report, TriskarConfig};
use rtcan_sim::{candump, paper, report, robot, svg};

const USAGE: &str = "usage: rtcan sim [robot.toml] [--scenario triskar2|rtcan-paper|file.toml] [--seconds N] [--seed S]
                 [--load X] [--ber P] [--json] [--out DIR] [--sweep] [--master-dies-at S]
                 [--cpu on|off] [--cpu-design prioritised|single-priority] [--cpi X] [--cpu-cost max|mean]";

struct Args {
    robot: Option<PathBuf>,
    scenario: Option<String>,
    cfg: SimConfig,
    json: bool,
    out: Option<PathBuf>,
    sweep: bool,
    seconds_given: bool,
    master_dies_at: Option<f64>,
}

fn parse(args: &[String]) -> Result<Args, String> {
    let mut a = Args {
        robot: None,
        scenario: None,
        cfg: SimConfig::default(),
        json: false,
        out: None,
        sweep: false,
        seconds_given: false,
        master_dies_at: None,
    };
    // The CPU model (rtcan_sim::cpu): on by default, prioritised design, CPI 1.25.
    let (mut cpu_on, mut design, mut cpi) = (true, rtcan_model::costs::Design::Prioritised, 1.25);
    let mut cost = rtcan_sim::cpu::Cost::Max;
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let mut value = |name: &str| it.next().cloned().ok_or(format!("{name} needs a value"));
        match arg.as_str() {
            "--scenario" => a.scenario = Some(value("--scenario")?),
            "--seconds" => {
                a.cfg.seconds = value("--seconds")?.parse().map_err(|_| "bad --seconds")?;
                a.seconds_given = true;
            }
            "--master-dies-at" => {
                a.master_dies_at = Some(
                    value("--master-dies-at")?
                        .parse()
                        .map_err(|_| "bad --master-dies-at")?,
                )
            }
            "--seed" => a.cfg.seed = value("--seed")?.parse().map_err(|_| "bad --seed")?,
            "--load" => a.cfg.load = value("--load")?.parse().map_err(|_| "bad --load")?,
            "--ber" => a.cfg.bit_error_rate = value("--ber")?.parse().map_err(|_| "bad --ber")?,
            "--out" => a.out = Some(PathBuf::from(value("--out")?)),
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
            "--json" => a.json = true,
            "--sweep" => a.sweep = true,
            s if s.starts_with("--") => return Err(format!("unknown option `{s}`")),
            s => a.robot = Some(PathBuf::from(s)),
        }
    }
    if !(a.cfg.seconds > 0.0 && a.cfg.seconds <= 100_000.0) {
        return Err("--seconds must be in (0, 100000]".into());
    }
    if !(a.cfg.load > 0.0 && a.cfg.load <= 100.0) {
        return Err("--load must be in (0, 100]".into());
    }
    if !(0.0..1.0).contains(&a.cfg.bit_error_rate) {
        return Err("--ber must be in [0, 1)".into());
    }
    a.cfg.cpu = if cpu_on {
        Some(rtcan_sim::cpu::CpuModel::new(design, cpi)?.with_cost(cost))
    } else {
        None
    };
    Ok(a)
}

/// Runs `rtcan sim`; returns the exit code.
pub fn run(args: &[String]) -> i32 {
    let a = match parse(args) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}\n{USAGE}");
            return 2;
        }
    };
    let default_robot = PathBuf::from("robot.toml");
    let result = match (a.scenario.as_deref(), &a.robot) {
        (Some("rtcan-paper"), _) => run_paper(&a),
        (Some("triskar2"), robot) => {
            run_triskar(&a, robot.as_ref().unwrap_or(&default_robot), true)
        }
        (Some(file), _) => run_user_file(&a, Path::new(file)),
        (None, robot) => run_triskar(&a, robot.as_ref().unwrap_or(&default_robot), false),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}

fn write(dir: &Path, name: &str, text: &str) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
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

fn speed_line(sim_s: f64, wall: f64, cpu: Option<f64>) -> String {
    let mut s = format!(
        "speed: {sim_s:.1} s simulated in {wall:.3} s wall = {:.0}x real time",
        sim_s / wall.max(1e-9)
    );
    if let Some(cpu) = cpu {
        s.push_str(&format!(
            "; {cpu:.3} s on CPU = {:.0}x real time per core",
            sim_s / cpu.max(1e-9)
        ));
    }
    s
}

/// CPU time of this thread (Linux schedstat), so the speed figure does not depend on
/// what else the machine runs.
fn thread_cpu_s() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns / 1e9)
}

fn outputs(dir: &Path, sc: &Scenario, run: &Run) -> Result<(), String> {
    write(dir, "can0.log", &candump::log(&run.wire, "can0"))?;
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

fn run_paper(a: &Args) -> Result<(), String> {
    let t0 = Instant::now();
    let cmp: Comparison = paper_comparison(&a.cfg);
    let wall = t0.elapsed().as_secs_f64();
    let sweep = if a.sweep {
        paper_sweep(&a.cfg, progress)
    } else {
        Vec::new()
    };
    // Speed of one engine run alone (the figure the README quotes).
    let t1 = Instant::now();
    let c1 = thread_cpu_s();
    let sc = paper::scenario(paper::our_laxity(), a.cfg.load);
    let _ = run_engine(
        &sc,
        &SimConfig {
            record_wire: false,
            ..a.cfg.clone()
        },
        PolicyKind::Ours,
        Policy::OURS,
    );
    let one = t1.elapsed().as_secs_f64();
    let cpu = thread_cpu_s().zip(c1).map(|(b, a)| b - a);
    if a.json {
        let pts: Vec<String> = sweep.iter().map(report::comparison_json).collect();
        println!(
            "{{\"scenario\":\"rtcan-paper\",\"seconds\":{},\"seed\":{},\"comparison\":{},\"sweep\":[{}],\"speed_x_real_time\":{:.1}}}",
            a.cfg.seconds,
            a.cfg.seed,
            report::comparison_json(&cmp),
            pts.join(","),
            a.cfg.seconds / cpu.unwrap_or(one).max(1e-9)
        );
    } else {
        println!(
            "rtcan-paper: {} s simulated, seed {}\n",
            a.cfg.seconds, a.cfg.seed
        );
        print!("{}", report::comparison_text(&cmp));
        for r in &cmp.runs {
            println!();
            print!("{}", report::text(r));
        }
        for c in &sweep {
            println!();
            print!("{}", report::comparison_text(c));
        }
        println!();
        println!("{}", speed_line(a.cfg.seconds, one, cpu));
        println!("(all four policies: {wall:.3} s wall)");
    }
    if let Some(dir) = &a.out {
        if let Some(ours) = cmp
            .runs
            .iter()
            .find(|r| r.policy == PolicyKind::Ours.name())
        {
            outputs(dir, &sc, ours)?;
        }
        for r in cmp
            .runs
            .iter()
            .filter(|r| r.policy != PolicyKind::Ours.name())
        {
            write(
                dir,
                &format!("srt-latency-{}.svg", r.policy),
                &svg::srt_latency(r),
            )?;
        }
        if let Some(r) = cmp
            .runs
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
            let (miss, lat) = svg::sweep(&sweep);
            write(dir, "sweep-miss.svg", &miss)?;
            write(dir, "sweep-latency.svg", &lat)?;
        }
        write(dir, "report.json", &report::comparison_json(&cmp))?;
        if !a.json {
            println!("wrote {}", dir.display());
        }
    }
    Ok(())
}

fn run_user_file(a: &Args, file: &Path) -> Result<(), String> {
    let text = std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?;
    let user = robot::parse_user(&text, file.parent().unwrap_or(Path::new(".")))?;
    let plan = rtcan_model::Robot::load(&user.robot).map_err(|d| d.render())?;
    let traffic = robot::expand(&user, &plan)?;
    run_plan(a, &plan, &traffic)
}

fn run_plan(a: &Args, plan: &rtcan_model::Plan, traffic: &[robot::Traffic]) -> Result<(), String> {
    let sc = robot::scenario(plan, traffic)?;
    let t0 = Instant::now();
    let c0 = thread_cpu_s();
    let run = run_engine(&sc, &a.cfg, PolicyKind::Ours, Policy::OURS);
    let wall = t0.elapsed().as_secs_f64();
    let cpu = thread_cpu_s().zip(c0).map(|(b, a)| b - a);
    if a.json {
        println!(
            "{{\"robot\":\"{}\",\"seconds\":{},\"seed\":{},\"run\":{},\"speed_x_real_time\":{:.1}}}",
            plan.file.replace('\\', "\\\\").replace('"', "\\\""),
            a.cfg.seconds,
            a.cfg.seed,
            report::run_json(&run),
            a.cfg.seconds / cpu.unwrap_or(wall).max(1e-9)
        );
    } else {
        println!(
            "{}: {} s simulated, seed {}\n",
            plan.file, a.cfg.seconds, a.cfg.seed
        );
        print!("{}", report::text(&run));
        println!("{}", speed_line(a.cfg.seconds, wall, cpu));
    }
    if let Some(dir) = &a.out {
        outputs(dir, &sc, &run)?;
        write(dir, "report.json", &report::run_json(&run))?;
    }
    Ok(())
}

/// The triskar2 scenario on `path`, which must be the robot the simulator's code was
/// generated from (the workspace robot.toml). Any other robot runs the generic traffic
/// scenario instead, unless triskar2 was asked for explicitly.
fn run_triskar(a: &Args, path: &Path, explicit: bool) -> Result<(), String> {
    let plan = rtcan_model::Robot::load(path).map_err(|d| d.render())?;
    if let Err(why) = triskar::check_plan(&plan) {
        if explicit {
            return Err(format!("triskar2: {why}"));
        }
        eprintln!(
            "note: {why}.\nnote: the triskar2 scenario (plants, node code) runs only the workspace robot; \
             running the generic traffic scenario of {} instead (HRT always fresh, SRT/NRT at their declared rates).",
            plan.file
        );
        return run_plan(a, &plan, &[]);
    }
    let mut cfg = TriskarConfig {
        sim: a.cfg.clone(),
        gateway_dies_at_s: a.master_dies_at,
        ..TriskarConfig::default()
    };
    if !a.seconds_given {
        cfg.sim.seconds = TriskarConfig::default().sim.seconds;
    }
    let t0 = Instant::now();
    let c0 = thread_cpu_s();
    let r = triskar::run(&plan, &cfg)?;
    let wall = t0.elapsed().as_secs_f64();
    let cpu = thread_cpu_s().zip(c0).map(|(b, a)| b - a);
    let speed = cfg.sim.seconds / cpu.unwrap_or(wall).max(1e-9);
    if a.json {
        println!("{}", triskar_report::triskar_json(&r, speed));
    } else {
        println!(
            "triskar2 on {}: {} s simulated, seed {}, 6 modules on one bus (generated engines, ModuleHosts and node code)\n",
            plan.file, cfg.sim.seconds, cfg.sim.seed
        );
        print!("{}", triskar_report::triskar_text(&r));
        println!();
        println!("{}", speed_line(cfg.sim.seconds, wall, cpu));
    }
    if let Some(dir) = &a.out {
        let sc = robot::scenario(&plan, &[])?;
        outputs(dir, &sc, &r.run)?;
        write(dir, "path.svg", &triskar_report::path_svg(&r))?;
        write(dir, "report.json", &triskar_report::triskar_json(&r, speed))?;
        if !a.json {
            println!("wrote {}", dir.display());
        }
    }
    Ok(())
}
