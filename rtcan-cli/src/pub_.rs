//! `rtcan pub TOPIC '{json}'`: publishes one value from the host side, after checking it
//! fits the topic's type exactly, then watches the bus for `--seconds` (default 1) and
//! reports how many messages of the topic carried exactly those bytes.
use rtcan_host::value::{field_list, from_json};
use rtcan_sim::decode::{Decoded, Decoder};

use crate::link_args::{entry, LinkArgs};

/// `rtcan pub`: JSON is an object with every field of TOPIC's type, e.g.
/// `rtcan pub teleop '{"vx":0.3,"vy":0,"wz":0}'`; a value that does not fit its field's
/// type is refused (exit 2). Then watches the bus for --seconds (default 1).
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The topic, by its robot.toml name
    topic: String,
    /// The value, a JSON object with the topic's field names
    #[arg(allow_hyphen_values = true)]
    value: String,
    #[command(flatten)]
    la: LinkArgs,
}

/// Runs `rtcan pub`; returns the exit code.
pub fn run(mut a: Args) -> i32 {
    if a.la.seconds.is_none() {
        a.la.seconds = Some(1.0);
    }
    match publish(&a.la, &a.topic, &a.value) {
        Ok(()) => 0,
        Err((code, e)) => {
            eprintln!("error: {e}");
            code
        }
    }
}

fn publish(la: &LinkArgs, topic: &str, value: &str) -> Result<(), (i32, String)> {
    let (plan, cat) = la.robot().map_err(|e| (1, e))?;
    let ti = cat
        .topics
        .iter()
        .position(|t| t.name == topic)
        .ok_or_else(|| (2, format!("no topic `{topic}` on the bus of {}", plan.file)))?;
    let tp = cat
        .topics
        .get(ti)
        .ok_or((1, "topic vanished".to_string()))?;
    let json: serde_json::Value = serde_json::from_str(value).map_err(|e| {
        (
            2,
            format!(
                "`{value}` is not JSON ({e}); `{topic}` takes {{{}}}",
                field_list(tp)
            ),
        )
    })?;
    let payload = from_json(tp, &json).map_err(|e| (2, format!("{topic}: {e}")))?;
    let mut link = la.open(&plan).map_err(|e| (1, e))?;
    link.publish(topic, &payload).map_err(|e| (1, e))?;
    let end = la.end_ns(link.now_ns());
    let mut dec = Decoder::new(&cat);
    let (mut carried, mut other) = (0u64, 0u64);
    while link.now_ns() < end {
        let Some(batch) = link.recv().map_err(|e| (1, e))? else {
            break;
        };
        for s in batch {
            if let Some(Decoded::Message {
                topic: t,
                payload: p,
                ..
            }) = dec.push(&entry(&s))
            {
                if t == ti {
                    if p == payload {
                        carried += 1;
                    } else {
                        other += 1;
                    }
                }
            }
        }
    }
    println!(
        "published {topic} {json}; in {:.1} s the bus carried it {carried} times ({other} other {topic} messages)",
        la.seconds.unwrap_or(0.0)
    );
    Ok(())
}
