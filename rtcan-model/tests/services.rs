//! `[services]` in robot.toml (issue 15): request/reply services, validated with spans
//! and planned as two SRT topics numbered after the declared ones.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
use rtcan_core::Class;
use rtcan_model::{analyze, Plan};

fn robot() -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robot.toml");
    std::fs::read_to_string(path).unwrap()
}

fn plan(src: &str) -> Plan {
    let a = analyze("robot.toml", src);
    match a.plan {
        Some(p) if a.diagnostics.is_empty() => p,
        _ => panic!("{}", a.diagnostics.render()),
    }
}

/// The workspace robot without its `[services]` tables.
fn without_services() -> String {
    let src = robot();
    let start = src.find("[services.proximity_read]").unwrap();
    let end = start + src[start..].find("\n# ----").unwrap();
    format!("{}{}", &src[..start], &src[end..])
}

#[test]
fn triskar2_service_is_two_srt_topics_after_the_declared_ones() {
    let p = plan(&robot());
    let s = p.service("proximity_read").unwrap();
    let node = |i: usize| p.nodes[i].name.as_str();
    assert_eq!(
        (node(s.server), node(s.client)),
        ("ir_ranger", "ros_bridge")
    );
    assert_eq!(
        (s.timeout_ns, s.deadline_ns, s.in_flight),
        (20_000_000, 5_000_000, 2)
    );
    assert_eq!(s.rate_hz, Some(10.0));
    let req = &p.topics[s.request_topic];
    let rep = &p.topics[s.reply_topic];
    assert_eq!(
        (req.name.as_str(), rep.name.as_str()),
        ("proximity_read_request", "proximity_read_reply")
    );
    for t in [req, rep] {
        assert_eq!(t.class, Class::Srt);
        assert_eq!(t.deadline_ns, Some(5_000_000));
        assert!(t.on_bus);
        assert_eq!(t.fragments, 1);
    }
    // Frame = call number u16 + payload.
    assert_eq!((req.size, rep.size), (3, 5));
    let ty = |i: usize| &p.types[i];
    assert_eq!(ty(s.request_ty).name, "ProximityReadRequest");
    assert_eq!(ty(s.reply_ty).name, "ProximityReadReply");
    let frame: Vec<_> = ty(rep.ty)
        .fields
        .iter()
        .map(|f| (f.name.as_str(), f.ty.rust(), f.offset))
        .collect();
    assert_eq!(
        frame,
        [
            ("call", "u16".to_string(), 0),
            ("sensor", "u8".to_string(), 2),
            ("range_mm", "u16".to_string(), 3)
        ]
    );
    // Request: gateway -> proximity; reply: proximity -> gateway.
    assert_eq!(p.modules[req.module].name, "gateway");
    assert_eq!(p.modules[rep.module].name, "proximity");
    let gw = p.module("gateway").unwrap();
    let px = p.module("proximity").unwrap();
    assert!(gw.tx.contains(&s.request_topic) && gw.rx.contains(&s.reply_topic));
    assert!(px.rx.contains(&s.request_topic) && px.tx.contains(&s.reply_topic));
    // Exactly the IDs after every declared topic: the declared ones end at 0x0149
    // (the local encoder2), so the services' groups start at 0x014A, one block per
    // receiving module (gateway before proximity by name).
    assert_eq!((req.msg_id.0, rep.msg_id.0), (0x014B, 0x014A));
}

#[test]
fn adding_a_service_moves_no_declared_topic_id() {
    let with = plan(&robot());
    let without = plan(&without_services());
    assert_eq!(with.topics.len(), without.topics.len() + 2);
    for t in &without.topics {
        let w = with.topic(&t.name).unwrap();
        assert_eq!(
            (w.msg_id, w.phase_slot),
            (t.msg_id, t.phase_slot),
            "{}",
            t.name
        );
    }
    // The declared topics (not the module-state topics, numbered after them).
    let state = without.module_state.as_ref().unwrap();
    let max_declared = (0..without.topics.len())
        .filter(|&t| !state.contains(t))
        .map(|t| without.topics[t].msg_id.0)
        .max()
        .unwrap();
    assert_eq!(max_declared, 0x0149);
    assert_ne!(with.fingerprint, without.fingerprint);
}

#[test]
fn filters_pass_the_service_frames_to_server_and_client_only() {
    let p = plan(&robot());
    let s = p.service("proximity_read").unwrap();
    let req = p.topics[s.request_topic].msg_id.0;
    let rep = p.topics[s.reply_topic].msg_id.0;
    for m in &p.modules {
        let ids: Vec<u16> = m.rx.iter().map(|i| p.topics[*i].msg_id.0).collect();
        assert_eq!(ids.contains(&req), m.name == "proximity", "{}", m.name);
        assert_eq!(ids.contains(&rep), m.name == "gateway", "{}", m.name);
        // Every received topic is accepted by one of the module's banks.
        for i in &m.rx {
            let id = p.topics[*i].msg_id.0;
            let w = rtcan_model::filters::WireTopic {
                topic: *i,
                msg_id: id,
                fixed_id: None,
            };
            let passes = m
                .banks
                .iter()
                .any(|b| rtcan_model::lock::may_pass(&b.filter, &w));
            assert!(passes, "{}: {:#06x}", m.name, id);
        }
    }
}

fn errors(extra: &str) -> String {
    let src = format!("{}\n{extra}", without_services());
    let a = analyze("robot.toml", &src);
    assert!(
        a.plan.is_none() || !a.diagnostics.is_empty(),
        "accepted: {extra}"
    );
    a.diagnostics.render()
}

const OK: &str = "request = { sensor = \"u8\" }\nreply = { mm = \"u16\" }\nserver = \"ir_ranger\"\nclient = \"ros_bridge\"\ntimeout = \"20ms\"\n";

#[test]
fn a_minimal_service_gets_half_the_timeout_as_deadline_and_two_in_flight() {
    let p = plan(&format!("{}\n[services.read]\n{OK}", without_services()));
    let s = p.service("read").unwrap();
    assert_eq!(
        (s.deadline_ns, s.in_flight, s.rate_hz),
        (10_000_000, 2, None)
    );
    // A `[types]` name works as a payload too.
    let p = plan(&format!(
        "{}\n[services.read]\nrequest = \"Battery\"\nreply = \"Proximity\"\nserver = \"battery_monitor\"\nclient = \"ir_ranger\"\ntimeout = \"20ms\"\nin_flight = 4\n",
        without_services()
    ));
    let s = p.service("read").unwrap();
    assert_eq!(p.types[s.request_ty].name, "Battery");
    assert_eq!(p.topics[s.request_topic].size, 7);
    assert_eq!(p.topics[s.reply_topic].size, 10);
    assert_eq!(p.topics[s.reply_topic].fragments, 2);
    assert_eq!(p.topics[s.request_topic].subscribers[0].queue, 4);
}

#[test]
fn bad_services_are_rustc_style_errors_with_a_hint() {
    let cases: &[(&str, &str)] = &[
        (
            "[services.read]\nrequest = { sensor = \"u8\" }\nreply = { mm = \"u16\" }\nserver = \"nobody\"\nclient = \"ros_bridge\"\ntimeout = \"20ms\"\n",
            "error[unknown-node]: `services.read.server`: no node `nobody`",
        ),
        (
            &format!("[services.read]\n{OK}colour = 1\n"),
            "error[unknown-key]: unknown key `colour` in `services.read`",
        ),
        (
            "[services.read]\nrequest = { sensor = \"u7\" }\nreply = { mm = \"u16\" }\nserver = \"ir_ranger\"\nclient = \"ros_bridge\"\ntimeout = \"20ms\"\n",
            "error[unknown-type]: `services.read.request`: unknown field type `u7` for `sensor`",
        ),
        (
            "[services.read]\nrequest = \"Sonar\"\nreply = { mm = \"u16\" }\nserver = \"ir_ranger\"\nclient = \"ros_bridge\"\ntimeout = \"20ms\"\n",
            "error[unknown-type]: `services.read.request`: no message type `Sonar`",
        ),
        (
            &format!("[services.read]\n{OK}deadline = \"15ms\"\n"),
            "error[bad-value]: `services.read`: timeout 20 ms is shorter than a round trip at the deadline",
        ),
        (
            "[services.read]\nrequest = { sensor = \"u8\" }\nreply = { mm = \"u16\" }\nserver = \"ir_ranger\"\ntimeout = \"20ms\"\n",
            "error[missing-key]: `services.read` has no `client`",
        ),
        (
            &format!("[services.read]\n{OK}in_flight = 9\n"),
            "error[bad-value]: `services.read.in_flight` must be an integer 1..=8",
        ),
        (
            "[services.read]\nrequest = { call = \"u8\" }\nreply = { mm = \"u16\" }\nserver = \"ir_ranger\"\nclient = \"ros_bridge\"\ntimeout = \"20ms\"\n",
            "error[name-collision]: `services.read.request`: field `call` collides",
        ),
        (
            &format!("[types.ReadRequest]\nx = \"u8\"\n[services.read]\n{OK}"),
            "error[duplicate-name]: service `read` needs the message type `ReadRequest`, which is already declared",
        ),
        (
            &format!("[services.Read]\n{OK}"),
            "error[bad-name]: service name `Read` is not a valid name",
        ),
        (
            &format!("[services.read]\n{OK}timeout = \"soon\"\n"),
            "duplicate key",
        ),
        (
            &format!("[services.read]\n{}", OK.replace("\"20ms\"", "\"soon\"")),
            "error[bad-value]: `services.read.timeout`: `soon` is not a duration",
        ),
        (
            &format!("[services.read]\n{}", OK.replace("ros_bridge", "ir_ranger")),
            "error[bad-value]: `services.read`: the client is the server",
        ),
        (
            &format!("[services.read]\n{}", OK.replace("\"u16\" }", "\"[u8; 255]\" }")),
            "error[payload-too-large]: service `read`: `ReadReplyFrame` is 257 bytes",
        ),
        (
            &format!("[services.read]\n{OK}deadline = \"50us\"\n"),
            "error[srt-deadline-too-short]: service `read`: deadline 50 us",
        ),
    ];
    for (extra, want) in cases {
        let e = errors(extra);
        assert!(e.contains(want), "want `{want}` in:\n{e}");
        assert!(e.contains("robot.toml:"), "no location:\n{e}");
        if !want.contains("duplicate") {
            assert!(e.contains("help:"), "no hint:\n{e}");
        }
    }
}

#[test]
fn wrong_value_kinds_are_errors_never_panics() {
    let cases: &[(&str, &str)] = &[
        ("services = 3\n", "error[wrong-type]: `services` must be a table, found an integer"),
        ("[services]\nread = 5\n", "error[wrong-type]: `services.read` must be a table"),
        (
            &format!("[services.read]\n{}", OK.replace("request = { sensor = \"u8\" }", "request = 3")),
            "error[wrong-type]: `services.read.request` must be a type name or a field table, found an integer",
        ),
        (
            &format!("[services.read]\n{}", OK.replace("server = \"ir_ranger\"", "server = 5")),
            "error[wrong-type]: `services.read.server` must be a node name (a string)",
        ),
        (
            &format!("[services.read]\n{}", OK.replace("timeout = \"20ms\"", "timeout = 20")),
            "error[wrong-type]: `services.read.timeout` must be a duration string",
        ),
        (
            &format!("[services.read]\n{OK}in_flight = \"2\"\n"),
            "error[bad-value]: `services.read.in_flight` must be an integer 1..=8",
        ),
        (
            &format!("[services.read]\n{OK}rate = 1\n"),
            "error[wrong-type]: `services.read.rate` must be a frequency string",
        ),
        (
            &format!("[services.read]\n{OK}rate = \"fast\"\n"),
            "error[bad-value]: `services.read.rate`:",
        ),
        (
            &format!("[services.read]\n{}", OK.replace("{ sensor = \"u8\" }", "{ sensor = 1 }")),
            "error[wrong-type]: `services.read.request`: field `sensor` must be a type string",
        ),
        (
            &format!("[services.read]\n{}", OK.replace("{ sensor = \"u8\" }", "{ Sensor = \"u8\" }")),
            "error[bad-name]: `services.read.request`: field name `Sensor` is not a valid name",
        ),
    ];
    for (extra, want) in cases {
        // A top-level key must come before the first table to be top-level.
        let e = if extra.starts_with("services =") {
            analyze("robot.toml", &format!("{extra}{}", without_services()))
                .diagnostics
                .render()
        } else {
            errors(extra)
        };
        assert!(e.contains(want), "want `{want}` in:\n{e}");
        assert!(e.contains("help:"), "no hint:\n{e}");
    }
}
