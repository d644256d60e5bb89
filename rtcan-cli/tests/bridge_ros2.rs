#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! `rtcan bridge --ros2 --sim robot.toml` joins ROS 2 the way rmw_zenoh nodes do (issue
//! 13): through a Zenoh router (here a router session in the test process; `zenohd` is
//! not installed), with rmw_zenoh's liveliness tokens, key expressions, CDR and
//! attachments. A peer of the router plays the ROS 2 node: it finds the bridge's node,
//! publishers and subscription by their tokens, decodes `velocity` and `odometry`,
//! publishes a `geometry_msgs/msg/Twist` on `/triskar2/teleop` that drives the robot,
//! and puts a sample on a read-only topic and a big-endian Twist: refused / bad, counted.
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use rtcan_bridge::ros2::rmw::{self, Kind, NodeNames};
use rtcan_bridge::ros2::types;
use rtcan_model::bridge_keys::Ros2Type;
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

fn twist_cdr(vx: f64) -> Vec<u8> {
    let v = serde_json::json!({"vx": vx, "vy": 0.0, "wz": 0.0});
    types::encode(Ros2Type::Twist, &v, types::Stamp::from_ns(0), "", 0.0).remove(0)
}

fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

#[test]
fn a_ros2_node_on_rmw_zenoh_sees_and_drives_the_simulated_robot() {
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let router = session("router", "listen/endpoints", &endpoint);
    let mut bridge = Command::new(env!("CARGO_BIN_EXE_rtcan"))
        .args([
            "bridge",
            "--ros2",
            "--sim",
            "robot.toml",
            "--connect",
            &endpoint,
        ])
        .args(["--seconds", "60", "--speed", "2"])
        .env_remove("ROS_DOMAIN_ID")
        .current_dir(root())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(bridge.stdout.take().unwrap());
    let mut ready = String::new();
    out.read_line(&mut ready).unwrap();
    assert!(
        ready.starts_with(
            "ros2 bridge ready: node /triskar2/rtcan_bridge in domain 0 (connect [\"tcp/127.0.0.1:"
        ) && ready.ends_with("writable: teleop\n"),
        "{ready}"
    );
    // The tokens it prints: node, teleop subscription, 7 publishers.
    let mut printed = Vec::new();
    for _ in 0..9 {
        let mut l = String::new();
        out.read_line(&mut l).unwrap();
        printed.push(l.trim().to_string());
    }

    // The ROS 2 node: a peer of the router, as rmw_zenoh's sessions are.
    let ros = session("peer", "connect/endpoints", &endpoint);
    // The graph as `ros2 topic list` builds it: every liveliness token of domain 0.
    let mut tokens = Vec::new();
    let t0 = Instant::now();
    while tokens.len() < 9 && t0.elapsed() < Duration::from_secs(20) {
        tokens = ros
            .liveliness()
            .get("@ros2_lv/0/**")
            .wait()
            .unwrap()
            .iter()
            .filter_map(|r| r.into_result().ok().map(|s| s.key_expr().to_string()))
            .collect();
        std::thread::sleep(Duration::from_millis(100));
    }
    tokens.sort();
    let mut sorted_printed = printed.clone();
    sorted_printed.sort();
    assert_eq!(tokens, sorted_printed, "tokens on the router vs printed");
    // Every token exactly as rmw_zenoh writes it, for the bridge's session ID.
    let zid = printed[0].split('/').nth(2).unwrap().to_string();
    let node = NodeNames {
        domain: 0,
        zid,
        node_id: 0,
        namespace: "/triskar2".into(),
        name: "rtcan_bridge".into(),
    };
    let qos = rmw::qos_default(10);
    let th = |t| types::type_hash(&types::description(t));
    let dds = |t: Ros2Type| types::dds_name(t.name());
    let mut want = vec![
        node.node_token(),
        node.entity_token(
            1,
            Kind::Subscription,
            "teleop",
            &dds(Ros2Type::Twist),
            &th(Ros2Type::Twist),
            &qos,
        ),
    ];
    let pubs = [
        ("velocity", Ros2Type::Twist),
        ("odometry", Ros2Type::Odometry),
        ("proximity_0", Ros2Type::Range),
        ("proximity_1", Ros2Type::Range),
        ("proximity_2", Ros2Type::Range),
        ("proximity_3", Ros2Type::Range),
        ("battery", Ros2Type::BatteryState),
    ];
    for (i, (t, ty)) in pubs.iter().enumerate() {
        want.push(node.entity_token(i as u32 + 2, Kind::Publisher, t, &dds(*ty), &th(*ty), &qos));
    }
    assert_eq!(printed, want, "printed tokens");
    assert_eq!(
        want[2],
        format!(
            "@ros2_lv/0/{}/0/2/MP/%/%triskar2/rtcan_bridge/%triskar2%velocity/geometry_msgs::msg::dds_::Twist_/RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a/::,10:,:,:,,",
            node.zid
        )
    );

    let key = |t: &str, ty: Ros2Type| node.topic_key(t, &dds(ty), &th(ty));
    let velocity_key = key("velocity", Ros2Type::Twist);
    assert_eq!(
        velocity_key,
        "0/triskar2/velocity/geometry_msgs::msg::dds_::Twist_/RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a"
    );
    let odometry_key = key("odometry", Ros2Type::Odometry);
    // The bridge's samples only (not this node's own puts below).
    let sub = ros
        .declare_subscriber("0/triskar2/**")
        .allowed_origin(zenoh::sample::Locality::Remote)
        .wait()
        .unwrap();
    let teleop = ros
        .declare_publisher(key("teleop", Ros2Type::Twist))
        .wait()
        .unwrap();

    let velocity_gid = rmw::gid(&want[2]);
    let (mut vx, mut odom_x, mut last_seq, mut odometry_n) = (0.0f64, 0.0f64, 0i64, 0u32);
    let mut last_put = Instant::now() - Duration::from_secs(1);
    let mut bad_sent = false;
    let mut seq = 1i64;
    let t0 = Instant::now();
    while odom_x < 0.05 && t0.elapsed() < Duration::from_secs(50) {
        if vx == 0.0 && last_put.elapsed() > Duration::from_millis(300) {
            let gid = [7u8; 16];
            teleop
                .put(twist_cdr(0.3))
                .attachment(rmw::attachment(seq, rtcan_bridge::ros2::now_ns(), &gid))
                .wait()
                .unwrap();
            seq += 1;
            last_put = Instant::now();
        }
        let Ok(Some(s)) = sub.recv_timeout(Duration::from_millis(100)) else {
            continue;
        };
        let b = s.payload().to_bytes();
        let k = s.key_expr().as_str();
        if k == velocity_key {
            let v = types::decode_twist(&b).unwrap();
            vx = v["vx"].as_f64().unwrap();
            let (sq, ts, gid) = rmw::parse_attachment(&s.attachment().unwrap().to_bytes()).unwrap();
            assert_eq!(gid, velocity_gid);
            assert!(
                sq > last_seq,
                "sequence numbers increase: {sq} after {last_seq}"
            );
            last_seq = sq;
            assert!((ts - rtcan_bridge::ros2::now_ns()).abs() < 10_000_000_000);
        } else if k == odometry_key {
            assert_eq!(b.len(), 724);
            assert_eq!(&b[..4], &[0, 1, 0, 0]);
            assert_eq!(&b[12..21], b"\x05\0\0\0odom\0");
            // pose.pose.position.x after header and child_frame_id "base_link".
            odom_x = f64_at(&b, 44);
            odometry_n += 1;
        }
        if vx > 0.0 && !bad_sent {
            // A sample on a read-only topic, and a Twist in big-endian CDR.
            ros.put(odometry_key.clone(), vec![0u8, 1, 0, 0])
                .wait()
                .unwrap();
            let mut be = twist_cdr(0.1);
            be[1] = 0;
            teleop.put(be).wait().unwrap();
            bad_sent = true;
        }
    }
    assert!((vx - 0.3).abs() < 1e-6, "velocity vx {vx}");
    assert!(odom_x >= 0.05, "odometry x {odom_x} after {odometry_n}");
    std::thread::sleep(Duration::from_millis(500));
    drop(sub);
    drop(teleop);
    ros.close().wait().unwrap();
    // SAFETY: kill(2) on the child this test spawned.
    assert_eq!(unsafe { libc::kill(bridge.id() as i32, libc::SIGTERM) }, 0);
    let rest: Vec<String> = out.lines().map(|l| l.unwrap()).collect();
    assert!(bridge.wait().unwrap().success());
    router.close().wait().unwrap();
    let report = rest.iter().find(|l| l.starts_with("bridged ")).unwrap();
    assert!(
        report.ends_with("accepted, 1 refused (not writable), 1 bad"),
        "{report}"
    );
    let accepted: u64 = report
        .split("commands: ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .unwrap()
        .parse()
        .unwrap();
    assert!(accepted >= 1, "{report}");
}

#[test]
fn ros2_usage_errors_exit_2() {
    for (args, want) in [
        (&["--domain-id", "3"][..], "--domain-id needs --ros2"),
        (
            &["--ros2", "--raw"][..],
            "--raw and --ros2 exclude each other",
        ),
        (
            &["--ros2", "--domain-id", "233"][..],
            "domain id `233`: expected 0..=232",
        ),
        (
            &["--ros2", "--domain-id", "x"][..],
            "domain id `x`: expected 0..=232",
        ),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_rtcan"))
            .arg("bridge")
            .args(args)
            .current_dir(root())
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(want), "{args:?}: {err}");
    }
}
