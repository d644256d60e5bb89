//! On-target test of the parameter service (issue 15, docs/SERVICES.md §2) on the
//! Cortex-M3: a `ParamClient` and a module's `ParamServer` exchange the exact frames of
//! the reserved parameter channel; the module range-checks every set with its
//! `Params` (f32 compares and NaN in software float) before applying it, persists the
//! persisted ones in a `ParamStore` on the F103 flash model (1 KiB pages, half-word
//! programming), and after a "reset" (the store reopened from the same flash) gets them
//! back while the others are at their defaults. A request to an absent module times out
//! exactly at its deadline. Exit code 0 = pass.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use lm3s6965 as _;
use rtcan::core::Frame;
use rtcan::pubsub::flash::F103Flash;
use rtcan::pubsub::param::bus::{ClientEvent, ParamClient, ParamServer};
use rtcan::pubsub::param::{ParamSpec, Params, Refused, Reply, Request, Value};
use rtcan::pubsub::param_store::{Found, ParamStore};
use rtcan_board_qemu::{check, pass};

/// Bus index of the serving module.
const MODULE: u8 = 2;
const MS: u64 = 1_000_000;

static SPECS: [ParamSpec; 3] = [
    ParamSpec {
        name: "motor.kp",
        default: Value::F32(0.04),
        min: Value::F32(0.0),
        max: Value::F32(1.0),
        unit: "duty/(rad/s)",
        persist: true,
    },
    ParamSpec {
        name: "motor.log_every",
        default: Value::U32(10),
        min: Value::U32(1),
        max: Value::U32(1000),
        unit: "cycles",
        persist: false,
    },
    ParamSpec {
        name: "motor.enabled",
        default: Value::Bool(true),
        min: Value::Bool(false),
        max: Value::Bool(true),
        unit: "",
        persist: true,
    },
];

type Store = ParamStore<F103Flash<2>, 3>;

/// One request through the channel: client → request frame → server (serve, persist)
/// → reply frame → client. Returns the reply and the two frames.
fn exchange(
    client: &mut ParamClient,
    server: &mut ParamServer,
    params: &mut Params<3>,
    store: &mut Store,
    req: Request,
    now: u64,
) -> (Option<ClientEvent>, Frame, Frame) {
    check!(
        client.request(MODULE, req, now).is_ok(),
        "request {:?}",
        req
    );
    let Some(request) = client.next_frame() else {
        check!(false, "no request frame");
        unreachable!()
    };
    client.sent();
    let mine = server.on_frame(&request, |bytes| {
        params.serve(bytes, &mut |i, bits| store.write(i, bits).is_ok())
    });
    check!(mine, "the server takes its own request");
    let Some(reply) = server.next() else {
        check!(false, "no reply frame");
        unreachable!()
    };
    server.sent();
    (client.on_frame(&reply, now + MS), request, reply)
}

#[entry]
fn main() -> ! {
    let (mut store, found) = Store::open(F103Flash::default());
    check!(found == Found::Empty, "fresh flash: {:?}", found);
    let mut params = Params::new(&SPECS);
    let mut server = ParamServer::new(MODULE);
    let mut client = ParamClient::new(50 * MS);

    // A set of kp: the exact frames (NRT, message ID 0xFF00 + m / 0xFF40 + m).
    let (ev, req, rep) = exchange(
        &mut client,
        &mut server,
        &mut params,
        &mut store,
        Request::Set {
            index: 0,
            bits: 0.8f32.to_bits(),
        },
        0,
    );
    check!(
        req.id().raw() == (63 << 23) | ((0xFF00 + u32::from(MODULE)) << 7),
        "request ID {:#x}",
        req.id().raw()
    );
    let b = 0.8f32.to_bits().to_le_bytes();
    check!(
        req.data() == [2, 0, 0, 0, b[0], b[1], b[2], b[3]],
        "request bytes {:?}",
        req.data()
    );
    check!(
        rep.id().raw() == (63 << 23) | ((0xFF40 + u32::from(MODULE)) << 7),
        "reply ID {:#x}",
        rep.id().raw()
    );
    check!(
        rep.data() == [0, 3, 0, 0, b[0], b[1], b[2], b[3]],
        "reply bytes {:?}",
        rep.data()
    );
    check!(
        ev == Some(ClientEvent::Reply {
            module: MODULE,
            reply: Reply::Value {
                index: 0,
                bits: 0.8f32.to_bits(),
                count: 3
            }
        }),
        "{:?}",
        ev
    );
    check!(params.f32(0) == Some(0.8), "kp applied");

    // Refusals: out of range, NaN, a bool other than 0/1, an unknown index; nothing
    // applied, each counted.
    for (req, why) in [
        (
            Request::Set {
                index: 0,
                bits: 1.5f32.to_bits(),
            },
            Refused::OutOfRange,
        ),
        (
            Request::Set {
                index: 0,
                bits: f32::NAN.to_bits(),
            },
            Refused::BadValue,
        ),
        (Request::Set { index: 1, bits: 0 }, Refused::OutOfRange),
        (Request::Set { index: 2, bits: 2 }, Refused::BadValue),
        (Request::Get { index: 3 }, Refused::Unknown),
    ] {
        let (ev, _, _) = exchange(
            &mut client,
            &mut server,
            &mut params,
            &mut store,
            req,
            10 * MS,
        );
        let index = req.index();
        check!(
            ev == Some(ClientEvent::Reply {
                module: MODULE,
                reply: Reply::Refused { index, why }
            }),
            "{:?} -> {:?}",
            req,
            ev
        );
    }
    check!(
        params.f32(0) == Some(0.8),
        "a refused value is never applied"
    );
    check!(params.refused == 5, "refused {}", params.refused);

    // Not persisted: log_every; persisted: enabled = false; then 300 more kp writes,
    // which wrap the log over both pages (compaction).
    let sets = [
        Request::Set {
            index: 1,
            bits: 100,
        },
        Request::Set { index: 2, bits: 0 },
    ];
    for req in sets {
        let (ev, _, _) = exchange(
            &mut client,
            &mut server,
            &mut params,
            &mut store,
            req,
            20 * MS,
        );
        check!(
            matches!(
                ev,
                Some(ClientEvent::Reply {
                    reply: Reply::Value { .. },
                    ..
                })
            ),
            "{:?}",
            ev
        );
    }
    let mut last = 0.0f32;
    for i in 0..300u32 {
        last = (i % 100) as f32 / 100.0;
        let (ev, _, _) = exchange(
            &mut client,
            &mut server,
            &mut params,
            &mut store,
            Request::Set {
                index: 0,
                bits: last.to_bits(),
            },
            u64::from(i) * MS,
        );
        check!(ev.is_some(), "write {}", i);
    }

    // A request to a module that does not answer: timed out exactly at its deadline.
    check!(
        client
            .request(MODULE + 1, Request::Get { index: 0 }, 1_000 * MS)
            .is_ok(),
        "request"
    );
    client.sent();
    check!(
        client.poll(1_050 * MS - 1).is_none(),
        "not before the deadline"
    );
    check!(
        client.poll(1_050 * MS)
            == Some(ClientEvent::TimedOut {
                module: MODULE + 1,
                request: Request::Get { index: 0 }
            }),
        "timed out at the deadline"
    );

    // "Reset": the store reopened from the same flash, the table back to its defaults
    // and loaded from it: the persisted values are back, the other at its default.
    let (store, found) = Store::open(store.into_flash());
    check!(found == Found::Ok, "reopened: {:?}", found);
    let mut params = Params::new(&SPECS);
    let loaded = params.load(store.values());
    check!(loaded == 2, "loaded {}", loaded);
    check!(params.f32(0) == Some(last), "kp {:?}", params.get(0));
    check!(
        params.get(1) == Some(Value::U32(10)),
        "log_every {:?}",
        params.get(1)
    );
    check!(
        params.get(2) == Some(Value::Bool(false)),
        "enabled {:?}",
        params.get(2)
    );
    check!(
        server.stats.requests == 308 && client.stats.timeouts == 1,
        "{:?} {:?}",
        server.stats,
        client.stats
    );
    hprintln!("PASS param_exchange");
    pass()
}
