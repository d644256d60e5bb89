//! Bridge latency and throughput (docs/BRIDGE.md), measured, not asserted:
//! `cargo run --release -p rtcan-bridge --example bridge_bench`.
//!
//! The frames of 20 s of the simulated Triskar2 bus are fed to a `Bridge` one at a time
//! (an in-memory `Link`); a second Zenoh session connected over TCP loopback subscribes to
//! every topic. Latency: from handing the frame that completes a message to the bridge
//! until the subscriber has the sample (decode, JSON, Zenoh, TCP, one message in flight).
//! Throughput: every message of the recording put back to back, counted by a callback
//! subscriber.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use rtcan_bridge::{open_session, Bridge, Options};
use rtcan_host::{Link, Stamped};
use rtcan_sim::decode::plan_catalog;
use zenoh::Wait;

struct VecLink {
    frames: std::vec::IntoIter<Stamped>,
}

impl Link for VecLink {
    fn recv(&mut self) -> Result<Option<Vec<Stamped>>, String> {
        Ok(self.frames.next().map(|f| vec![f]))
    }
    fn publish(&mut self, _: &str, _: &[u8]) -> Result<(), String> {
        Ok(())
    }
    fn now_ns(&self) -> u64 {
        0
    }
}

fn main() {
    let plan = rtcan_model::Robot::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml"))
        .map_err(|d| d.render())
        .unwrap();
    let cat = plan_catalog(&plan);
    let mut frames = Vec::new();
    {
        let mut sim = rtcan_host::sim::SimLink::start(&plan, 0.0).unwrap();
        while sim.now_ns() < 20_000_000_000 {
            frames.extend(sim.recv().unwrap().unwrap());
        }
    }
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let opts = Options {
        robot: "bench".into(),
        listen: vec![endpoint.clone()],
        ..Options::default()
    };
    let mut bridge = Bridge::new(&cat, opts).unwrap();
    let sub_session = open_session(&[], &[endpoint]).unwrap();

    // Latency, one message in flight.
    let sub = sub_session
        .declare_subscriber("rtcan/bench/**")
        .wait()
        .unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let mut link = VecLink {
        frames: frames.clone().into_iter(),
    };
    let mut lat = Vec::new();
    loop {
        let before = bridge.counts.published;
        let t0 = Instant::now();
        if !bridge.step(&mut link).unwrap() {
            break;
        }
        if bridge.counts.published > before
            && sub.recv_timeout(Duration::from_secs(2)).unwrap().is_some()
        {
            lat.push(t0.elapsed());
        }
    }
    drop(sub);
    lat.sort();
    let q = |p: f64| lat[((lat.len() - 1) as f64 * p) as usize].as_secs_f64() * 1e6;
    println!(
        "latency bus frame -> Zenoh subscriber (JSON, TCP loopback), {} messages: median {:.1} us, p90 {:.1} us, p99 {:.1} us, max {:.1} us",
        lat.len(),
        q(0.5),
        q(0.9),
        q(0.99),
        q(1.0)
    );

    // Throughput: the recording five times, back to back.
    let got = Arc::new(AtomicU64::new(0));
    let g = got.clone();
    let _cb = sub_session
        .declare_subscriber("rtcan/bench/**")
        .callback(move |_| {
            g.fetch_add(1, Ordering::Relaxed);
        })
        .wait()
        .unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let start = bridge.counts.published;
    let t0 = Instant::now();
    for _ in 0..5 {
        let mut link = VecLink {
            frames: frames.clone().into_iter(),
        };
        while bridge.step(&mut link).unwrap() {}
    }
    let sent = bridge.counts.published - start;
    while got.load(Ordering::Relaxed) < sent && t0.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_micros(200));
    }
    let dt = t0.elapsed().as_secs_f64();
    let n = got.load(Ordering::Relaxed);
    println!(
        "throughput: {sent} messages put, {n} received in {dt:.3} s: {:.0} msg/s",
        n as f64 / dt
    );
}
