//! One entry point for every scenario: `resolve` turns what the user named into a
//! `Which`, `run` runs it and returns a `Report`; the CLI only parses and prints.
use std::path::{Path, PathBuf};
use std::time::Instant;

use rtcan_core::engine::Policy;
use rtcan_model::Plan;

use crate::compare::{paper_comparison, paper_sweep, Comparison};
use crate::policy::PolicyKind;
use crate::run::{run_engine, Run, Scenario, SimConfig};
use crate::triskar::{self, TriskarConfig, TriskarRun};
use crate::{paper, robot};

/// Built-in scenarios by name, with what they run.
pub const BUILT_IN: [(&str, &str); 2] = [
    (
        "rtcan-paper",
        "the RTCAN paper's §4 benchmark (robots/rtcan-paper.toml), four policies side by side",
    ),
    (
        "triskar2",
        "the whole Triskar2 robot (the workspace robot.toml): plants, node code, engines",
    ),
];

/// The built-in scenarios as text, one per line (for error messages and help).
pub fn built_in_list() -> String {
    BUILT_IN
        .iter()
        .map(|(n, what)| format!("  {n:<12} {what}"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// What to simulate.
#[derive(Clone, Debug, PartialEq)]
pub enum Which {
    /// The paper's benchmark, every policy.
    Paper,
    /// The Triskar2 robot on `robot`; when not `explicit` and `robot` is another robot,
    /// its generic traffic scenario runs instead.
    Triskar {
        /// robot.toml path.
        robot: PathBuf,
        /// `--scenario triskar2` was given.
        explicit: bool,
    },
    /// A user scenario file (docs/SIM.md).
    File(PathBuf),
}

/// Resolves the command line's robot path and `--scenario` value.
pub fn resolve(robot: Option<PathBuf>, scenario: Option<&str>) -> Result<Which, String> {
    let default_robot = || PathBuf::from("robot.toml");
    match scenario {
        Some("rtcan-paper") => match robot {
            Some(r) => Err(format!(
                "--scenario rtcan-paper runs robots/rtcan-paper.toml; drop the robot path `{}`",
                r.display()
            )),
            None => Ok(Which::Paper),
        },
        Some("triskar2") => Ok(Which::Triskar {
            robot: robot.unwrap_or_else(default_robot),
            explicit: true,
        }),
        Some(file) if file.ends_with(".toml") || file.contains('/') => match robot {
            Some(r) => Err(format!(
                "the scenario file `{file}` names its robot; drop the robot path `{}`",
                r.display()
            )),
            None => Ok(Which::File(PathBuf::from(file))),
        },
        Some(other) => Err(format!(
            "unknown scenario `{other}`; built-in scenarios:\n{}\nor a scenario file (path ending in .toml, docs/SIM.md)",
            built_in_list()
        )),
        None => Ok(Which::Triskar {
            robot: robot.unwrap_or_else(default_robot),
            explicit: false,
        }),
    }
}

/// A request: what, for how long, with which knobs.
#[derive(Clone, Debug, PartialEq)]
pub struct Request {
    /// The scenario.
    pub which: Which,
    /// Run parameters.
    pub cfg: SimConfig,
    /// `cfg.seconds` was chosen by the user (triskar2 otherwise runs its own 10 s).
    pub seconds_given: bool,
    /// Add the load sweep (rtcan-paper only).
    pub sweep: bool,
    /// The bus master stops at this many seconds (triskar2 only).
    pub master_dies_at: Option<f64>,
    /// Scripted faults, `MODULE:KIND@TIME` (`fault::parse`; triskar2 only).
    pub faults: Vec<String>,
    /// Run the fault campaign (`campaign`) instead: every case for `cfg.seconds`.
    pub campaign: bool,
}

/// Simulated time against the time it took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Speed {
    /// Simulated seconds.
    pub sim_s: f64,
    /// Wall-clock seconds.
    pub wall_s: f64,
    /// CPU seconds of the simulating thread (Linux), when known.
    pub cpu_s: Option<f64>,
}

impl Speed {
    /// Simulated seconds per CPU second (wall when CPU is unknown).
    pub fn x_real_time(&self) -> f64 {
        self.sim_s / self.cpu_s.unwrap_or(self.wall_s).max(1e-9)
    }
}

/// CPU time of this thread (Linux schedstat), so the speed figure does not depend on
/// what else the machine runs.
fn thread_cpu_s() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns / 1e9)
}

fn timed<T>(sim_s: f64, f: impl FnOnce() -> Result<T, String>) -> Result<(T, Speed), String> {
    let t0 = Instant::now();
    let c0 = thread_cpu_s();
    let v = f()?;
    let wall_s = t0.elapsed().as_secs_f64();
    let cpu_s = thread_cpu_s().zip(c0).map(|(b, a)| b - a);
    Ok((
        v,
        Speed {
            sim_s,
            wall_s,
            cpu_s,
        },
    ))
}

/// What a run produced.
#[derive(Debug)]
pub enum Report {
    /// The paper's benchmark.
    Paper {
        /// Every policy at the requested load.
        comparison: Comparison,
        /// The load sweep (empty unless asked for).
        sweep: Vec<Comparison>,
        /// The `ours` scenario (tables, topics) the outputs describe.
        scenario: Scenario,
        /// One `ours` run without the wire log (the figure the README quotes).
        speed: Speed,
        /// All four policies, wall seconds.
        all_wall_s: f64,
    },
    /// A robot's generic traffic scenario or a user scenario file.
    Robot {
        /// The robot file.
        file: String,
        /// Its scenario.
        scenario: Scenario,
        /// The run (policy `ours`).
        run: Box<Run>,
        /// Speed.
        speed: Speed,
        /// Notes for the user (why this scenario ran).
        notes: Vec<String>,
        /// robot.toml's end-to-end chains measured on the run's wire.
        chains: Vec<crate::chains::ChainMeasure>,
    },
    /// The fault campaign (`campaign::cases`), one row per case.
    Campaign {
        /// The rows, in case order.
        rows: Vec<crate::campaign::Row>,
        /// Every case, wall and CPU seconds.
        speed: Speed,
    },
    /// The Triskar2 robot.
    Triskar {
        /// The robot file.
        file: String,
        /// The run.
        result: Box<TriskarRun>,
        /// Its tables and topics (for the outputs).
        scenario: Scenario,
        /// Seconds and seed actually run.
        cfg: Box<SimConfig>,
        /// Speed.
        speed: Speed,
        /// The `proximity_read` service: the gateway called it at its declared rate.
        services: Box<crate::triskar::services::ServiceLog>,
        /// robot.toml's end-to-end chains measured on the run's wire (node code included).
        chains: Vec<crate::chains::ChainMeasure>,
    },
}

fn load(path: &Path) -> Result<Plan, String> {
    rtcan_model::Robot::load(path).map_err(|d| d.render())
}

fn run_plan(
    plan: &Plan,
    traffic: &[robot::Traffic],
    req: &Request,
    notes: Vec<String>,
) -> Result<Report, String> {
    let mut scenario = robot::scenario(plan, traffic)?;
    robot::scale_load(&mut scenario, req.cfg.load);
    let cfg = SimConfig {
        keep_msg_ids: crate::chains::msg_ids(plan),
        ..req.cfg.clone()
    };
    let (run, speed) = timed(req.cfg.seconds, || {
        run_engine(&scenario, &cfg, PolicyKind::Ours, Policy::OURS)
    })?;
    let chains = crate::chains::measure(plan, &run.wire);
    Ok(Report::Robot {
        file: plan.file.clone(),
        scenario,
        run: Box::new(run),
        speed,
        notes,
        chains,
    })
}

/// The fault campaign on the workspace robot at `path` (`Request::campaign`).
fn run_campaign(
    req: &Request,
    path: &Path,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Report, String> {
    if req.sweep
        || req.master_dies_at.is_some()
        || !req.faults.is_empty()
        || req.cfg.load != 1.0
        || req.cfg.bit_error_rate != 0.0
        || req.cfg.wire_log.is_some()
    {
        return Err(
            "--campaign runs the workspace robot with its own faults: it takes only \
             [robot.toml] [--seconds N] [--seed S] [--json] and the --cpu options"
                .into(),
        );
    }
    let plan = load(path)?;
    triskar::check_plan(&plan).map_err(|why| format!("--campaign: {why}"))?;
    let n = crate::campaign::cases().len() as f64;
    let (rows, speed) = timed(req.cfg.seconds * n, || {
        crate::campaign::run(&plan, &req.cfg, progress)
    })?;
    Ok(Report::Campaign { rows, speed })
}

/// Runs `req`; `progress(done, total)` hears about each finished sweep point (or
/// campaign case).
pub fn run(req: &Request, progress: &mut dyn FnMut(usize, usize)) -> Result<Report, String> {
    if req.campaign {
        return match &req.which {
            Which::Triskar { robot, .. } => run_campaign(req, robot, progress),
            _ => Err(
                "--campaign runs the workspace robot (triskar2 and rtcan-paper): drop --scenario"
                    .into(),
            ),
        };
    }
    if let Some(at) = req.master_dies_at {
        if !(at.is_finite() && at >= 0.0) {
            return Err(format!(
                "--master-dies-at must be a time in seconds >= 0, not {at}"
            ));
        }
        if !matches!(req.which, Which::Triskar { .. }) {
            return Err("--master-dies-at is supported by the triskar2 scenario only".into());
        }
    }
    if !req.faults.is_empty() && !matches!(req.which, Which::Triskar { .. }) {
        return Err("--fault is supported by the triskar2 scenario only".into());
    }
    if req.sweep && req.which != Which::Paper {
        return Err("--sweep is supported by the rtcan-paper scenario only".into());
    }
    match &req.which {
        Which::Paper => {
            let t0 = Instant::now();
            let comparison = paper_comparison(&req.cfg)?;
            let all_wall_s = t0.elapsed().as_secs_f64();
            let sweep = if req.sweep {
                paper_sweep(&req.cfg, &mut *progress)?
            } else {
                Vec::new()
            };
            let scenario = paper::scenario(paper::our_laxity(), req.cfg.load)?;
            let quiet = SimConfig {
                record_wire: false,
                wire_log: None,
                ..req.cfg.clone()
            };
            let (_, speed) = timed(req.cfg.seconds, || {
                run_engine(&scenario, &quiet, PolicyKind::Ours, Policy::OURS)
            })?;
            Ok(Report::Paper {
                comparison,
                sweep,
                scenario,
                speed,
                all_wall_s,
            })
        }
        Which::File(file) => {
            let text = std::fs::read_to_string(file).map_err(|e| {
                format!(
                    "{}: {e}\nbuilt-in scenarios:\n{}",
                    file.display(),
                    built_in_list()
                )
            })?;
            let user = robot::parse_user(&text, file.parent().unwrap_or(Path::new(".")))?;
            let plan = load(&user.robot)?;
            let traffic = robot::expand(&user, &plan)?;
            let names: Vec<&str> = plan.modules.iter().map(|m| m.name.as_str()).collect();
            let mut req = req.clone();
            for spec in &user.faults {
                let f = crate::fault::parse(spec, &names)?;
                use crate::fault::FaultKind as K;
                if !matches!(
                    f.kind,
                    K::Stuck | K::Release | K::Partition | K::Rejoin | K::Stall(_)
                ) {
                    return Err(format!(
                        "{}: fault `{spec}`: a scenario file's nodes take the bus-level faults \
                         stuck, release, partition, rejoin and stall=D (module faults run on \
                         triskar2, `--fault`)",
                        file.display()
                    ));
                }
                req.cfg.faults.push(f);
            }
            crate::fault::bus_actions(&req.cfg.faults)
                .map_err(|e| format!("{}: {e}", file.display()))?;
            run_plan(&plan, &traffic, &req, Vec::new())
        }
        Which::Triskar {
            robot: path,
            explicit,
        } => {
            let plan = load(path)?;
            if let Err(why) = triskar::check_plan(&plan) {
                if *explicit {
                    return Err(format!("triskar2: {why}"));
                }
                if req.master_dies_at.is_some() {
                    return Err(format!(
                        "--master-dies-at is supported by the triskar2 scenario only, and {why}"
                    ));
                }
                if !req.faults.is_empty() {
                    return Err(format!(
                        "--fault is supported by the triskar2 scenario only, and {why}"
                    ));
                }
                let note = format!(
                    "{why}.\nthe triskar2 scenario (plants, node code) runs only the workspace robot; \
                     running the generic traffic scenario of {} instead (HRT always fresh, SRT/NRT at their declared rates).",
                    plan.file
                );
                return run_plan(&plan, &[], req, vec![note]);
            }
            if req.cfg.load != 1.0 {
                return Err(
                    "--load is not supported by the triskar2 scenario (its traffic comes from the node code)"
                        .into(),
                );
            }
            let mut cfg = TriskarConfig {
                sim: req.cfg.clone(),
                gateway_dies_at_s: req.master_dies_at,
                faults: req
                    .faults
                    .iter()
                    .map(|f| crate::fault::parse(f, &triskar::MODULES))
                    .collect::<Result<_, _>>()?,
                ..TriskarConfig::default()
            };
            if !req.seconds_given {
                cfg.sim.seconds = TriskarConfig::default().sim.seconds;
            }
            cfg.sim.keep_msg_ids = crate::chains::msg_ids(&plan);
            let script = triskar::services::ServiceScript::from_plan(&plan);
            let ((result, services), speed) = timed(cfg.sim.seconds, || {
                triskar::run_with_services(&plan, &cfg, &script)
            })?;
            let scenario = robot::scenario(&plan, &[])?;
            let chains = crate::chains::measure(&plan, &result.run.wire);
            Ok(Report::Triskar {
                chains,
                file: plan.file.clone(),
                result: Box::new(result),
                scenario,
                cfg: Box::new(cfg.sim),
                speed,
                services: Box::new(services),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn req(which: Which) -> Request {
        Request {
            which,
            cfg: SimConfig {
                seconds: 0.05,
                ..SimConfig::default()
            },
            seconds_given: true,
            sweep: false,
            master_dies_at: None,
            faults: Vec::new(),
            campaign: false,
        }
    }

    #[test]
    fn unknown_scenario_lists_the_built_in_ones() {
        let e = resolve(None, Some("rtcan_paper")).unwrap_err();
        assert!(e.starts_with("unknown scenario `rtcan_paper`"), "{e}");
        assert!(e.contains("rtcan-paper") && e.contains("triskar2"), "{e}");
        assert_eq!(resolve(None, Some("rtcan-paper")), Ok(Which::Paper));
        assert_eq!(
            resolve(None, Some("x/s.toml")),
            Ok(Which::File("x/s.toml".into()))
        );
        assert!(resolve(Some("r.toml".into()), Some("rtcan-paper")).is_err());
        let e = run(&req(Which::File("no/such.toml".into())), &mut |_, _| {}).unwrap_err();
        assert!(e.contains("rtcan-paper") && e.contains("triskar2"), "{e}");
    }

    #[test]
    fn master_dies_at_is_checked_not_ignored() {
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            let mut r = req(Which::Triskar {
                robot: "robot.toml".into(),
                explicit: true,
            });
            r.master_dies_at = Some(bad);
            let e = run(&r, &mut |_, _| {}).unwrap_err();
            assert!(e.contains(">= 0"), "{bad}: {e}");
        }
        let mut r = req(Which::Paper);
        r.master_dies_at = Some(1.0);
        let e = run(&r, &mut |_, _| {}).unwrap_err();
        assert!(e.contains("triskar2 scenario only"), "{e}");
        let mut r = req(Which::Triskar {
            robot: concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/hrt200.toml").into(),
            explicit: false,
        });
        r.master_dies_at = Some(1.0);
        let e = run(&r, &mut |_, _| {}).unwrap_err();
        assert!(e.contains("triskar2 scenario only"), "{e}");
    }
}

#[cfg(test)]
mod fault_file_tests {
    use super::*;

    fn scenario(dir: &Path, faults: &str) -> PathBuf {
        let robot = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/rtcan-paper.toml");
        let p = dir.join(format!("s{}.toml", faults.len()));
        std::fs::write(
            &p,
            format!("robot = \"{robot}\"\nfaults = [{faults}]\n[traffic]\n\"s_*\" = {{ period = \"20ms\" }}\n"),
        )
        .unwrap();
        p
    }

    fn hrt_misses(faults: &str, dir: &Path) -> Result<u64, String> {
        let r = Request {
            which: Which::File(scenario(dir, faults)),
            cfg: SimConfig {
                seconds: 1.0,
                record_wire: false,
                ..SimConfig::default()
            },
            seconds_given: true,
            sweep: false,
            master_dies_at: None,
            faults: Vec::new(),
            campaign: false,
        };
        match run(&r, &mut |_, _| {})? {
            Report::Robot { run, .. } => Ok(run.figures.hrt.iter().map(|h| h.misses).sum()),
            _ => Err("not a robot report".into()),
        }
    }

    /// A scenario file scripts the bus-level faults; module faults are refused there.
    #[test]
    fn a_scenario_file_scripts_bus_faults() {
        let dir = std::env::temp_dir().join(format!("rtcan-fault-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert_eq!(hrt_misses("", &dir), Ok(0));
        // The bus held dominant for 200 ms: every HRT occurrence in it is missed.
        let stuck = hrt_misses("\"node3:stuck@300ms\", \"node3:release@500ms\"", &dir).unwrap();
        assert!(stuck > 100, "{stuck}");
        let e = hrt_misses("\"node3:dies@300ms\"", &dir).unwrap_err();
        assert!(e.contains("bus-level faults"), "{e}");
        let e = hrt_misses("\"node9:stuck@300ms\"", &dir).unwrap_err();
        assert!(e.contains("no module `node9`"), "{e}");
        let e = hrt_misses("\"node3:release@300ms\"", &dir).unwrap_err();
        assert!(e.contains("not stuck"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[cfg(test)]
mod load_tests {
    use super::*;

    fn events(report: &Report) -> u64 {
        match report {
            Report::Robot { run, .. } => run.figures.srt.iter().map(|c| c.count).sum(),
            _ => 0,
        }
    }

    /// `--load` was silently ignored outside rtcan-paper: it scales a user scenario's
    /// (and a robot's declared) rates, and triskar2, whose traffic is node code, refuses it.
    #[test]
    fn load_scales_user_scenarios_and_triskar2_refuses_it() {
        let file = PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/scenarios/rtcan-paper.toml"
        ));
        let mut r = Request {
            which: Which::File(file),
            cfg: SimConfig {
                seconds: 1.0,
                record_wire: false,
                ..SimConfig::default()
            },
            seconds_given: true,
            sweep: false,
            master_dies_at: None,
            faults: Vec::new(),
            campaign: false,
        };
        let one = events(&run(&r, &mut |_, _| {}).unwrap());
        r.cfg.load = 0.5;
        let half = events(&run(&r, &mut |_, _| {}).unwrap());
        assert!(one > 1000, "{one}");
        let ratio = half as f64 / one as f64;
        assert!((0.4..0.6).contains(&ratio), "{half} / {one}");
        r.which = Which::Triskar {
            robot: concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml").into(),
            explicit: true,
        };
        let e = run(&r, &mut |_, _| {}).unwrap_err();
        assert!(e.contains("--load is not supported"), "{e}");
    }
}
