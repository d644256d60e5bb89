//! A Zenoh router for trying `rtcan bridge --ros2` and the WAN of CANs by hand where
//! `zenohd` / `ros2 run rmw_zenoh_cpp rmw_zenohd` is not installed (docs/BRIDGE.md):
//! `cargo run -p rtcan-bridge --example zrouter -- tcp/127.0.0.1:7447 [SECONDS]`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use zenoh::Wait;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let endpoint = args.first().cloned().unwrap_or("tcp/127.0.0.1:7447".into());
    let seconds: u64 = args.get(1).map_or(3600, |s| s.parse().unwrap());
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"router\"").unwrap();
    c.insert_json5("scouting/multicast/enabled", "false")
        .unwrap();
    c.insert_json5("listen/endpoints", &format!("[\"{endpoint}\"]"))
        .unwrap();
    let _router = zenoh::open(c).wait().unwrap();
    println!("router on {endpoint} for {seconds} s");
    std::thread::sleep(std::time::Duration::from_secs(seconds));
}
