//! WAN of CANs latency and throughput through a Zenoh router (docs/BRIDGE.md), measured,
//! not asserted: `cargo run --release -p rtcan-bridge --example wan_bench`.
//!
//! The frames of 20 s of the simulated Triskar2 bus are fed one at a time to the bridge of
//! robot `triskar2` (an in-memory `Link`). A router session listens on loopback; the
//! bridges are peers connected to it, the measuring subscriber a *client* of it, so every
//! sample it gets went through the router. Figures:
//! 1. bus frame → Zenoh subscriber, JSON bridge (`rtcan bridge`), via the router;
//! 2. bus frame → Zenoh subscriber, ROS 2 bridge (`--ros2`: CDR + attachment), via the router;
//! 3. bus → bus: the leader's `velocity` frame handed to its bridge → the follower's bridge
//!    (robots/triskar2_follower.toml, `teleop` `remote = "triskar2/velocity"`) publishing
//!    it on the follower's link;
//! 4. throughput of one bridge through the router (the recording 5 times back to back).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::unnecessary_to_owned
)]

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use rtcan_bridge::ros2::Ros2Bridge;
use rtcan_bridge::{open_session, Bridge, Options};
use rtcan_host::{Link, Stamped};
use rtcan_sim::decode::plan_catalog;
use zenoh::Wait;

/// Frames one at a time; remembers when something was published on it.
struct VecLink {
    frames: std::vec::IntoIter<Stamped>,
    published: Option<Instant>,
    endless: bool,
}

impl VecLink {
    fn new(frames: &[Stamped]) -> Self {
        VecLink {
            frames: frames.to_vec().into_iter(),
            published: None,
            endless: false,
        }
    }
}

impl Link for VecLink {
    fn recv(&mut self) -> Result<Option<Vec<Stamped>>, String> {
        match self.frames.next() {
            Some(f) => Ok(Some(vec![f])),
            None if self.endless => Ok(Some(Vec::new())),
            None => Ok(None),
        }
    }
    fn publish(&mut self, _: &str, _: &[u8]) -> Result<(), String> {
        self.published = Some(Instant::now());
        Ok(())
    }
    fn now_ns(&self) -> u64 {
        0
    }
}

fn load(path: &str) -> rtcan_model::Plan {
    rtcan_model::Robot::load(format!("{}/../{path}", env!("CARGO_MANIFEST_DIR")))
        .map_err(|d| d.render())
        .unwrap()
}

fn client(endpoint: &str) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"client\"").unwrap();
    c.insert_json5("scouting/multicast/enabled", "false")
        .unwrap();
    c.insert_json5("connect/endpoints", &format!("[\"{endpoint}\"]"))
        .unwrap();
    zenoh::open(c).wait().unwrap()
}

fn quantiles(what: &str, mut lat: Vec<Duration>) {
    lat.sort();
    let q = |p: f64| lat[((lat.len() - 1) as f64 * p) as usize].as_secs_f64() * 1e6;
    println!(
        "{what}, {} messages: median {:.1} us, p90 {:.1} us, p99 {:.1} us, max {:.1} us",
        lat.len(),
        q(0.5),
        q(0.9),
        q(0.99),
        q(1.0)
    );
}

/// Latency of `step` → a sample on `sub`, one message in flight.
fn latency(
    frames: &[Stamped],
    sub: &zenoh::pubsub::Subscriber<zenoh::handlers::FifoChannelHandler<zenoh::sample::Sample>>,
    mut step: impl FnMut(&mut VecLink) -> (bool, bool),
) -> Vec<Duration> {
    let mut link = VecLink::new(frames);
    let mut lat = Vec::new();
    loop {
        let t0 = Instant::now();
        let (more, put) = step(&mut link);
        if !more {
            break;
        }
        if put && sub.recv_timeout(Duration::from_secs(2)).unwrap().is_some() {
            lat.push(t0.elapsed());
            // Samples of a message that became several ROS 2 messages (Range ×4).
            while sub.try_recv().ok().flatten().is_some() {}
        }
    }
    lat
}

fn main() {
    let plan = load("robot.toml");
    let follower_plan = load("robots/triskar2_follower.toml");
    let cat = plan_catalog(&plan);
    let fcat = plan_catalog(&follower_plan);
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
    let mut rc = zenoh::Config::default();
    rc.insert_json5("mode", "\"router\"").unwrap();
    rc.insert_json5("scouting/multicast/enabled", "false")
        .unwrap();
    rc.insert_json5("listen/endpoints", &format!("[\"{endpoint}\"]"))
        .unwrap();
    let _router = zenoh::open(rc).wait().unwrap();
    let sub_session = client(&endpoint);

    // 1. JSON bridge.
    let opts = Options {
        robot: "triskar2".into(),
        connect: vec![endpoint.clone()],
        ..Options::default()
    };
    let mut bridge = Bridge::new(&cat, opts).unwrap();
    let sub = sub_session
        .declare_subscriber("rtcan/triskar2/**")
        .wait()
        .unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let lat = latency(&frames, &sub, |link| {
        let before = bridge.counts.published;
        let more = bridge.step(link).unwrap();
        (more, bridge.counts.published > before)
    });
    quantiles(
        "1. latency bus frame -> Zenoh subscriber via the router (JSON)",
        lat,
    );
    drop(sub);

    // 2. ROS 2 bridge.
    {
        let session = open_session(&[], std::slice::from_ref(&endpoint)).unwrap();
        let mut r2 = Ros2Bridge::new(session, &plan, &cat, "triskar2", 0, &[]).unwrap();
        let sub = sub_session
            .declare_subscriber("0/triskar2/**")
            .wait()
            .unwrap();
        std::thread::sleep(Duration::from_millis(500));
        let lat = latency(&frames, &sub, |link| {
            let before = r2.counts.published;
            let more = r2.step(link).unwrap();
            (more, r2.counts.published > before)
        });
        quantiles(
            "2. latency bus frame -> ROS 2 subscriber via the router (CDR + attachment)",
            lat,
        );
    }

    // 3. bus -> bus: leader bridge -> router -> follower bridge -> follower's link.
    {
        let fopts = Options {
            robot: "follower".into(),
            connect: vec![endpoint.clone()],
            writable: follower_plan.bridge.writable(),
            imports: follower_plan.bridge.imports(),
            ..Options::default()
        };
        let mut follower = Bridge::new(&fcat, fopts).unwrap();
        std::thread::sleep(Duration::from_millis(500));
        let velocity = cat
            .topics
            .iter()
            .position(|t| t.name == "velocity")
            .unwrap();
        let mut flink = VecLink::new(&[]);
        flink.endless = true;
        let mut lat = Vec::new();
        let mut dec = rtcan_sim::decode::Decoder::new(&cat);
        for f in &frames {
            let done = rtcan_bridge::messages(&mut dec, vec![*f]);
            let Some((_, payload)) = done.into_iter().find(|(t, _)| *t == velocity) else {
                continue;
            };
            flink.published = None;
            let t0 = Instant::now();
            bridge.put(velocity, &payload).unwrap();
            while flink.published.is_none() && t0.elapsed() < Duration::from_secs(2) {
                follower.step(&mut flink).unwrap();
            }
            if let Some(t) = flink.published {
                lat.push(t - t0);
            }
        }
        quantiles(
            "3. latency leader velocity -> follower's bus (teleop), via the router",
            lat,
        );
    }

    // 4. Throughput of one bridge through the router.
    let got = Arc::new(AtomicU64::new(0));
    let g = got.clone();
    let _cb = sub_session
        .declare_subscriber("rtcan/triskar2/**")
        .callback(move |_| {
            g.fetch_add(1, Ordering::Relaxed);
        })
        .wait()
        .unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let start = bridge.counts.published;
    let t0 = Instant::now();
    for _ in 0..5 {
        let mut link = VecLink::new(&frames);
        while bridge.step(&mut link).unwrap() {}
    }
    let sent = bridge.counts.published - start;
    while got.load(Ordering::Relaxed) < sent && t0.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_micros(200));
    }
    let dt = t0.elapsed().as_secs_f64();
    let n = got.load(Ordering::Relaxed);
    println!(
        "4. throughput via the router (JSON): {sent} messages put, {n} received in {dt:.3} s: {:.0} msg/s",
        n as f64 / dt
    );
}
