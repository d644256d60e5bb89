//! The host side of the update protocol on the bus (docs/SERVICES.md §4): turns an
//! image into request frames for one module, keeps up to `window` `Data` requests
//! outstanding, and recovers from what the bus loses:
//!
//! - an `Ack { next }` that makes no progress while later chunks are out (a request
//!   was lost, or the module dropped a fragment): go back to `next` once (go-back-N;
//!   the module ignores chunks past the offset it expects, `update.rs`);
//! - no reply at all for `timeout_ns` after the last frame or reply: repeat from the
//!   last acknowledged point (`Begin`, the first unacknowledged `Data`, or `End`);
//! - `Failed { why }`: the update is over, nothing committed.
//!
//! No heap: the image is the caller's (`&[u8]` on a module), one request's payload is
//! built at a time.
use rtcan_core::{Frame, Nanos};

use crate::can::{parse_reply, request_frame, request_payload, REQUEST_BYTES, REQUEST_FRAMES};
use crate::update::{Msg, Reply, Why, MAX_CHUNK};
use crate::Crc32;

/// Sender settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Config {
    /// `Data` requests outstanding at most (sent, no reply yet).
    pub window: u32,
    /// Silence (no frame sent, no reply) after which the sender repeats.
    pub timeout_ns: Nanos,
    /// Silence allowed after `Begin`: the module erases a whole slot first.
    pub begin_timeout_ns: Nanos,
    /// Repetitions (timeouts and go-backs) before giving up.
    pub max_retries: u32,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            window: 4,
            timeout_ns: 100_000_000,
            begin_timeout_ns: 2_000_000_000,
            max_retries: 50,
        }
    }
}

/// How an update ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Committed: the module boots `slot` (sequence `seq`) at its next reset.
    Done { slot: u8, seq: u16 },
    /// Refused by the module.
    Failed(Why),
    /// No answer after `max_retries` repetitions.
    Timeout,
}

/// What the sender did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Requests whose every frame was sent.
    pub requests: u32,
    /// Request frames sent.
    pub frames: u32,
    /// Replies from the module.
    pub replies: u32,
    /// Repetitions: timeouts and go-backs.
    pub retries: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Begin,
    Data,
    End,
    Finished(Outcome),
}

/// A request being sent: its payload and the counter of its next frame.
struct Current {
    payload: [u8; REQUEST_BYTES],
    counter: u8,
}

fn start(msg: Msg<'_>) -> Option<Current> {
    Some(Current {
        payload: request_payload(&msg)?,
        counter: REQUEST_FRAMES - 1,
    })
}

/// The host side of one module's update.
pub struct Sender<I: AsRef<[u8]>> {
    module: u8,
    image: I,
    fingerprint: u32,
    cfg: Config,
    phase: Phase,
    /// Image bytes the module acknowledged.
    acked: u32,
    /// Image bytes handed to requests so far.
    sent_upto: u32,
    /// `Data` requests sent and not answered.
    in_flight: u32,
    /// The `Begin`/`End` request of the phase was built (awaiting its reply).
    asked: bool,
    cur: Option<Current>,
    tid: u8,
    /// Last frame sent or reply received (the timeout counts from here).
    last_activity: Option<Nanos>,
    /// The offset last gone back to (a go-back happens once per offset).
    rewound_to: Option<u32>,
    pub stats: Stats,
}

impl<I: AsRef<[u8]>> Sender<I> {
    /// The update of `module` with `image`, built for the robot of `fingerprint`.
    pub fn new(module: u8, image: I, fingerprint: u32, cfg: Config) -> Self {
        Sender {
            module,
            image,
            fingerprint,
            cfg,
            phase: Phase::Begin,
            acked: 0,
            sent_upto: 0,
            in_flight: 0,
            asked: false,
            cur: None,
            tid: 0,
            last_activity: None,
            rewound_to: None,
            stats: Stats::default(),
        }
    }

    fn len(&self) -> u32 {
        u32::try_from(self.image.as_ref().len()).unwrap_or(u32::MAX)
    }

    /// The result, once over.
    pub fn outcome(&self) -> Option<Outcome> {
        match self.phase {
            Phase::Finished(o) => Some(o),
            _ => None,
        }
    }

    /// Image bytes the module acknowledged.
    pub fn acked(&self) -> u32 {
        self.acked
    }

    fn finish(&mut self, o: Outcome) {
        self.phase = Phase::Finished(o);
        self.cur = None;
    }

    /// Builds the next request if one is due and none is being sent.
    fn refill(&mut self) {
        if self.cur.is_some() {
            return;
        }
        match self.phase {
            Phase::Begin if !self.asked => {
                self.asked = true;
                self.cur = start(Msg::Begin {
                    len: self.len(),
                    crc: Crc32::of(self.image.as_ref()),
                    fingerprint: self.fingerprint,
                });
            }
            Phase::Data if self.sent_upto < self.len() && self.in_flight < self.cfg.window => {
                let from = self.sent_upto as usize;
                let image = self.image.as_ref();
                let to = (from + MAX_CHUNK).min(image.len());
                let Some(bytes) = image.get(from..to) else {
                    return;
                };
                self.in_flight += 1;
                self.sent_upto = to as u32;
                self.cur = start(Msg::Data {
                    offset: from as u32,
                    bytes,
                });
            }
            Phase::End if !self.asked => {
                self.asked = true;
                self.cur = start(Msg::End);
            }
            _ => {}
        }
    }

    /// The next frame to send (the same one until [`Sender::sent`]), after repeating
    /// what timed out at `now`.
    pub fn next_frame(&mut self, now: Nanos) -> Option<Frame> {
        self.check_timeout(now);
        self.refill();
        let c = self.cur.as_ref()?;
        request_frame(self.module, self.tid, c.counter, &c.payload)
    }

    /// The frame from [`Sender::next_frame`] was sent at `now`.
    pub fn sent(&mut self, now: Nanos) {
        let Some(c) = self.cur.as_mut() else {
            return;
        };
        self.stats.frames += 1;
        self.last_activity = Some(now);
        if c.counter == 0 {
            self.cur = None;
            self.tid = self.tid.wrapping_add(1);
            self.stats.requests += 1;
        } else {
            c.counter -= 1;
        }
    }

    fn check_timeout(&mut self, now: Nanos) {
        let Some(last) = self.last_activity else {
            return;
        };
        let waiting = match self.phase {
            Phase::Begin | Phase::End => self.asked && self.cur.is_none(),
            Phase::Data => self.in_flight > 0 && self.cur.is_none(),
            Phase::Finished(_) => false,
        };
        let limit = if self.phase == Phase::Begin {
            self.cfg.begin_timeout_ns
        } else {
            self.cfg.timeout_ns
        };
        if !waiting || now.saturating_sub(last) < limit {
            return;
        }
        self.stats.retries += 1;
        if self.stats.retries > self.cfg.max_retries {
            self.finish(Outcome::Timeout);
            return;
        }
        self.last_activity = Some(now);
        self.asked = false;
        self.in_flight = 0;
        self.sent_upto = self.acked;
    }

    /// A frame from the update range (`Host::service_rx` on the gateway): replies of
    /// this sender's module move the update on; anything else is ignored.
    pub fn on_frame(&mut self, frame: &Frame, now: Nanos) {
        let Some((m, reply)) = parse_reply(frame) else {
            return;
        };
        if m != self.module || self.outcome().is_some() {
            return;
        }
        self.stats.replies += 1;
        self.last_activity = Some(now);
        match (self.phase, reply) {
            // A `Begin` is never answered so: a late reply to an earlier, interrupted
            // update's requests (the module replies in order, so none comes after Ready).
            (
                Phase::Begin,
                Reply::Failed {
                    why: Why::NotStarted,
                },
            ) => {}
            (_, Reply::Failed { why }) => self.finish(Outcome::Failed(why)),
            (Phase::Begin, Reply::Ready { .. }) => {
                self.phase = Phase::Data;
                self.asked = false;
            }
            (Phase::Data, Reply::Ack { next }) => {
                self.in_flight = self.in_flight.saturating_sub(1);
                if next > self.acked && next <= self.len() {
                    self.acked = next;
                    self.rewound_to = None;
                } else if next == self.acked
                    && next < self.sent_upto
                    && self.rewound_to != Some(next)
                {
                    // The chunk at `next` never arrived: send again from there.
                    self.rewound_to = Some(next);
                    self.stats.retries += 1;
                    self.sent_upto = next;
                    self.in_flight = 0;
                }
                if self.acked == self.len() {
                    self.phase = Phase::End;
                    self.asked = false;
                }
            }
            (Phase::End, Reply::Done { slot, seq }) => self.finish(Outcome::Done { slot, seq }),
            // Late answers to repeated requests.
            _ => {}
        }
    }
}
