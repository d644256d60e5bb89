//! The generated service handles (rtcan-codegen `services.rs`) of robots/services.toml:
//! `plan_status` is local (client `logger` and server `planner` both on `head`), so a
//! call, its answer and its timeout run here without a bus; `scan` goes on the bus
//! (its request is queued for the engine).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
use rtcan::pubsub::service::{CallError, CallId, Event};
use rtcan::pubsub::Message;

mod svc {
    rtcan::robot!("robots/services.toml");
}
use svc::head::services::{PlanStatusClient, PlanStatusServer, ScanClient};
use svc::sonar::services::ScanServer;

const MS: u64 = 1_000_000;

/// Runs `f` to completion on this thread (its waits are ready futures).
fn block_on<F: std::future::Future>(f: F) -> F::Output {
    let mut f = std::pin::pin!(f);
    let mut cx = std::task::Context::from_waker(std::task::Waker::noop());
    loop {
        if let std::task::Poll::Ready(v) = f.as_mut().poll(&mut cx) {
            return v;
        }
    }
}

/// The statics are per process: one test function runs the local service.
#[test]
fn local_service_calls_answers_times_out_and_refuses() {
    svc::reset();
    assert_eq!(PlanStatusClient::TIMEOUT_NS, 4 * MS);
    assert_eq!(PlanStatusClient::IN_FLIGHT, 2);
    let mut client = PlanStatusClient::new();
    let mut server = PlanStatusServer::new();
    // A call and its answer.
    let a = client.call(10 * MS, &svc::PlanStatusRequest {}).unwrap();
    assert_eq!(a, CallId(0));
    assert_eq!(client.next_deadline(), Some(14 * MS));
    let answered = server.serve(11 * MS, |_req| svc::PlanStatusReply {
        busy: true,
        goals: 3,
    });
    assert_eq!(answered, 1);
    assert_eq!(
        client.poll(11 * MS),
        Some(Event::Reply(
            a,
            svc::PlanStatusReply {
                busy: true,
                goals: 3
            }
        ))
    );
    assert_eq!(client.poll(11 * MS), None);
    // Two in flight, the third refused.
    let b = client.call(20 * MS, &svc::PlanStatusRequest {}).unwrap();
    let c = client.call(21 * MS, &svc::PlanStatusRequest {}).unwrap();
    assert_eq!(
        client.call(21 * MS, &svc::PlanStatusRequest {}),
        Err(CallError::Busy)
    );
    // No answer: each times out exactly at call + 4 ms, the earliest first.
    assert_eq!(client.poll(24 * MS - 1), None);
    assert_eq!(client.poll(24 * MS), Some(Event::TimedOut(b)));
    assert_eq!(client.poll(25 * MS), Some(Event::TimedOut(c)));
    // The server answers both now: too late, counted, not delivered.
    assert_eq!(
        server.serve(26 * MS, |_| svc::PlanStatusReply {
            busy: false,
            goals: 0
        }),
        2
    );
    assert_eq!(client.poll(26 * MS), None);
    let k = client.counters();
    assert_eq!(
        (k.calls, k.replies, k.timeouts, k.late_or_unknown, k.busy),
        (3, 1, 2, 2, 1)
    );
    assert!(!client.server_absent());
    let d = client.call(30 * MS, &svc::PlanStatusRequest {}).unwrap();
    assert_eq!(client.poll(34 * MS), Some(Event::TimedOut(d)));
    assert!(client.server_absent(), "three timeouts in a row");
    assert_eq!(server.served, 3);

    // The async call: answered by the server while the caller waits (the `wait` closure
    // stands in for the other task running and the clock advancing 1 ms per wait).
    let clock = std::cell::Cell::new(40 * MS);
    let waits = std::cell::Cell::new(0u32);
    let mut client = PlanStatusClient::new();
    let mut server = PlanStatusServer::new();
    let reply = block_on(client.call_async(
        &svc::PlanStatusRequest {},
        || clock.get(),
        |until| {
            assert_eq!(
                until,
                44 * MS,
                "waits until the call's deadline at the latest"
            );
            waits.set(waits.get() + 1);
            clock.set(clock.get() + MS);
            if waits.get() == 2 {
                server.serve(clock.get(), |_| svc::PlanStatusReply {
                    busy: false,
                    goals: 7,
                });
            }
            std::future::ready(())
        },
    ));
    assert_eq!(
        reply,
        Ok(svc::PlanStatusReply {
            busy: false,
            goals: 7
        })
    );
    assert_eq!((waits.get(), clock.get()), (2, 42 * MS));
    // No server: `TimedOut` exactly at call + 4 ms.
    let reply = block_on(client.call_async(
        &svc::PlanStatusRequest {},
        || clock.get(),
        |until| {
            clock.set(until);
            std::future::ready(())
        },
    ));
    assert_eq!(reply, Err(CallError::TimedOut));
    assert_eq!(clock.get(), 46 * MS);
    // Another call in flight: refused, not stolen.
    let other = client.call(50 * MS, &svc::PlanStatusRequest {}).unwrap();
    let reply = block_on(client.call_async(
        &svc::PlanStatusRequest {},
        || 50 * MS,
        |_| std::future::ready(()),
    ));
    assert_eq!(reply, Err(CallError::Busy));
    assert_eq!(client.poll(54 * MS), Some(Event::TimedOut(other)));
    svc::reset();
}

#[test]
fn bus_service_frames_are_the_call_number_then_the_payload() {
    // Frame types: `call: u16` then the payload's fields, little-endian, packed.
    let f = svc::ScanRequestFrame {
        call: 0x0102,
        sensor: 7,
        samples: 0x0304,
    };
    let mut b = [0u8; 5];
    f.encode(&mut b);
    assert_eq!(b, [0x02, 0x01, 7, 0x04, 0x03]);
    assert_eq!(<svc::ScanReplyFrame as Message>::SIZE, 2 + 1 + 8 + 1);
    assert_eq!(ScanClient::TIMEOUT_NS, 30 * MS);
    assert_eq!(ScanClient::IN_FLIGHT, 3);
    // The message IDs are the plan's: after `level` (0x0140), reply then request.
    assert_eq!(svc::topics::SCAN_REPLY.msg_id.0, 0x0141);
    assert_eq!(svc::topics::SCAN_REQUEST.msg_id.0, 0x0142);
    assert_eq!(svc::topics::SCAN_REQUEST.class, rtcan::core::Class::Srt);
    let _ = ScanServer::new();
}
