//! `rtcan param list | get <node.name> | set <node.name> <value> [--sim robot.toml] [--json]`:
//! parameters over the parameter protocol (docs/SERVICES.md §2). With `--sim` (the
//! default, `robot.toml`) every module's parameter server runs in this process, on
//! its F103 flash model; requests and replies go through the same 8-byte wire form as on
//! the bus, and the module range-checks (a refused value is never applied).
use rtcan_model::params::{load, ParamDecl, ParamTy};
use rtcan_model::read_source;
use rtcan_pubsub::param::{serve, ParamSpec, ParamType, Refused, Reply, Request, Value};
use std::path::Path;

fn ty(t: ParamTy) -> ParamType {
    match t {
        ParamTy::F32 => ParamType::F32,
        ParamTy::I32 => ParamType::I32,
        ParamTy::U32 => ParamType::U32,
        ParamTy::Bool => ParamType::Bool,
    }
}

fn value(t: ParamTy, v: f64) -> Value {
    match t {
        ParamTy::F32 => Value::F32(v as f32),
        ParamTy::I32 => Value::I32(v as i32),
        ParamTy::U32 => Value::U32(v as u32),
        ParamTy::Bool => Value::Bool(v != 0.0),
    }
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

/// One simulated module's parameter server: the declarations, the live values, the
/// refusals counted (the module's own `rtcan_pubsub::param::serve`).
struct Server {
    specs: Vec<ParamSpec>,
    values: Vec<u32>,
    refused: u32,
}

impl Server {
    fn serve(&mut self, req: &[u8]) -> [u8; 8] {
        // In-process: no flash behind `persist` (the store is tested on its flash model).
        serve(
            &self.specs,
            &mut self.values,
            &mut self.refused,
            req,
            &mut |_, _| true,
        )
        .encode()
    }
}

fn servers(params: &[ParamDecl], modules: usize) -> Vec<Server> {
    let mut out: Vec<Server> = (0..modules)
        .map(|_| Server {
            specs: Vec::new(),
            values: Vec::new(),
            refused: 0,
        })
        .collect();
    for p in params {
        if let Some(s) = out.get_mut(p.module) {
            // The CLI lives as long as the process: names and units are leaked once.
            let name: &'static str = Box::leak(p.name.clone().into_boxed_str());
            let unit: &'static str = Box::leak(p.unit.clone().into_boxed_str());
            let spec = ParamSpec {
                name,
                default: value(p.ty, p.default),
                min: value(p.ty, p.min),
                max: value(p.ty, p.max),
                unit,
                persist: p.persist,
            };
            s.values.push(spec.default.bits());
            s.specs.push(spec);
        }
    }
    out
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

/// `rtcan param`: every module's parameter server runs in this process (--sim).
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

/// Exit code: 0 done, 1 refused by the module, 2 bad input or usage.
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
    let mut srv = servers(&params, plan.modules.len());
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
    // One request to the module serving `p`, through the wire form.
    let mut call = |p: &ParamDecl, req: Request| -> Result<Value, Refused> {
        let bytes = req.encode();
        let reply = srv
            .get_mut(p.module)
            .map(|s| s.serve(&bytes))
            .and_then(|r| Reply::decode(&r));
        match reply {
            Some(Reply::Value { bits, .. }) => {
                Value::from_bits(ty(p.ty), bits).ok_or(Refused::BadValue)
            }
            Some(Reply::Refused { why, .. }) => Err(why),
            None => Err(Refused::BadRequest),
        }
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
            let mut rows = Vec::new();
            for p in &params {
                match call(p, Request::List { index: p.index }) {
                    Ok(v) => rows.push(line(p, v)),
                    Err(why) => {
                        eprintln!("error: {}: {}", p.name, why.reason());
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
        Op::Get { name } => match find(name) {
            Err(e) => {
                eprintln!("error: {e}");
                2
            }
            Ok(p) => match call(p, Request::Get { index: p.index }) {
                Ok(v) => {
                    println!("{}", line(p, v));
                    0
                }
                Err(why) => {
                    eprintln!("error: {name}: {}", why.reason());
                    1
                }
            },
        },
        Op::Set { name, value: v } => {
            let p = match find(name) {
                Ok(p) => p,
                Err(e) => {
                    eprintln!("error: {e}");
                    return 2;
                }
            };
            let bits = match parse_value(p.ty, v) {
                Ok(b) => b,
                Err(e) => {
                    eprintln!("error: {name}: {e}");
                    return 2;
                }
            };
            match call(
                p,
                Request::Set {
                    index: p.index,
                    bits,
                },
            ) {
                Ok(v) => {
                    println!("{}", line(p, v));
                    0
                }
                Err(why) => {
                    eprintln!(
                        "error: {name}: refused by module {}: {} (value {v}, range [{}, {}]); not applied",
                        plan.modules.get(p.module).map_or("?", |m| m.name.as_str()),
                        why.reason(),
                        show(value(p.ty, p.min)),
                        show(value(p.ty, p.max)),
                    );
                    1
                }
            }
        }
    }
}
