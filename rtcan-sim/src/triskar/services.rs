//! The `proximity_read` service of robot.toml on the simulated Triskar2: the proximity
//! module serves it with the generated `ProximityReadServer` (its rangers read from the
//! plant), the gateway calls it with the generated `ProximityReadClient` on a script
//! (period, calls per period); requests and replies are SRT frames on the simulated bus
//! with the service's deadline, planned like every topic.
//!
//! Every call is logged with its local times (the client's clock: timeouts are counted
//! on it) and global times (latency), and every answer the server gave, so a test can
//! match replies to the readings they carry. A lost reply is injected as the gateway's
//! controller losing that reply frame (`ServiceScript::lose_replies`, by call number).
use rtcan::core::{Frame, Nanos};
use rtcan::pubsub::service::{CallError, ClientCounters, Event};
use rtcan::pubsub::Message;
use rtcan::robot_toml as robot;

use super::module::Shared;

/// What the gateway's client does.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ServiceScript {
    /// Call `proximity_read` this often (global ns); `None`: never.
    pub period_ns: Option<Nanos>,
    /// Calls started together each period (concurrent calls), for sensors 0, 1, 2, ...
    /// (sensor `k % 5`: 4 is no ranger, answered with `NO_RANGER`).
    pub burst: usize,
    /// First calls at this global time.
    pub from_ns: Nanos,
    /// Call numbers whose reply frame the gateway's controller loses.
    pub lose_replies: Vec<u16>,
    /// One call with exactly this request payload (robot.toml field order, little-endian:
    /// `rtcan call`) instead of the periodic calls.
    pub request: Option<Vec<u8>>,
}

impl ServiceScript {
    /// What `rtcan sim` runs: one call per period of the service's declared `rate`
    /// (10 Hz when it has none) from 1 s on, one at a time.
    pub fn from_plan(plan: &rtcan_model::Plan) -> ServiceScript {
        let hz = plan
            .service("proximity_read")
            .and_then(|s| s.rate_hz)
            .filter(|h| *h > 0.0)
            .unwrap_or(10.0);
        ServiceScript {
            period_ns: Some((1e9 / hz).round().max(1.0) as Nanos),
            burst: 1,
            from_ns: 1_000_000_000,
            lose_replies: Vec::new(),
            request: None,
        }
    }
}

/// `"services":{"proximity_read":{...}}` members of the `rtcan sim --json` report.
pub fn json(log: &ServiceLog) -> String {
    let f = log.figures();
    format!(
        "{{\"{}\":{{\"calls\":{},\"replies\":{},\"timeouts\":{},\"late\":{},\"busy\":{},\"server_absent\":{},\"latency_max_ns\":{},\"latency_mean_ns\":{}}}}}",
        f.name,
        f.calls,
        f.replies,
        f.timeouts,
        f.late,
        log.counters.busy,
        f.server_absent,
        f.latency_max_ns,
        f.latency_mean_ns
    )
}

/// One line of the text report.
pub fn text(log: &ServiceLog) -> String {
    let f = log.figures();
    format!(
        "service {}: {} calls, {} replies, {} timeouts, {} late{}; call latency max {:.1} us, mean {:.1} us",
        f.name,
        f.calls,
        f.replies,
        f.timeouts,
        f.late,
        if f.server_absent { ", server absent" } else { "" },
        f.latency_max_ns as f64 / 1e3,
        f.latency_mean_ns as f64 / 1e3
    )
}

/// Reply of `proximity_read` for a sensor the module does not have.
pub const NO_RANGER: u16 = u16::MAX;

/// What became of one call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// No reply, no timeout yet (or the client rebooted before either).
    Pending,
    /// `sensor` and `range_mm` as the reply carried them, at these times.
    Replied {
        local_ns: Nanos,
        global_ns: Nanos,
        sensor: u8,
        range_mm: u16,
    },
    /// Timed out at these times.
    TimedOut { local_ns: Nanos, global_ns: Nanos },
    /// The request could not be queued or the client was busy.
    Refused(CallError),
}

/// One call the gateway made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Call {
    /// Call number (`None` when refused before it got one).
    pub call: Option<u16>,
    pub sensor: u8,
    pub local_ns: Nanos,
    pub global_ns: Nanos,
    pub outcome: Outcome,
}

/// One request the proximity module answered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Served {
    pub sensor: u8,
    pub range_mm: u16,
    pub global_ns: Nanos,
}

/// Everything the service did in one run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ServiceLog {
    pub script: ServiceScript,
    pub calls: Vec<Call>,
    pub served: Vec<Served>,
    /// The client's counters at the end (of its last boot).
    pub counters: ClientCounters,
    /// Global time the client first reported the server absent.
    pub absent_at: Option<Nanos>,
    /// Reply frames the gateway's controller lost on purpose.
    pub lost_frames: u32,
    /// Every reply delivered: call number and the reply payload's wire bytes.
    pub replies: Vec<(u16, Vec<u8>)>,
}

/// The `services` figures of `rtcan sim --json`.
#[derive(Clone, Debug, PartialEq)]
pub struct ServiceFigures {
    pub name: &'static str,
    pub calls: u32,
    pub replies: u32,
    pub timeouts: u32,
    /// Replies after their call's deadline (or unknown): counted, not delivered.
    pub late: u32,
    pub server_absent: bool,
    /// Call → reply on the bus's global time, over the replied calls.
    pub latency_max_ns: Nanos,
    pub latency_mean_ns: Nanos,
}

impl ServiceLog {
    /// The figures of the run.
    pub fn figures(&self) -> ServiceFigures {
        let lat: Vec<Nanos> = self
            .calls
            .iter()
            .filter_map(|c| match c.outcome {
                Outcome::Replied { global_ns, .. } => Some(global_ns.saturating_sub(c.global_ns)),
                _ => None,
            })
            .collect();
        ServiceFigures {
            name: "proximity_read",
            calls: self.counters.calls,
            replies: self.counters.replies,
            timeouts: self.counters.timeouts,
            late: self.counters.late_or_unknown,
            server_absent: self.absent_at.is_some(),
            latency_max_ns: lat.iter().copied().max().unwrap_or(0),
            latency_mean_ns: if lat.is_empty() {
                0
            } else {
                lat.iter().sum::<Nanos>() / lat.len() as Nanos
            },
        }
    }
}

/// A module's part in a service, run after its app each time the module runs.
pub trait ServiceHook {
    /// Local time `now`, global `global`; returns the next local time it must run at.
    fn poll(&mut self, now: Nanos, global: Nanos, shared: &mut Shared) -> Option<Nanos>;
    /// A frame the controller received: true if it is lost (never reaches the engine).
    fn lose(&mut self, _frame: &Frame, _shared: &mut Shared) -> bool {
        false
    }
    /// The module booted again: its service state is back to power-on.
    fn reboot(&mut self, _shared: &mut Shared) {}
}

/// The proximity module: `ProximityReadServer` answering from the plant's rangers.
#[derive(Default)]
pub struct Server {
    inner: robot::proximity::services::ProximityReadServer,
}

impl ServiceHook for Server {
    fn poll(&mut self, now: Nanos, global: Nanos, shared: &mut Shared) -> Option<Nanos> {
        let physics = &mut shared.physics;
        let served = &mut shared.services.served;
        self.inner.serve(now, |req| {
            // Read only when asked: a measurement draws the rangers' noise.
            let range_mm = physics
                .ranges_m()
                .get(usize::from(req.sensor))
                .map_or(NO_RANGER, |m| {
                    (f64::from(*m) * 1000.0).round().clamp(0.0, 65534.0) as u16
                });
            served.push(Served {
                sensor: req.sensor,
                range_mm,
                global_ns: global,
            });
            robot::ProximityReadReply {
                sensor: req.sensor,
                range_mm,
            }
        });
        None
    }
}

/// The gateway: `ProximityReadClient` on the script of `Shared::services`.
#[derive(Default)]
pub struct Caller {
    client: robot::gateway::services::ProximityReadClient,
    next_call: Option<Nanos>,
    sent: u32,
}

impl Caller {
    fn record(&mut self, shared: &mut Shared, now: Nanos, global: Nanos) {
        while let Some(ev) = self.client.poll(now) {
            let (id, outcome) = match ev {
                Event::Reply(id, r) => {
                    let mut bytes = vec![0u8; <robot::ProximityReadReply as Message>::SIZE];
                    r.encode(&mut bytes);
                    shared.services.replies.push((id.0, bytes));
                    (
                        id,
                        Outcome::Replied {
                            local_ns: now,
                            global_ns: global,
                            sensor: r.sensor,
                            range_mm: r.range_mm,
                        },
                    )
                }
                Event::TimedOut(id) => (
                    id,
                    Outcome::TimedOut {
                        local_ns: now,
                        global_ns: global,
                    },
                ),
            };
            let log = &mut shared.services;
            if let Some(c) = log
                .calls
                .iter_mut()
                .rev()
                .find(|c| c.call == Some(id.0) && c.outcome == Outcome::Pending)
            {
                c.outcome = outcome;
            }
        }
        let log = &mut shared.services;
        log.counters = self.client.counters();
        if self.client.server_absent() && log.absent_at.is_none() {
            log.absent_at = Some(global);
        }
    }
}

impl ServiceHook for Caller {
    fn poll(&mut self, now: Nanos, global: Nanos, shared: &mut Shared) -> Option<Nanos> {
        self.record(shared, now, global);
        let script = shared.services.script.clone();
        let period = script.period_ns?;
        let due = *self.next_call.get_or_insert(script.from_ns);
        let once = script.request.as_deref();
        if global >= due && !(once.is_some() && self.sent > 0) {
            for _ in 0..script.burst.max(1) {
                let asked = once.and_then(<robot::ProximityReadRequest as Message>::decode);
                let req = asked.unwrap_or(robot::ProximityReadRequest {
                    sensor: (self.sent % 5) as u8,
                });
                let sensor = req.sensor;
                self.sent += 1;
                let (call, outcome) = match self.client.call(now, &req) {
                    Ok(id) => (Some(id.0), Outcome::Pending),
                    Err(e) => (None, Outcome::Refused(e)),
                };
                shared.services.calls.push(Call {
                    call,
                    sensor,
                    local_ns: now,
                    global_ns: global,
                    outcome,
                });
            }
            self.next_call = Some(due + period);
            shared.services.counters = self.client.counters();
        }
        // Wake for the next call (converted on this module's clock by the caller: the
        // local and global times differ by drift only) and for the next deadline.
        let to_call = self.next_call.map(|g| now + g.saturating_sub(global));
        [to_call, self.client.next_deadline()]
            .into_iter()
            .flatten()
            .min()
    }

    fn lose(&mut self, frame: &Frame, shared: &mut Shared) -> bool {
        let reply = robot::topics::PROXIMITY_READ_REPLY.msg_id;
        if frame.id().msg_id() != reply {
            return false;
        }
        let call = match frame.data() {
            [a, b, ..] => u16::from_le_bytes([*a, *b]),
            _ => return false,
        };
        let lost = shared.services.script.lose_replies.contains(&call);
        if lost {
            shared.services.lost_frames += 1;
        }
        lost
    }

    fn reboot(&mut self, shared: &mut Shared) {
        // The calls in flight die with the module: they stay `Pending`.
        *self = Caller {
            next_call: self.next_call,
            ..Caller::default()
        };
        shared.services.counters = self.client.counters();
    }
}
