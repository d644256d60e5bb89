//! Parameters over the bus (docs/SERVICES.md §2, docs/PROTOCOL.md §2.3): the 8-byte
//! requests and replies of [`super::Request`]/[`super::Reply`] as single NRT frames on the
//! reserved parameter channel — request to module `m` on message ID `0xFF00 + m`, its
//! reply on `0xFF40 + m`, fragment field 0, DLC 8. The engine routes the channel to the
//! module's host (`Host::service_rx`/`service_tx`/`service_sent`); this file is what the
//! host does with it: [`ParamServer`] on the module that owns the parameters (a firmware
//! image's code: no heap, a fixed reply queue), [`ParamClient`] on the node that asks (the
//! gateway for the PC, or any module), one request in flight with a timeout.
use rtcan_core::id::{CanId, LAXITY_NRT};
use rtcan_core::service::{param_reply_id, param_request_id, PARAM_REP_BASE};
use rtcan_core::{Frame, Nanos};

use super::{Reply, Request};

/// Replies a server holds until the engine has sent them; a request arriving with the
/// queue full is dropped and counted (the asker times out). One client keeps one request
/// in flight, so 4 leaves room for several askers.
pub const REPLY_QUEUE: usize = 4;

/// The frame of `req` to `module`; `None` for `module >= 64`.
pub fn request_frame(module: u8, req: Request) -> Option<Frame> {
    let id = CanId::new(LAXITY_NRT, param_request_id(module)?, 0)?;
    Frame::new(id, &req.encode())
}

/// The frame of `module`'s reply `rep`; `None` for `module >= 64`.
pub fn reply_frame(module: u8, rep: Reply) -> Option<Frame> {
    let id = CanId::new(LAXITY_NRT, param_reply_id(module)?, 0)?;
    Frame::new(id, &rep.encode())
}

/// The sender and reply of a parameter-reply frame; `None` for any other frame or a
/// malformed reply (not NRT, a fragment other than 0, not 8 bytes, unknown status).
pub fn parse_reply(frame: &Frame) -> Option<(u8, Reply)> {
    let id = frame.id();
    let msg = id.msg_id().0;
    if id.laxity() != LAXITY_NRT || id.fragment() != 0 {
        return None;
    }
    let module = u8::try_from(msg.checked_sub(PARAM_REP_BASE)?).ok()?;
    if param_reply_id(module)?.0 != msg {
        return None;
    }
    Some((module, Reply::decode(frame.data())?))
}

/// A server's counters (nothing is dropped silently).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ServerStats {
    /// Requests answered (refusals included).
    pub requests: u32,
    /// Frames on this module's request ID that are not a single NRT frame: ignored.
    pub malformed: u32,
    /// Requests dropped because the reply queue was full.
    pub overflow: u32,
}

/// The module side: answers the requests addressed to `module` with the module's own
/// parameter code (`Params::serve` or [`super::serve`]) and queues the reply frames for
/// the engine.
#[derive(Clone, Debug)]
pub struct ParamServer {
    module: u8,
    queue: [Option<Frame>; REPLY_QUEUE],
    head: usize,
    len: usize,
    pub stats: ServerStats,
}

impl ParamServer {
    /// The server of bus module `module`.
    pub const fn new(module: u8) -> Self {
        ParamServer {
            module,
            queue: [None; REPLY_QUEUE],
            head: 0,
            len: 0,
            stats: ServerStats {
                requests: 0,
                malformed: 0,
                overflow: 0,
            },
        }
    }

    /// A frame of the host range (`Host::service_rx`). Returns whether it was addressed
    /// to this server (the caller hands other frames to other channels). A request is
    /// answered by `serve` (given the 8 request bytes; a wrong length is its
    /// `BadRequest`), the reply queued.
    pub fn on_frame(&mut self, frame: &Frame, serve: impl FnOnce(&[u8]) -> Reply) -> bool {
        let id = frame.id();
        if param_request_id(self.module) != Some(id.msg_id()) {
            return false;
        }
        // A parameter request is one NRT frame; anything else on the ID is not one (a
        // stray fragment would otherwise be answered as a request).
        if id.laxity() != LAXITY_NRT || id.fragment() != 0 {
            self.stats.malformed = self.stats.malformed.saturating_add(1);
            return true;
        }
        if self.len >= REPLY_QUEUE {
            self.stats.overflow = self.stats.overflow.saturating_add(1);
            return true;
        }
        self.stats.requests = self.stats.requests.saturating_add(1);
        let reply = serve(frame.data());
        if let Some(f) = reply_frame(self.module, reply) {
            let at = (self.head + self.len) % REPLY_QUEUE;
            if let Some(slot) = self.queue.get_mut(at) {
                *slot = Some(f);
                self.len += 1;
            }
        }
        true
    }

    /// The oldest reply not yet sent (`Host::service_tx`: the same frame until `sent`).
    pub fn next(&self) -> Option<Frame> {
        if self.len == 0 {
            return None;
        }
        self.queue.get(self.head).copied().flatten()
    }

    /// The frame `next` returned was sent (`Host::service_sent`).
    pub fn sent(&mut self) {
        if self.len == 0 {
            return;
        }
        if let Some(slot) = self.queue.get_mut(self.head) {
            *slot = None;
        }
        self.head = (self.head + 1) % REPLY_QUEUE;
        self.len -= 1;
    }
}

/// What became of a client's request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ClientEvent {
    /// The module answered (a value, or a refusal with its reason).
    Reply { module: u8, reply: Reply },
    /// No reply within the timeout: the module is absent, not running, or the request
    /// or reply was lost.
    TimedOut { module: u8, request: Request },
}

/// Why a request was not started.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ClientError {
    /// A request is in flight.
    Busy,
    /// No module with this number on the channel (`module >= 64`).
    NoSuchModule,
}

/// A client's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ClientStats {
    pub requests: u32,
    pub replies: u32,
    pub timeouts: u32,
    /// Replies that match no request in flight (late after a timeout, another asker's).
    pub unmatched: u32,
}

/// The asking side: one request in flight, answered by the matching reply (same module,
/// same parameter index) before `now + timeout`, else timed out.
#[derive(Clone, Debug)]
pub struct ParamClient {
    timeout_ns: Nanos,
    /// Module, request, deadline.
    pending: Option<(u8, Request, Nanos)>,
    /// The request frame until the engine has sent it.
    to_send: Option<Frame>,
    pub stats: ClientStats,
}

impl ParamClient {
    /// A client that waits `timeout_ns` for each reply (from the request, so the time
    /// the request waits for a free window counts).
    pub const fn new(timeout_ns: Nanos) -> Self {
        ParamClient {
            timeout_ns,
            pending: None,
            to_send: None,
            stats: ClientStats {
                requests: 0,
                replies: 0,
                timeouts: 0,
                unmatched: 0,
            },
        }
    }

    /// A request is in flight.
    pub fn busy(&self) -> bool {
        self.pending.is_some()
    }

    /// The deadline of the request in flight.
    pub fn deadline(&self) -> Option<Nanos> {
        self.pending.map(|(_, _, d)| d)
    }

    /// Sends `req` to `module` at `now`; `Busy` while a request is in flight or the
    /// last request frame is still unsent.
    pub fn request(&mut self, module: u8, req: Request, now: Nanos) -> Result<(), ClientError> {
        if self.pending.is_some() || self.to_send.is_some() {
            return Err(ClientError::Busy);
        }
        let frame = request_frame(module, req).ok_or(ClientError::NoSuchModule)?;
        self.pending = Some((module, req, now.saturating_add(self.timeout_ns)));
        self.to_send = Some(frame);
        self.stats.requests = self.stats.requests.saturating_add(1);
        Ok(())
    }

    /// How long the client waits for a reply.
    pub fn timeout_ns(&self) -> Nanos {
        self.timeout_ns
    }

    /// The request frame to send (`Host::service_tx`: the same frame until `sent`).
    pub fn next_frame(&self) -> Option<Frame> {
        self.to_send
    }

    /// The frame `next_frame` returned was sent.
    pub fn sent(&mut self) {
        self.to_send = None;
    }

    /// A frame of the host range; the reply to the request in flight if it is one.
    pub fn on_frame(&mut self, frame: &Frame, now: Nanos) -> Option<ClientEvent> {
        let (module, reply) = parse_reply(frame)?;
        let index = match reply {
            Reply::Value { index, .. } | Reply::Refused { index, .. } => index,
        };
        match self.pending {
            Some((m, req, deadline)) if m == module && req.index() == index && now < deadline => {
                self.pending = None;
                self.to_send = None;
                self.stats.replies = self.stats.replies.saturating_add(1);
                Some(ClientEvent::Reply { module, reply })
            }
            _ => {
                self.stats.unmatched = self.stats.unmatched.saturating_add(1);
                None
            }
        }
    }

    /// The request in flight timed out at `now`. A frame not yet sent stays offered: the
    /// engine may hold it in a mailbox already (`Host::service_tx` offers a frame
    /// unchanged until it is sent); its late reply is unmatched.
    pub fn poll(&mut self, now: Nanos) -> Option<ClientEvent> {
        let (module, request, deadline) = self.pending?;
        if now < deadline {
            return None;
        }
        self.pending = None;
        self.stats.timeouts = self.stats.timeouts.saturating_add(1);
        Some(ClientEvent::TimedOut { module, request })
    }
}

#[cfg(test)]
mod tests {
    use super::super::{serve, ParamSpec, Refused, Value};
    use super::*;

    static SPECS: [ParamSpec; 2] = [
        ParamSpec {
            name: "",
            default: Value::F32(0.04),
            min: Value::F32(0.0),
            max: Value::F32(1.0),
            unit: "",
            persist: false,
        },
        ParamSpec {
            name: "",
            default: Value::U32(10),
            min: Value::U32(1),
            max: Value::U32(1000),
            unit: "",
            persist: false,
        },
    ];

    fn nrt(msg: u16, field: u8, data: &[u8]) -> Frame {
        Frame::new(
            CanId::new(LAXITY_NRT, rtcan_core::MsgId(msg), field).unwrap(),
            data,
        )
        .unwrap()
    }

    #[test]
    fn exact_frames_of_a_get_and_a_set() {
        let get = request_frame(1, Request::Get { index: 0 }).unwrap();
        assert_eq!(get.id().raw(), 0x1FFF_8080);
        assert_eq!(get.data(), &[1, 0, 0, 0, 0, 0, 0, 0]);
        let set = request_frame(4, Request::Set { index: 1, bits: 20 }).unwrap();
        assert_eq!(set.id().raw(), 0x1FFF_8200);
        assert_eq!(set.data(), &[2, 0, 1, 0, 20, 0, 0, 0]);
        let rep = reply_frame(
            1,
            Reply::Value {
                index: 0,
                bits: 0.04f32.to_bits(),
                count: 2,
            },
        )
        .unwrap();
        assert_eq!(rep.id().raw(), 0x1FFF_A080);
        assert_eq!(rep.data(), &[0, 2, 0, 0, 0x0A, 0xD7, 0x23, 0x3D]);
        assert_eq!(
            parse_reply(&rep),
            Some((
                1,
                Reply::Value {
                    index: 0,
                    bits: 0.04f32.to_bits(),
                    count: 2
                }
            ))
        );
        assert_eq!(request_frame(64, Request::Get { index: 0 }), None);
        // Not replies: a request, an update reply, a fragment, bad status.
        assert_eq!(parse_reply(&get), None);
        assert_eq!(parse_reply(&nrt(0xFFC1, 0, &[1, 0])), None);
        assert_eq!(parse_reply(&nrt(0xFF41, 1, rep.data())), None);
        assert_eq!(
            parse_reply(&nrt(0xFF41, 0, &[9, 0, 0, 0, 0, 0, 0, 0])),
            None
        );
    }

    #[test]
    fn server_answers_its_own_requests_refuses_bad_values_and_counts() {
        let mut s = ParamServer::new(1);
        let mut values = [0.04f32.to_bits(), 10];
        let mut refused = 0u32;
        // Another module's request, an update frame: not ours.
        let other = request_frame(2, Request::Get { index: 0 }).unwrap();
        assert!(!s.on_frame(&other, |_| unreachable!()));
        assert!(!s.on_frame(&nrt(0xFF81, 31, &[0; 8]), |_| unreachable!()));
        // Set kp = 3.0: out of range, refused, not applied.
        let bad = request_frame(
            1,
            Request::Set {
                index: 0,
                bits: 3.0f32.to_bits(),
            },
        )
        .unwrap();
        assert!(s.on_frame(&bad, |r| serve(
            &SPECS,
            &mut values,
            &mut refused,
            r,
            &mut |_, _| true
        )));
        assert_eq!(values[0], 0.04f32.to_bits());
        assert_eq!(refused, 1);
        let f = s.next().unwrap();
        assert_eq!(f.id().raw(), 0x1FFF_A080);
        assert_eq!(f.data(), &[2, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(s.next(), Some(f), "offered again until sent");
        s.sent();
        assert_eq!(s.next(), None);
        // A fragment on the request ID: ignored, counted.
        assert!(s.on_frame(&nrt(0xFF01, 3, &[1, 0, 0, 0, 0, 0, 0, 0]), |_| {
            unreachable!()
        }));
        assert_eq!(s.stats.malformed, 1);
        // A short request: answered BadRequest.
        let mut r = 0;
        let mut srv = |req: &[u8]| serve(&SPECS, &mut values, &mut r, req, &mut |_, _| true);
        assert!(s.on_frame(&nrt(0xFF01, 0, &[1, 0, 0]), &mut srv));
        assert_eq!(s.next().unwrap().data(), &[4, 0, 0, 0, 0, 0, 0, 0]);
        // Queue full: 4 replies held, the 5th request dropped and counted.
        let get = request_frame(1, Request::Get { index: 1 }).unwrap();
        for _ in 0..4 {
            assert!(s.on_frame(&get, &mut srv));
        }
        assert_eq!(s.stats.overflow, 1);
        assert_eq!(s.stats.requests, 5);
        let mut n = 0;
        while s.next().is_some() {
            s.sent();
            n += 1;
        }
        assert_eq!(n, 4);
    }

    #[test]
    fn client_matches_its_reply_and_times_out() {
        let mut c = ParamClient::new(50_000_000);
        c.request(1, Request::Get { index: 0 }, 1_000).unwrap();
        assert_eq!(
            c.request(2, Request::Get { index: 0 }, 1_000),
            Err(ClientError::Busy)
        );
        let f = c.next_frame().unwrap();
        assert_eq!(f.id().raw(), 0x1FFF_8080);
        c.sent();
        assert_eq!(c.next_frame(), None);
        // Another module's reply, another index: unmatched.
        let r2 = reply_frame(
            2,
            Reply::Value {
                index: 0,
                bits: 1,
                count: 1,
            },
        )
        .unwrap();
        assert_eq!(c.on_frame(&r2, 2_000), None);
        let r1 = reply_frame(
            1,
            Reply::Refused {
                index: 0,
                why: Refused::OutOfRange,
            },
        )
        .unwrap();
        assert_eq!(
            c.on_frame(&r1, 3_000),
            Some(ClientEvent::Reply {
                module: 1,
                reply: Reply::Refused {
                    index: 0,
                    why: Refused::OutOfRange
                }
            })
        );
        assert!(!c.busy());
        // Absent module: nothing comes; the timeout is exact.
        c.request(5, Request::List { index: 0 }, 10_000).unwrap();
        let f5 = c.next_frame().unwrap();
        assert_eq!(c.poll(50_009_999), None);
        assert_eq!(
            c.poll(50_010_000),
            Some(ClientEvent::TimedOut {
                module: 5,
                request: Request::List { index: 0 }
            })
        );
        // Never sent (a busy bus): still offered, unchanged, and nothing new until sent.
        assert_eq!(c.next_frame(), Some(f5));
        assert_eq!(
            c.request(5, Request::Get { index: 0 }, 50_010_000),
            Err(ClientError::Busy)
        );
        c.sent();
        // Its late reply is unmatched.
        let late = reply_frame(
            5,
            Reply::Value {
                index: 0,
                bits: 0,
                count: 1,
            },
        )
        .unwrap();
        assert_eq!(c.on_frame(&late, 60_000_000), None);
        assert_eq!(
            c.stats,
            ClientStats {
                requests: 2,
                replies: 1,
                timeouts: 1,
                unmatched: 2
            }
        );
        assert_eq!(
            c.request(64, Request::Get { index: 0 }, 0),
            Err(ClientError::NoSuchModule)
        );
    }
}
