//! A plain Zenoh subscriber for trying the bridge by hand (docs/BRIDGE.md):
//! `cargo run -p rtcan-bridge --example zsub -- tcp/127.0.0.1:7447 'rtcan/triskar2/**' 5`
//! prints the first N samples as `key payload`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use zenoh::Wait;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let endpoint = args.first().cloned().unwrap_or("tcp/127.0.0.1:7447".into());
    let key = args.get(1).cloned().unwrap_or("rtcan/**".into());
    let n: usize = args.get(2).map_or(10, |s| s.parse().unwrap());
    let session = rtcan_bridge::open_session(&[], &[endpoint]).unwrap();
    let sub = session.declare_subscriber(key).wait().unwrap();
    for _ in 0..n {
        let s = sub.recv().unwrap();
        println!(
            "{} {}",
            s.key_expr(),
            String::from_utf8_lossy(&s.payload().to_bytes())
        );
    }
}
