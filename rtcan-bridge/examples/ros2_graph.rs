//! What `ros2 topic list -t` reads from rmw_zenoh's graph, without ROS 2 (docs/BRIDGE.md):
//! `cargo run -p rtcan-bridge --example ros2_graph -- tcp/127.0.0.1:7447 [DOMAIN]` prints
//! every liveliness token of the domain (`@ros2_lv/<domain>/**`) and then the topics and
//! types the publisher/subscription tokens declare, demangled as rmw_zenoh does.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use zenoh::Wait;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let endpoint = args.first().cloned().unwrap_or("tcp/127.0.0.1:7447".into());
    let domain = args.get(1).cloned().unwrap_or("0".into());
    let session = rtcan_bridge::open_session(&[], &[endpoint]).unwrap();
    std::thread::sleep(std::time::Duration::from_millis(500));
    let mut tokens: Vec<String> = session
        .liveliness()
        .get(format!("@ros2_lv/{domain}/**"))
        .wait()
        .unwrap()
        .iter()
        .filter_map(|r| r.into_result().ok().map(|s| s.key_expr().to_string()))
        .collect();
    tokens.sort();
    let mut topics = std::collections::BTreeSet::new();
    for t in &tokens {
        println!("{t}");
        let p: Vec<&str> = t.split('/').collect();
        // @ros2_lv/domain/zid/nid/id/kind/enclave/ns/node/topic/type/hash/qos
        if p.len() == 13 && (p[5] == "MP" || p[5] == "MS") {
            let ty = p[10].replace("::dds_::", "::").replace("::", "/");
            topics.insert(format!(
                "{} [{}]",
                p[9].replace('%', "/"),
                ty.trim_end_matches('_')
            ));
        }
    }
    println!();
    for t in topics {
        println!("{t}");
    }
}
