//! `rtcan param` against the in-process simulated Triskar2 (issue 15).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
mod common;
use common::rtcan;

#[test]
fn list_get_set_with_the_default_sim_robot() {
    let (code, out, err) = rtcan(&["param", "list"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        out,
        "motor1.kp = 0.04 duty/(rad/s)  (f32 in [0, 1], default 0.04, persisted)\n\
         motor1.ki = 1 duty/rad  (f32 in [0, 20], default 1, persisted)\n\
         proximity.stop_distance = 0.25 m  (f32 in [0.05, 1], default 0.25, persisted)\n\
         proximity.log_every = 10 cycles  (u32 in [1, 1000], default 10)\n"
    );
    let (code, out, _) = rtcan(&["param", "get", "motor1.kp", "--sim", "robot.toml"]);
    assert_eq!(code, 0);
    assert!(out.starts_with("motor1.kp = 0.04 "), "{out}");
    let (code, out, _) = rtcan(&["param", "set", "motor1.kp", "0.8"]);
    assert_eq!(code, 0);
    assert!(out.starts_with("motor1.kp = 0.8 "), "{out}");
    let (code, out, _) = rtcan(&["param", "list", "--json"]);
    assert_eq!(code, 0);
    assert!(out.starts_with("[{\"name\":\"motor1.kp\",\"module\":\"motor1\",\"type\":\"f32\",\"value\":0.04,\"default\":0.04,\"min\":0,\"max\":1,\"unit\":\"duty/(rad/s)\",\"persist\":true},"), "{out}");
}

#[test]
fn bad_values_are_refused_with_a_reason_and_bad_usage_exits_2() {
    let (code, out, err) = rtcan(&["param", "set", "motor1.kp", "3"]);
    assert_eq!(code, 1);
    assert_eq!(out, "");
    assert_eq!(
        err,
        "error: motor1.kp: refused by module motor1: value outside the declared range (value 3, range [0, 1]); not applied\n"
    );
    let (code, _, err) = rtcan(&["param", "set", "motor1.kp", "NaN"]);
    assert_eq!(code, 1);
    assert!(err.contains("not a value of the parameter's type"), "{err}");
    let (code, _, err) = rtcan(&["param", "set", "proximity.log_every", "-3"]);
    assert_eq!(code, 2);
    assert!(err.contains("`-3` is not a u32"), "{err}");
    let (code, _, err) = rtcan(&["param", "get", "motor1.kq"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("no parameter `motor1.kq`") && err.contains("motor1.kp"),
        "{err}"
    );
    let (code, _, _) = rtcan(&["param"]);
    assert_eq!(code, 2);
    let (code, _, _) = rtcan(&["param", "list", "--sim"]);
    assert_eq!(code, 2);
    let (code, _, err) = rtcan(&["param", "list", "--sim", "nonexistent.toml"]);
    assert_eq!(code, 2);
    assert!(err.contains("nonexistent.toml"), "{err}");
}

#[test]
fn over_the_bus_an_absent_module_times_out_and_others_answer() {
    // motor1 dies before the host asks: no reply within the timeout, exit 1.
    let (code, out, err) = rtcan(&["param", "get", "motor1.kp", "--fault", "motor1:dies@0.2s"]);
    assert_eq!((code, out.as_str()), (1, ""), "{err}");
    assert_eq!(
        err,
        "error: motor1.kp: no reply from module motor1 within 50 ms (is it powered and on the bus?)\n"
    );
    let (code, _, err) = rtcan(&[
        "param",
        "set",
        "motor1.kp",
        "0.5",
        "--fault",
        "motor1:dies@0.2s",
    ]);
    assert_eq!(code, 1);
    assert!(
        err.ends_with("; the value may or may not have been applied\n"),
        "{err}"
    );
    // proximity still answers while motor1 is dead.
    let (code, out, err) = rtcan(&[
        "param",
        "set",
        "proximity.stop_distance",
        "0.3",
        "--fault",
        "motor1:dies@0.2s",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        out,
        "proximity.stop_distance = 0.3 m  (f32 in [0.05, 1], default 0.25, persisted)\n"
    );
    // A fault naming no module: bad input.
    let (code, _, err) = rtcan(&["param", "list", "--fault", "wheel9:dies@1s"]);
    assert_eq!(code, 2);
    assert!(err.contains("wheel9"), "{err}");
}
