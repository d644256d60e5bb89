#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! A WAN of CANs (paper 003; issue 13): two simulated robots, each on its own bus with
//! its own `rtcan bridge` process, joined by a Zenoh router on loopback (a router session
//! in this process). The follower's robot.toml declares `teleop` `remote =
//! "triskar2/velocity"`: a command given to the leader over Zenoh moves the leader, its
//! filtered `velocity` crosses to the follower's bus as the follower's `teleop`, and the
//! follower drives too.
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, ChildStdout, Command, Stdio};
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

fn session(mode: &str, key: &str, endpoint: &str) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", &format!("\"{mode}\"")).unwrap();
    c.insert_json5("scouting/multicast/enabled", "false")
        .unwrap();
    c.insert_json5(key, &format!("[\"{endpoint}\"]")).unwrap();
    zenoh::open(c).wait().unwrap()
}

fn bridge(robot: &str, endpoint: &str) -> (Child, BufReader<ChildStdout>, Vec<String>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rtcan"))
        .args(["bridge", "--sim", robot, "--connect", endpoint])
        .args(["--seconds", "60", "--speed", "2"])
        .current_dir(root())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut head = Vec::new();
    let mut l = String::new();
    out.read_line(&mut l).unwrap();
    head.push(l.trim_end().to_string());
    if robot.contains("follower") {
        let mut l = String::new();
        out.read_line(&mut l).unwrap();
        head.push(l.trim_end().to_string());
    }
    (child, out, head)
}

fn stop(mut child: Child, out: BufReader<ChildStdout>) -> Vec<String> {
    // SAFETY: kill(2) on a child this test spawned.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGTERM) }, 0);
    let rest: Vec<String> = out.lines().map(|l| l.unwrap()).collect();
    assert!(child.wait().unwrap().success());
    rest
}

#[test]
fn two_robots_exchange_declared_topics_through_a_router() {
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let router = session("router", "listen/endpoints", &endpoint);
    let (leader, leader_out, lh) = bridge("robot.toml", &endpoint);
    assert!(
        // With the 8 module-state topics of the supervised Triskar2.
        lh[0].starts_with("bridge ready: 19 topics on rtcan/triskar2/*"),
        "{lh:?}"
    );
    let (follower, follower_out, fh) = bridge("robots/triskar2_follower.toml", &endpoint);
    assert!(
        fh[0].starts_with("bridge ready: 19 topics on rtcan/follower/*")
            && fh[0].ends_with("writable: teleop"),
        "{fh:?}"
    );
    assert_eq!(fh[1], "  teleop <- rtcan/triskar2/velocity");

    let peer = session("peer", "connect/endpoints", &endpoint);
    let sub = peer.declare_subscriber("rtcan/**").wait().unwrap();
    let teleop = peer
        .declare_publisher("rtcan/triskar2/teleop")
        .wait()
        .unwrap();
    let (mut leader_vx, mut follower_vx, mut follower_x, mut leader_x) = (0.0, 0.0, 0.0, 0.0);
    let mut last_put = Instant::now() - Duration::from_secs(1);
    let t0 = Instant::now();
    while follower_x < 0.05 && t0.elapsed() < Duration::from_secs(50) {
        if leader_vx == 0.0 && last_put.elapsed() > Duration::from_millis(300) {
            teleop.put(r#"{"vx":0.3,"vy":0,"wz":0}"#).wait().unwrap();
            last_put = Instant::now();
        }
        let Ok(Some(s)) = sub.recv_timeout(Duration::from_millis(100)) else {
            continue;
        };
        let v: serde_json::Value = serde_json::from_slice(&s.payload().to_bytes()).unwrap();
        match s.key_expr().as_str() {
            "rtcan/triskar2/velocity" => leader_vx = v["vx"].as_f64().unwrap(),
            "rtcan/triskar2/odometry" => leader_x = v["x"].as_f64().unwrap(),
            "rtcan/follower/velocity" => follower_vx = v["vx"].as_f64().unwrap(),
            "rtcan/follower/odometry" => follower_x = v["x"].as_f64().unwrap(),
            // The follower never took a command from this peer: only the leader did.
            "rtcan/follower/teleop" => assert!(v["vx"].as_f64().unwrap() >= 0.0),
            _ => {}
        }
    }
    assert!((leader_vx - 0.3f64).abs() < 1e-6, "leader vx {leader_vx}");
    assert!(
        (follower_vx - 0.3f64).abs() < 1e-6,
        "follower vx {follower_vx}"
    );
    assert!(follower_x >= 0.05, "follower x {follower_x}");
    assert!(leader_x > 0.0, "leader x {leader_x}");
    drop(sub);
    drop(teleop);
    peer.close().wait().unwrap();
    let lr = stop(leader, leader_out);
    let fr = stop(follower, follower_out);
    router.close().wait().unwrap();
    let report = |r: &[String], p: &str| r.iter().find(|l| l.starts_with(p)).unwrap().clone();
    // The leader took the commands; the follower none, but the leader's velocity.
    assert!(
        !report(&lr, "bridged ").contains("commands: 0 accepted"),
        "{lr:?}"
    );
    assert!(
        report(&fr, "bridged ").ends_with("commands: 0 accepted, 0 refused (not writable), 0 bad"),
        "{fr:?}"
    );
    let imported: u64 = report(&fr, "imported ")
        .split(' ')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert!(imported > 10, "{fr:?}");
}
