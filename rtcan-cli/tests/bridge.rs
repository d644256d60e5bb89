#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! `rtcan bridge --sim robot.toml` in one process, a Zenoh peer in this one (issue 13):
//! velocity and odometry arrive as JSON objects, a teleop put drives the simulated
//! robot, puts on other topics and values that do not fit are refused and counted.
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use zenoh::Wait;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

#[test]
fn a_zenoh_peer_in_another_process_sees_and_drives_the_simulated_robot() {
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let mut bridge = Command::new(env!("CARGO_BIN_EXE_rtcan"))
        .args(["bridge", "--sim", "robot.toml", "--listen", &endpoint])
        .args(["--seconds", "60", "--speed", "2"])
        .current_dir(root())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(bridge.stdout.take().unwrap());
    let mut ready = String::new();
    out.read_line(&mut ready).unwrap();
    assert!(
        // 11 declared and service topics, and the 8 module-state topics of the supervised
        // Triskar2 (six `health_<m>`, two `module_state_<m>`).
        ready.starts_with("bridge ready: 19 topics on rtcan/triskar2/*")
            && ready.contains("writable: teleop"),
        "{ready}"
    );

    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"peer\"").unwrap();
    c.insert_json5("scouting/multicast/enabled", "false")
        .unwrap();
    c.insert_json5("connect/endpoints", &format!("[\"{endpoint}\"]"))
        .unwrap();
    let session = zenoh::open(c).wait().unwrap();
    let sub = session
        .declare_subscriber("rtcan/triskar2/**")
        .wait()
        .unwrap();
    let teleop = session
        .declare_publisher("rtcan/triskar2/teleop")
        .wait()
        .unwrap();

    let (mut velocity_vx, mut odometry_x, mut odometry_n) = (0.0f64, 0.0f64, 0u32);
    let t0 = Instant::now();
    let mut last_put = Instant::now() - Duration::from_secs(1);
    let mut refused_sent = false;
    // Until the robot has moved by its own odometry (the limit only guards against a hang).
    while odometry_x < 0.05 && t0.elapsed() < Duration::from_secs(50) {
        // Repeat the command until it shows up on the bus (the first put may precede
        // the bridge's view of this peer's publisher).
        if velocity_vx == 0.0 && last_put.elapsed() > Duration::from_millis(300) {
            teleop.put(r#"{"vx":0.3,"vy":0,"wz":0}"#).wait().unwrap();
            last_put = Instant::now();
        }
        let Ok(Some(s)) = sub.recv_timeout(Duration::from_millis(100)) else {
            continue;
        };
        let v: serde_json::Value = serde_json::from_slice(&s.payload().to_bytes()).unwrap();
        match s.key_expr().as_str() {
            "rtcan/triskar2/velocity" => {
                let keys: Vec<&String> = v.as_object().unwrap().keys().collect();
                assert_eq!(keys, ["vx", "vy", "wz"]);
                velocity_vx = v["vx"].as_f64().unwrap();
            }
            "rtcan/triskar2/odometry" => {
                let keys: Vec<&String> = v.as_object().unwrap().keys().collect();
                assert_eq!(keys, ["x", "y", "theta", "vx", "vy", "wz"]);
                odometry_x = v["x"].as_f64().unwrap();
                odometry_n += 1;
            }
            _ => {}
        }
        if velocity_vx > 0.0 && !refused_sent {
            // The bridge hears this peer now: one put on a read-only topic, one that
            // does not fit teleop's type.
            session
                .put(
                    "rtcan/triskar2/odometry",
                    r#"{"x":1,"y":0,"theta":0,"vx":0,"vy":0,"wz":0}"#,
                )
                .wait()
                .unwrap();
            teleop.put(r#"{"vx":"fast","vy":0,"wz":0}"#).wait().unwrap();
            refused_sent = true;
        }
    }
    assert!(
        (velocity_vx - 0.3).abs() < 1e-6,
        "velocity vx {velocity_vx}"
    );
    assert!(
        odometry_x >= 0.05,
        "odometry x {odometry_x} after {odometry_n}"
    );
    assert!(refused_sent);
    // Give the two bad puts time to arrive, then stop the bridge and read its report.
    std::thread::sleep(Duration::from_millis(500));
    drop(sub);
    drop(teleop);
    session.close().wait().unwrap();
    // Ctrl-C (SIGTERM here) stops the bridge, which reports what it did.
    // SAFETY: kill(2) on the child this test spawned.
    assert_eq!(unsafe { libc::kill(bridge.id() as i32, libc::SIGTERM) }, 0);
    let rest: Vec<String> = out.lines().map(|l| l.unwrap()).collect();
    assert!(bridge.wait().unwrap().success());
    let report = rest.iter().find(|l| l.starts_with("bridged ")).unwrap();
    let accepted: u64 = report
        .split("commands: ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .unwrap()
        .parse()
        .unwrap();
    assert!(accepted >= 1, "{report}");
    assert!(
        report.ends_with("accepted, 1 refused (not writable), 1 bad"),
        "{report}"
    );
    let published: u64 = report["bridged ".len()..]
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(published > u64::from(odometry_n), "{report}");
}
