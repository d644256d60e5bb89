//! Parameters over the bus on the simulated Triskar2 (docs/SERVICES.md §2): the host asks
//! through the gateway, each module's own server answers on the reserved parameter
//! channel (docs/PROTOCOL.md §2.3) — exact frames, a refused value never applied, an
//! absent module timing out, persisted values surviving a reset, and the robot's HRT
//! traffic untouched while parameters are set.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use rtcan_core::Nanos;
use rtcan_pubsub::param::{Refused, Reply, Request};
use rtcan_sim::param::{specs, ParamBus, ParamJob, ParamLog};
use rtcan_sim::run::SimConfig;
use rtcan_sim::triskar::{self, TriskarConfig, TriskarRun, MODULES};

const MS: Nanos = 1_000_000;

fn load() -> (rtcan_model::Plan, Vec<rtcan_model::params::ParamDecl>) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml");
    let src = std::fs::read_to_string(path).unwrap();
    rtcan_model::params::load("robot.toml", &src)
        .map_err(|d| d.render())
        .unwrap()
}

fn run(
    seconds: f64,
    requests: Vec<(Nanos, usize, Request)>,
    faults: &[&str],
) -> (TriskarRun, ParamLog) {
    let (plan, decls) = load();
    let job = ParamJob {
        specs: specs(&decls, MODULES.len()),
        requests,
        timeout_ns: 50 * MS,
    };
    let cfg = TriskarConfig {
        sim: SimConfig {
            seconds,
            seed: 1,
            record_wire: true,
            ..SimConfig::default()
        },
        faults: faults
            .iter()
            .map(|f| rtcan_sim::fault::parse(f, &MODULES).unwrap())
            .collect(),
        ..TriskarConfig::default()
    };
    triskar::run_with_params(&plan, &cfg, ParamBus::new(&job, MODULES.len())).unwrap()
}

fn f32b(v: f32) -> u32 {
    v.to_bits()
}

/// The frames of the parameter channel on the wire: (identifier, data).
fn channel(r: &TriskarRun) -> Vec<(u32, Vec<u8>)> {
    r.run
        .wire
        .iter()
        .filter(|w| w.ok && (0xFF00..=0xFF7F).contains(&w.frame.id().msg_id().0))
        .map(|w| (w.frame.id().raw(), w.frame.data().to_vec()))
        .collect()
}

fn hrt_misses(r: &TriskarRun) -> u64 {
    r.run.figures.hrt.iter().map(|h| h.misses).sum()
}

#[test]
fn get_and_set_over_the_bus_exact_frames_and_a_refused_value() {
    let t0 = 500 * MS;
    let reqs = vec![
        (t0, 1, Request::Get { index: 0 }),
        (
            t0,
            1,
            Request::Set {
                index: 0,
                bits: f32b(0.8),
            },
        ),
        // Out of [0, 1]: refused by motor1, never applied.
        (
            t0,
            1,
            Request::Set {
                index: 0,
                bits: f32b(3.0),
            },
        ),
        (t0, 1, Request::Get { index: 0 }),
        (t0, 4, Request::Set { index: 1, bits: 20 }),
        (t0, 4, Request::Set { index: 1, bits: 0 }),
        (t0, 5, Request::List { index: 0 }),
    ];
    let (r, log) = run(1.0, reqs.clone(), &[]);
    let replies: Vec<Option<Reply>> = log.results.iter().map(|o| o.reply).collect();
    let value = |index, bits, count| Some(Reply::Value { index, bits, count });
    let refused = |index, why| Some(Reply::Refused { index, why });
    assert_eq!(
        replies,
        vec![
            value(0, f32b(0.04), 2),
            value(0, f32b(0.8), 2),
            refused(0, Refused::OutOfRange),
            value(0, f32b(0.8), 2),
            value(1, 20, 2),
            refused(1, Refused::OutOfRange),
            // psu declares no parameter.
            refused(0, Refused::Unknown),
        ]
    );
    for (o, (_, m, q)) in log.results.iter().zip(&reqs) {
        assert_eq!((o.module, o.request), (*m, *q));
        let took = o.done_ns - o.asked_ns;
        eprintln!(
            "{:?} to {}: {} µs",
            o.request,
            MODULES[o.module],
            took / 1000
        );
        assert!(took > 0 && took < 10 * MS, "{o:?}");
    }
    // Exactly these frames, in this order: request 0xFF00 + m, reply 0xFF40 + m, one
    // 8-byte NRT frame each.
    let f = |b: f32| b.to_bits().to_le_bytes();
    let (kp04, kp08, kp3) = (f(0.04), f(0.8), f(3.0));
    let frames = channel(&r);
    let want: Vec<(u32, Vec<u8>)> = vec![
        (0x1FFF_8080, vec![1, 0, 0, 0, 0, 0, 0, 0]),
        (
            0x1FFF_A080,
            vec![0, 2, 0, 0, kp04[0], kp04[1], kp04[2], kp04[3]],
        ),
        (
            0x1FFF_8080,
            vec![2, 0, 0, 0, kp08[0], kp08[1], kp08[2], kp08[3]],
        ),
        (
            0x1FFF_A080,
            vec![0, 2, 0, 0, kp08[0], kp08[1], kp08[2], kp08[3]],
        ),
        (
            0x1FFF_8080,
            vec![2, 0, 0, 0, kp3[0], kp3[1], kp3[2], kp3[3]],
        ),
        (0x1FFF_A080, vec![2, 0, 0, 0, 0, 0, 0, 0]),
        (0x1FFF_8080, vec![1, 0, 0, 0, 0, 0, 0, 0]),
        (
            0x1FFF_A080,
            vec![0, 2, 0, 0, kp08[0], kp08[1], kp08[2], kp08[3]],
        ),
        (0x1FFF_8200, vec![2, 0, 1, 0, 20, 0, 0, 0]),
        (0x1FFF_A200, vec![0, 2, 1, 0, 20, 0, 0, 0]),
        (0x1FFF_8200, vec![2, 0, 1, 0, 0, 0, 0, 0]),
        (0x1FFF_A200, vec![2, 0, 1, 0, 0, 0, 0, 0]),
        (0x1FFF_8280, vec![3, 0, 0, 0, 0, 0, 0, 0]),
        (0x1FFF_A280, vec![1, 0, 0, 0, 0, 0, 0, 0]),
    ];
    assert_eq!(frames, want);
    // The live values: motor1.kp 0.8 (the 3.0 never applied), ki untouched;
    // proximity.log_every 20 (the 0 never applied).
    assert_eq!(log.values[1], vec![f32b(0.8), f32b(1.0)]);
    assert_eq!(log.values[4], vec![f32b(0.25), 20]);
    assert_eq!(log.refused, vec![0, 1, 0, 0, 1, 1]);
    assert_eq!(log.served, vec![0, 4, 0, 0, 2, 1]);
    assert_eq!(hrt_misses(&r), 0);
}

#[test]
fn an_absent_module_times_out_and_the_host_goes_on() {
    let t0 = 500 * MS;
    let reqs = vec![
        (t0, 2, Request::Get { index: 0 }),
        (t0, 1, Request::Get { index: 1 }),
        // No module 7 on this bus: nobody answers either.
        (t0, 7, Request::Get { index: 0 }),
    ];
    let (_, log) = run(1.0, reqs, &["motor2:dies@0.3s"]);
    let o = &log.results;
    assert_eq!(o.len(), 3);
    assert_eq!(o[0].reply, None);
    assert_eq!(o[0].asked_ns, t0);
    assert_eq!(
        o[0].done_ns,
        t0 + 50 * MS,
        "times out exactly at its deadline"
    );
    assert_eq!(
        o[1].reply,
        Some(Reply::Value {
            index: 1,
            bits: f32b(1.0),
            count: 2
        })
    );
    // Made at the gateway's next engine call after the timeout (the host acts when its
    // node runs: within a slot or two).
    eprintln!(
        "next request made {} µs after the timeout",
        (o[1].asked_ns - t0 - 50 * MS) / 1000
    );
    assert!(
        (t0 + 50 * MS..t0 + 52 * MS).contains(&o[1].asked_ns),
        "{:?}",
        o[1]
    );
    assert_eq!(o[2].reply, None);
    assert_eq!(o[2].done_ns - o[2].asked_ns, 50 * MS);
    assert_eq!(log.served[2], 0);
}

#[test]
fn persisted_values_survive_a_reset_the_others_do_not() {
    let t0 = 400 * MS;
    let reqs = vec![
        (
            t0,
            4,
            Request::Set {
                index: 0,
                bits: f32b(0.4),
            },
        ),
        (t0, 4, Request::Set { index: 1, bits: 99 }),
        // proximity resets at 0.6 s; asked again after it is back.
        (900 * MS, 4, Request::Get { index: 0 }),
        (900 * MS, 4, Request::Get { index: 1 }),
    ];
    let (r, log) = run(1.2, reqs, &["proximity:reset@0.6s"]);
    let replies: Vec<Option<Reply>> = log.results.iter().map(|o| o.reply).collect();
    assert_eq!(
        replies,
        vec![
            Some(Reply::Value {
                index: 0,
                bits: f32b(0.4),
                count: 2
            }),
            Some(Reply::Value {
                index: 1,
                bits: 99,
                count: 2
            }),
            // stop_distance is persisted: back from flash.
            Some(Reply::Value {
                index: 0,
                bits: f32b(0.4),
                count: 2
            }),
            // log_every is not: its default again.
            Some(Reply::Value {
                index: 1,
                bits: 10,
                count: 2
            }),
        ]
    );
    assert_eq!(log.loaded[4], 1);
    assert_eq!(r.modules[4].reboots, 1);
}

#[test]
fn hrt_traffic_untouched_while_parameters_are_set() {
    // 200 sets, back to back, over 3 s of the robot driving.
    let (plan, _) = load();
    let base = triskar::run(
        &plan,
        &TriskarConfig {
            sim: SimConfig {
                seconds: 3.0,
                seed: 1,
                ..SimConfig::default()
            },
            ..TriskarConfig::default()
        },
    )
    .unwrap();
    let reqs: Vec<(Nanos, usize, Request)> = (0..200u32)
        .map(|i| {
            (
                500 * MS,
                1 + (i as usize % 3),
                Request::Set {
                    index: 0,
                    bits: f32b(0.01 * (i % 100) as f32),
                },
            )
        })
        .collect();
    let (r, log) = run(3.0, reqs, &[]);
    // motor2 and motor3 declare no parameter: Unknown; motor1 takes every value.
    let answered = log.results.iter().filter(|o| o.reply.is_some()).count();
    let last = log.results.last().unwrap().done_ns;
    eprintln!(
        "{answered} of {} answered, the last at {:.3} s; HRT misses {}",
        log.results.len(),
        last as f64 / 1e9,
        hrt_misses(&r)
    );
    assert_eq!(answered, 200);
    assert_eq!(log.served[1] + log.served[2] + log.served[3], 200);
    assert_eq!(hrt_misses(&r), 0);
    assert_eq!(hrt_misses(&base), 0);
    // Every SRT topic as without the parameters: same messages, no miss.
    for (a, b) in r.run.figures.srt.iter().zip(&base.run.figures.srt) {
        assert_eq!((a.name.as_str(), a.misses), (b.name.as_str(), 0), "{a:?}");
        assert_eq!(a.count, b.count, "{}", a.name);
    }
    assert_eq!(r.run.counters[1].hrt_late, 0);
}
