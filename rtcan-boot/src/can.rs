//! The update protocol on the bus (docs/SERVICES.md §4, docs/PROTOCOL.md §2.3): requests
//! to module `m` on message ID `0xFF80 + m`, replies on `0xFFC0 + m`, both NRT (laxity
//! 63). A request is one fragmented transfer of a fixed `REQUEST_BYTES` (32 frames,
//! the largest transfer, §7.1): a length byte, the `Msg` wire form, `0xFF` padding —
//! fixed so the receiver reassembles with the same rules as a topic (`RxState`); a
//! reply is one 8-byte frame (`Reply::encode`).
//!
//! [`Port`] is the module side: attached to the engine through `Host::service_rx` /
//! `service_tx`, it reassembles requests, hands them to the [`Receiver`] writing the
//! flash, and queues the replies. No heap: fixed buffers.
use rtcan_core::fragment::{fragment_count, fragment_data, fragment_field, RxState, RxStep};
use rtcan_core::id::{CanId, LAXITY_NRT};
use rtcan_core::service::{reply_id, request_id, UPDATE_REP_BASE};
use rtcan_core::{Frame, Nanos};
use rtcan_pubsub::flash::Flash;

use crate::update::{Msg, Receiver, Reply};
use crate::Layout;

/// Payload of every request transfer.
pub const REQUEST_BYTES: usize = 256;
/// Frames of one request transfer.
pub const REQUEST_FRAMES: u8 = fragment_count(REQUEST_BYTES);
/// Replies a module holds while the bus is busy (one per outstanding request of the
/// host's window).
pub const REPLY_QUEUE: usize = 8;

/// A request's transfer payload: `[len][msg bytes][0xFF…]`; `None` if it does not fit.
pub fn request_payload(msg: &Msg<'_>) -> Option<[u8; REQUEST_BYTES]> {
    let mut p = [0xFFu8; REQUEST_BYTES];
    let n = msg.encode(p.get_mut(1..)?)?;
    *p.first_mut()? = u8::try_from(n).ok()?;
    Some(p)
}

/// The request frame of `module` for fragment `counter` of transfer `tid`.
pub fn request_frame(
    module: u8,
    tid: u8,
    counter: u8,
    payload: &[u8; REQUEST_BYTES],
) -> Option<Frame> {
    let mut data = [0u8; 8];
    let dlc = fragment_data(payload, counter, &mut data);
    let field = fragment_field(REQUEST_FRAMES, tid, counter);
    Frame::from_parts(
        CanId::new(LAXITY_NRT, request_id(module)?, field)?,
        dlc,
        data,
    )
}

/// `module`'s reply frame.
pub fn reply_frame(module: u8, reply: Reply) -> Option<Frame> {
    Frame::new(
        CanId::new(LAXITY_NRT, reply_id(module)?, 0)?,
        &reply.encode(),
    )
}

/// A reply frame: the module it came from and the reply; `None` for anything else
/// (wrong laxity, range, fragment field or contents).
pub fn parse_reply(frame: &Frame) -> Option<(u8, Reply)> {
    let id = frame.id();
    let msg = id.msg_id().0;
    if id.laxity() != LAXITY_NRT || id.fragment() != 0 || msg < UPDATE_REP_BASE {
        return None;
    }
    let module = u8::try_from(msg - UPDATE_REP_BASE).ok()?;
    Some((module, Reply::decode(frame.data())?))
}

/// Counters of the module's port (nothing lost silently).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PortCounters {
    /// Complete requests handed to the receiver.
    pub requests: u32,
    /// Frames for this module dropped by reassembly (lost or repeated fragments).
    pub frames_dropped: u32,
    /// Replies lost because the reply queue was full.
    pub replies_dropped: u32,
}

/// The module side of the update channel.
pub struct Port<'l> {
    module: u8,
    /// The robot fingerprint this module was built for: a `Begin` for another robot is
    /// refused before anything is erased.
    fingerprint: Option<u32>,
    pub receiver: Receiver<'l>,
    rx: RxState,
    buf: [u8; REQUEST_BYTES],
    /// Replies to send, oldest first (`len` of them from `head`).
    out: [Option<Frame>; REPLY_QUEUE],
    head: usize,
    len: usize,
    pub counters: PortCounters,
}

impl<'l> Port<'l> {
    /// Module `module`'s port; `running`: the slot it booted from (never written).
    pub fn new(module: u8, layout: &'l Layout, running: Option<usize>) -> Self {
        Port {
            module,
            fingerprint: None,
            receiver: Receiver::new(layout, running),
            rx: RxState::default(),
            buf: [0; REQUEST_BYTES],
            out: [None; REPLY_QUEUE],
            head: 0,
            len: 0,
            counters: PortCounters::default(),
        }
    }

    /// Refuse images announced for another robot than `fingerprint` (at `Begin`).
    pub fn with_fingerprint(mut self, fingerprint: u32) -> Self {
        self.fingerprint = Some(fingerprint);
        self
    }

    /// A frame of the update range (`Host::service_rx`). Requests to this module are
    /// reassembled; a complete one is handled (the flash written) and its reply queued.
    /// Returns the reply when there was one.
    pub fn on_frame(&mut self, flash: &mut impl Flash, frame: &Frame, sof: Nanos) -> Option<Reply> {
        let id = frame.id();
        if id.laxity() != LAXITY_NRT || Some(id.msg_id()) != request_id(self.module) {
            return None;
        }
        let reply = match self.rx.step(&mut self.buf, REQUEST_BYTES, frame, sof) {
            RxStep::Complete(p, _) => {
                // A length byte past the payload leaves nothing: malformed, and the
                // receiver answers it so.
                let m = p
                    .split_first()
                    .and_then(|(&n, rest)| rest.get(..usize::from(n)))
                    .unwrap_or(&[]);
                match (Msg::decode(m), self.fingerprint) {
                    (Some(Msg::Begin { fingerprint, .. }), Some(own)) if fingerprint != own => {
                        Reply::Failed {
                            why: crate::update::Why::Fingerprint,
                        }
                    }
                    _ => self.receiver.handle(flash, m),
                }
            }
            RxStep::Pending => return None,
            RxStep::Restarted | RxStep::Dropped(_) => {
                // Restarted: this first fragment discarded a partial request (its tail
                // was lost); the host repeats what got no reply.
                self.counters.frames_dropped = self.counters.frames_dropped.saturating_add(1);
                return None;
            }
        };
        self.counters.requests = self.counters.requests.saturating_add(1);
        self.push(reply);
        Some(reply)
    }

    fn push(&mut self, reply: Reply) {
        let Some(f) = reply_frame(self.module, reply) else {
            return;
        };
        if self.len == REPLY_QUEUE {
            self.counters.replies_dropped = self.counters.replies_dropped.saturating_add(1);
            return;
        }
        if let Some(slot) = self.out.get_mut((self.head + self.len) % REPLY_QUEUE) {
            *slot = Some(f);
            self.len += 1;
        }
    }

    /// The next reply to send (`Host::service_tx`), the same until [`Port::sent`].
    pub fn next(&self) -> Option<Frame> {
        if self.len == 0 {
            return None;
        }
        self.out.get(self.head).copied().flatten()
    }

    /// The reply from [`Port::next`] was sent (`Host::service_sent`).
    pub fn sent(&mut self) {
        if self.len > 0 {
            if let Some(s) = self.out.get_mut(self.head) {
                *s = None;
            }
            self.head = (self.head + 1) % REPLY_QUEUE;
            self.len -= 1;
        }
    }
}
