//! `rtcan call SERVICE JSON [--sim robot.toml] [--json] [--fault F]...`: one request/reply
//! call of a robot.toml service over the simulated bus (docs/SERVICES.md §3). The request
//! is checked against the service's request type exactly (exit 2), the simulated robot
//! runs with the service's client calling once at 1 s, and the reply is printed as JSON
//! with its field names (exit 0), or the call timed out or was refused (exit 1).
use rtcan_host::value::{field_list, from_json, to_json};
use rtcan_model::{MsgType, Plan};
use rtcan_sim::decode::{FieldDesc, TopicDesc};
use rtcan_sim::run::SimConfig;
use rtcan_sim::triskar::services::{Outcome, ServiceScript};
use rtcan_sim::triskar::{self, TriskarConfig, MODULES};

/// `rtcan call`: one service call on the simulated robot.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A `[services.NAME]` of the robot, e.g. proximity_read
    service: String,
    /// The request: an object with every field of the request type, e.g. '{"sensor":2}'
    request: String,
    /// The simulated robot
    #[arg(long, value_name = "robot.toml", default_value = "robot.toml")]
    sim: String,
    /// The call as one JSON object (service, call, request, reply or null, outcome
    /// replied|timeout|refused, latency_ns)
    #[arg(long)]
    json: bool,
    /// As `rtcan sim --fault`, e.g. proximity:dies@0.5s (repeatable)
    #[arg(long, value_name = "MODULE:KIND@T")]
    fault: Vec<String>,
}

fn desc(name: &str, ty: &MsgType) -> TopicDesc {
    TopicDesc {
        msg_id: 0,
        name: name.to_string(),
        class: rtcan_core::Class::Srt,
        size: u16::try_from(ty.size).unwrap_or(u16::MAX),
        fields: ty
            .fields
            .iter()
            .map(|f| FieldDesc {
                name: f.name.clone(),
                prim: f.ty.prim,
                len: f.ty.len,
                offset: f.offset,
            })
            .collect(),
        module: None,
    }
}

/// Runs `rtcan call`; returns the exit code.
pub fn run(a: Args) -> i32 {
    match call(&a.sim, &a.service, &a.request, &a.fault, a.json) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            2
        }
    }
}

/// The call; `Err` is bad input (exit 2).
fn call(
    robot: &str,
    name: &str,
    request: &str,
    faults: &[String],
    json: bool,
) -> Result<i32, String> {
    let plan: Plan = rtcan_model::Robot::load(robot).map_err(|d| d.render())?;
    let Some(svc) = plan.service(name) else {
        let known: Vec<&str> = plan.services.iter().map(|s| s.name.as_str()).collect();
        return Err(format!(
            "{robot} has no service `{name}` (services: {})",
            if known.is_empty() {
                "none".to_string()
            } else {
                known.join(", ")
            }
        ));
    };
    let (Some(req_ty), Some(rep_ty)) =
        (plan.types.get(svc.request_ty), plan.types.get(svc.reply_ty))
    else {
        return Err(format!("service `{name}`: types missing from the plan"));
    };
    let req_desc = desc(name, req_ty);
    let value: serde_json::Value =
        serde_json::from_str(request).map_err(|e| format!("the request is not JSON: {e}"))?;
    let bytes = from_json(&req_desc, &value).map_err(|e| {
        format!(
            "{e}\n`{name}` requests have the fields {}",
            field_list(&req_desc)
        )
    })?;
    triskar::check_plan(&plan)
        .map_err(|e| format!("{e}: `rtcan call` runs on the simulated workspace robot only"))?;
    if name != "proximity_read" {
        return Err(format!(
            "the simulated robot's node code serves `proximity_read` only, not `{name}`"
        ));
    }
    let faults = faults
        .iter()
        .map(|f| rtcan_sim::fault::parse(f, &MODULES))
        .collect::<Result<Vec<_>, _>>()?;
    let from_ns = 1_000_000_000;
    let cfg = TriskarConfig {
        sim: SimConfig {
            // The call at 1 s, its timeout, and a few cycles of margin.
            seconds: (from_ns + svc.timeout_ns + 50_000_000) as f64 / 1e9,
            record_wire: false,
            ..SimConfig::default()
        },
        faults,
        ..TriskarConfig::default()
    };
    let script = ServiceScript {
        period_ns: Some(svc.timeout_ns.max(1)),
        burst: 1,
        from_ns,
        lose_replies: Vec::new(),
        request: Some(bytes.clone()),
    };
    let (_, log) = triskar::run_with_services(&plan, &cfg, &script)?;
    let Some(c) = log.calls.first() else {
        return Err("the simulated client made no call".into());
    };
    let reply = c
        .call
        .and_then(|id| log.replies.iter().find(|(k, _)| *k == id))
        .map(|(_, b)| to_json(&desc(name, rep_ty), b));
    let (outcome, latency, code) = match c.outcome {
        Outcome::Replied { global_ns, .. } => ("replied", Some(global_ns - c.global_ns), 0),
        Outcome::TimedOut { .. } => ("timeout", None, 1),
        Outcome::Refused(_) | Outcome::Pending => ("refused", None, 1),
    };
    if json {
        let out = serde_json::json!({
            "service": name,
            "call": c.call,
            "request": to_json(&req_desc, &bytes),
            "reply": reply,
            "outcome": outcome,
            "latency_ns": latency,
            "timeout_ns": svc.timeout_ns,
        });
        println!("{out}");
    } else {
        match (&reply, code) {
            (Some(r), 0) => println!("{r}"),
            _ => eprintln!(
                "error: `{name}`: {} (timeout {} ms)",
                if outcome == "timeout" {
                    "no reply before the timeout"
                } else {
                    "the call could not be made"
                },
                svc.timeout_ns as f64 / 1e6
            ),
        }
    }
    Ok(code)
}
