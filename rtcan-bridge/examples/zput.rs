//! Puts one value on a key, N times, 100 ms apart (docs/BRIDGE.md): `cargo run -p
//! rtcan-bridge --example zput -- tcp/127.0.0.1:7447 rtcan/triskar2/teleop '{"vx":0.3,"vy":0,"wz":0}' 5`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use zenoh::Wait;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let endpoint = args.first().cloned().unwrap_or("tcp/127.0.0.1:7447".into());
    let key = args
        .get(1)
        .cloned()
        .unwrap_or("rtcan/triskar2/teleop".into());
    let value = args
        .get(2)
        .cloned()
        .unwrap_or(r#"{"vx":0.3,"vy":0,"wz":0}"#.into());
    let n: usize = args.get(3).map_or(1, |s| s.parse().unwrap());
    let session = rtcan_bridge::open_session(&[], &[endpoint]).unwrap();
    std::thread::sleep(std::time::Duration::from_millis(300));
    for _ in 0..n {
        session.put(&key, value.clone()).wait().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    println!("put {value} on {key} {n} times");
}
