//! `rtcan call` (issue 15): one request/reply call of a robot.toml service on the
//! simulated Triskar2, over the simulated bus.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
mod common;
use common::rtcan;

#[test]
fn a_call_prints_the_reply_with_field_names() {
    let (code, out, err) = rtcan(&["call", "proximity_read", r#"{"sensor":2}"#]);
    assert_eq!(code, 0, "{err}");
    // Ranger 2 of the simulated robot at 1 s (seed 1): nothing within its 0.8 m range.
    assert_eq!(out, "{\"sensor\":2,\"range_mm\":800}\n");
    // A sensor the module does not have: answered with 0xFFFF, not refused.
    let (code, out, err) = rtcan(&[
        "call",
        "proximity_read",
        r#"{"sensor":4}"#,
        "--sim",
        "robot.toml",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["service"], "proximity_read");
    assert_eq!(v["call"], 0);
    assert_eq!(v["request"], serde_json::json!({"sensor": 4}));
    assert_eq!(
        v["reply"],
        serde_json::json!({"sensor": 4, "range_mm": 65535})
    );
    assert_eq!(v["outcome"], "replied");
    assert_eq!(v["timeout_ns"], 20_000_000);
    // Request and reply: two SRT frames, each within the 5 ms deadline.
    let lat = v["latency_ns"].as_u64().unwrap();
    assert!(lat > 200_000 && lat <= 10_000_000, "{lat}");
}

#[test]
fn a_dead_server_times_out_with_exit_1() {
    let (code, out, err) = rtcan(&[
        "call",
        "proximity_read",
        r#"{"sensor":0}"#,
        "--fault",
        "proximity:dies@0.5s",
        "--json",
    ]);
    assert_eq!(code, 1, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["outcome"], "timeout");
    assert!(v["reply"].is_null() && v["latency_ns"].is_null(), "{v}");
    let (code, out, err) = rtcan(&[
        "call",
        "proximity_read",
        r#"{"sensor":0}"#,
        "--fault",
        "proximity:dies@0.5s",
    ]);
    assert_eq!((code, out.as_str()), (1, ""));
    assert!(
        err.contains("no reply before the timeout (timeout 20 ms)"),
        "{err}"
    );
}

#[test]
fn bad_input_exits_2_with_the_reason() {
    let cases: &[(&[&str], &str)] = &[
        (
            &["call", "proximity_read", r#"{"sensor":300}"#],
            "300 does not fit u8",
        ),
        (&["call", "proximity_read", r#"{"sensor":1,"x":2}"#], "x"),
        (&["call", "proximity_read", "{}"], "sensor"),
        (
            &["call", "proximity_read", "sensor=1"],
            "the request is not JSON",
        ),
        (
            &["call", "sonar", "{}"],
            "has no service `sonar` (services: proximity_read)",
        ),
        (
            &[
                "call",
                "scan",
                r#"{"sensor":1,"samples":4}"#,
                "--sim",
                "robots/services.toml",
            ],
            "runs on the simulated workspace robot only",
        ),
        (
            &["call", "proximity_read"],
            "required arguments were not provided",
        ),
        (
            &["call", "proximity_read", "{}", "--bogus"],
            "unexpected argument '--bogus'",
        ),
        (
            &[
                "call",
                "proximity_read",
                r#"{"sensor":1}"#,
                "--fault",
                "proximity:melts@1s",
            ],
            "melts",
        ),
    ];
    for (args, want) in cases {
        let (code, out, err) = rtcan(args);
        assert_eq!(code, 2, "{args:?}: {out}{err}");
        assert!(err.contains(want), "{args:?}: want `{want}` in {err}");
        assert!(out.is_empty(), "{args:?}: {out}");
    }
}
