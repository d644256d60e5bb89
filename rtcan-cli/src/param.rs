//! `rtcan param list | get <node.name> | set <node.name> <value> [--sim robot.toml]
//! [--json] [--fault F]`: parameters over the bus (docs/SERVICES.md §2). With `--sim` (the
//! default, `robot.toml`) the simulated Triskar2 runs with every module's parameter
//! server on its own module (`rtcan_sim::param`: `rtcan_pubsub`'s server behind the
//! module's engine); this command is the host behind the gateway: it sends each request
//! as an NRT frame of the parameter channel and waits for the module's reply with a
//! timeout. The module range-checks: a refused value is never applied.
use rtcan_core::Nanos;
use rtcan_model::params::{load, ParamDecl, ParamTy};
use rtcan_model::read_source;
use rtcan_pubsub::param::{ParamType, Refused, Reply, Request, Value};
use rtcan_sim::param::{specs, ParamBus, ParamJob, ParamOutcome};
use rtcan_sim::run::SimConfig;
use rtcan_sim::triskar::{self, TriskarConfig, MODULES};
use std::path::Path;

/// When the host sends its first request (the robot has synchronised by then).
const START_NS: Nanos = 500_000_000;
/// How long the host waits for each reply.
const TIMEOUT_NS: Nanos = 50_000_000;

fn ty(t: ParamTy) -> ParamType {
    match t {
        ParamTy::F32 => ParamType::F32,
        ParamTy::I32 => ParamType::I32,
        ParamTy::U32 => ParamType::U32,
        ParamTy::Bool => ParamType::Bool,
    }
}

fn value(t: ParamTy, v: f64) -> Value {
    rtcan_sim::param::value(t, v)
}

fn show(v: Value) -> String {
    match v {
        Value::F32(x) => format!("{x}"),
        Value::I32(x) => format!("{x}"),
        Value::U32(x) => format!("{x}"),
        Value::Bool(x) => format!("{x}"),
    }
}

/// Parses a command-line value as the parameter's type; bits on the wire.
fn parse_value(t: ParamTy, s: &str) -> Result<u32, String> {
    let v = match t {
        ParamTy::F32 => s.parse::<f32>().map(Value::F32).map_err(|e| e.to_string()),
        ParamTy::I32 => s.parse::<i32>().map(Value::I32).map_err(|e| e.to_string()),
        ParamTy::U32 => s.parse::<u32>().map(Value::U32).map_err(|e| e.to_string()),
        ParamTy::Bool => s
            .parse::<bool>()
            .map(Value::Bool)
            .map_err(|e| e.to_string()),
    };
    v.map(Value::bits)
        .map_err(|e| format!("`{s}` is not a {} ({e})", t.name()))
}

/// Runs the simulated robot with the host's `requests` (each to the module serving the
/// parameter); the outcomes in order.
fn over_the_bus(
    plan: &rtcan_model::Plan,
    params: &[ParamDecl],
    requests: Vec<(usize, Request)>,
    faults: &[String],
) -> Result<Vec<ParamOutcome>, String> {
    triskar::check_plan(plan)
        .map_err(|e| format!("{e}: `rtcan param` runs on the simulated workspace robot only"))?;
    let faults = faults
        .iter()
        .map(|f| rtcan_sim::fault::parse(f, &MODULES))
        .collect::<Result<Vec<_>, _>>()?;
    let n = requests.len() as Nanos;
    let job = ParamJob {
        specs: specs(params, MODULES.len()),
        requests: requests
            .into_iter()
            .map(|(m, r)| (START_NS, m, r))
            .collect(),
        timeout_ns: TIMEOUT_NS,
    };
    let cfg = TriskarConfig {
        sim: SimConfig {
            // Every request may take its whole timeout; a cycle of margin.
            seconds: (START_NS + n * TIMEOUT_NS + 10_000_000) as f64 / 1e9,
            record_wire: false,
            ..SimConfig::default()
        },
        faults,
        ..TriskarConfig::default()
    };
    let (_, log) = triskar::run_with_params(plan, &cfg, ParamBus::new(&job, MODULES.len()))?;
    Ok(log.results)
}

/// Why a request got no value.
enum Failed {
    Refused(Refused),
    /// No reply within the timeout.
    Silent,
}

fn json_str(s: &str) -> String {
    let mut o = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => o.push_str(&format!("\\u{:04x}", c as u32)),
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

/// `rtcan param`: the host's requests over the simulated robot's bus (--sim).
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    op: Op,
    /// The simulated robot
    #[arg(
        long,
        value_name = "robot.toml",
        default_value = "robot.toml",
        global = true
    )]
    sim: String,
    /// One JSON object per parameter
    #[arg(long, global = true)]
    json: bool,
    /// As `rtcan sim --fault`, e.g. motor1:dies@0.2s (repeatable)
    #[arg(long, value_name = "F", global = true)]
    fault: Vec<String>,
}

#[derive(clap::Subcommand, Debug)]
enum Op {
    /// Every parameter with its value, type, range and default
    List,
    /// One parameter's value
    Get {
        /// The parameter as <node.name>
        name: String,
    },
    /// Set a parameter; exit 1 when the module refuses the value
    Set {
        /// The parameter as <node.name>
        name: String,
        /// The new value, in the parameter's type
        #[arg(allow_hyphen_values = true)]
        value: String,
    },
}

/// Exit code: 0 done, 1 refused by the module or no reply, 2 bad input or usage.
pub fn run(a: Args) -> i32 {
    let (json, robot) = (a.json, a.sim);
    let (plan, params) =
        match read_source(Path::new(&robot), &robot).and_then(|src| load(&robot, &src)) {
            Ok(x) => x,
            Err(d) => {
                eprint!("{}", d.render());
                return 2;
            }
        };
    let find = |name: &str| -> Result<&ParamDecl, String> {
        params.iter().find(|p| p.name == name).ok_or_else(|| {
            let known: Vec<&str> = params.iter().map(|p| p.name.as_str()).collect();
            format!(
                "no parameter `{name}` in {robot} (declared: {})",
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            )
        })
    };
    // The requests to the modules serving `ps`, over the bus; per request its value or
    // why none.
    let ask =
        |ps: &[&ParamDecl], reqs: Vec<Request>| -> Result<Vec<Result<Value, Failed>>, String> {
            let out = over_the_bus(
                &plan,
                &params,
                ps.iter().map(|p| p.module).zip(reqs).collect(),
                &a.fault,
            )?;
            Ok(ps
                .iter()
                .enumerate()
                .map(|(i, p)| match out.get(i).and_then(|o| o.reply) {
                    Some(Reply::Value { bits, .. }) => {
                        Value::from_bits(ty(p.ty), bits).ok_or(Failed::Refused(Refused::BadValue))
                    }
                    Some(Reply::Refused { why, .. }) => Err(Failed::Refused(why)),
                    None => Err(Failed::Silent),
                })
                .collect())
        };
    let module_name = |p: &ParamDecl| plan.modules.get(p.module).map_or("?", |m| m.name.as_str());
    let silent = |p: &ParamDecl| {
        format!(
            "error: {}: no reply from module {} within {} ms (is it powered and on the bus?)",
            p.name,
            module_name(p),
            TIMEOUT_NS / 1_000_000
        )
    };
    let bad_input = |e: String| {
        eprintln!("error: {e}");
        2
    };
    let line = |p: &ParamDecl, v: Value| {
        if json {
            format!(
                "{{\"name\":{},\"module\":{},\"type\":\"{}\",\"value\":{},\"default\":{},\"min\":{},\"max\":{},\"unit\":{},\"persist\":{}}}",
                json_str(&p.name),
                json_str(plan.modules.get(p.module).map_or("", |m| m.name.as_str())),
                p.ty.name(),
                show(v),
                show(value(p.ty, p.default)),
                show(value(p.ty, p.min)),
                show(value(p.ty, p.max)),
                json_str(&p.unit),
                p.persist
            )
        } else {
            let unit = if p.unit.is_empty() {
                String::new()
            } else {
                format!(" {}", p.unit)
            };
            format!(
                "{} = {}{unit}  ({} in [{}, {}], default {}{})",
                p.name,
                show(v),
                p.ty.name(),
                show(value(p.ty, p.min)),
                show(value(p.ty, p.max)),
                show(value(p.ty, p.default)),
                if p.persist { ", persisted" } else { "" }
            )
        }
    };
    match &a.op {
        Op::List => {
            let ps: Vec<&ParamDecl> = params.iter().collect();
            let reqs = ps
                .iter()
                .map(|p| Request::List { index: p.index })
                .collect();
            let got = match ask(&ps, reqs) {
                Ok(g) => g,
                Err(e) => return bad_input(e),
            };
            let mut rows = Vec::new();
            for (p, r) in ps.iter().zip(got) {
                match r {
                    Ok(v) => rows.push(line(p, v)),
                    Err(Failed::Refused(why)) => {
                        eprintln!("error: {}: {}", p.name, why.reason());
                        return 1;
                    }
                    Err(Failed::Silent) => {
                        eprintln!("{}", silent(p));
                        return 1;
                    }
                }
            }
            if json {
                println!("[{}]", rows.join(","));
            } else {
                for r in rows {
                    println!("{r}");
                }
            }
            0
        }
        Op::Get { name } => {
            let p = match find(name) {
                Ok(p) => p,
                Err(e) => return bad_input(e),
            };
            let got = match ask(&[p], vec![Request::Get { index: p.index }]) {
                Ok(g) => g,
                Err(e) => return bad_input(e),
            };
            match got.into_iter().next() {
                Some(Ok(v)) => {
                    println!("{}", line(p, v));
                    0
                }
                Some(Err(Failed::Refused(why))) => {
                    eprintln!("error: {name}: {}", why.reason());
                    1
                }
                Some(Err(Failed::Silent)) | None => {
                    eprintln!("{}", silent(p));
                    1
                }
            }
        }
        Op::Set { name, value: v } => {
            let p = match find(name) {
                Ok(p) => p,
                Err(e) => return bad_input(e),
            };
            let bits = match parse_value(p.ty, v) {
                Ok(b) => b,
                Err(e) => return bad_input(format!("{name}: {e}")),
            };
            let req = Request::Set {
                index: p.index,
                bits,
            };
            let got = match ask(&[p], vec![req]) {
                Ok(g) => g,
                Err(e) => return bad_input(e),
            };
            match got.into_iter().next() {
                Some(Ok(v)) => {
                    println!("{}", line(p, v));
                    0
                }
                Some(Err(Failed::Refused(why))) => {
                    eprintln!(
                        "error: {name}: refused by module {}: {} (value {v}, range [{}, {}]); not applied",
                        module_name(p),
                        why.reason(),
                        show(value(p.ty, p.min)),
                        show(value(p.ty, p.max)),
                    );
                    1
                }
                Some(Err(Failed::Silent)) | None => {
                    eprintln!("{}; the value may or may not have been applied", silent(p));
                    1
                }
            }
        }
    }
}
