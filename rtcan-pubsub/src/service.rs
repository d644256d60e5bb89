//! Request/reply (docs/SERVICES.md §3), the bookkeeping both ends need whatever carries
//! the bytes: the client's table of calls in flight with their timeouts, matching
//! replies to calls by a call number, and counting what went wrong (timeouts, late or
//! unknown replies, calls refused because `N` are in flight, the server's absence); the
//! server's framing. Time is passed in (`now`, ns); no allocation.
//!
//! Frame: request = call number u16 LE then the request bytes; reply = the same call
//! number then the reply bytes.
use rtcan_core::Nanos;

/// Consecutive timeouts after which the server counts as absent (until a reply comes).
pub const ABSENT_AFTER_TIMEOUTS: u32 = 3;

/// A call in flight.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CallId(pub u16);

/// Why a call could not start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CallError {
    /// `N` calls are in flight already.
    Busy,
    /// The output buffer is shorter than the framed request.
    TooLong,
    /// The request could not be queued for sending (the call was withdrawn).
    NotSent,
    /// No reply before the call's timeout (the generated client's `call_async`).
    TimedOut,
}

/// What a typed client's `poll` reports (the generated `<Service>Client`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event<R> {
    /// The reply to a call, in time.
    Reply(CallId, R),
    /// A call got no reply before its timeout.
    TimedOut(CallId),
}

/// What became of a call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    Replied(CallId),
    TimedOut(CallId),
}

/// Client counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClientCounters {
    pub calls: u32,
    pub replies: u32,
    pub timeouts: u32,
    /// Replies for a call that had timed out already (or was never made).
    pub late_or_unknown: u32,
    /// Replies too short to carry a call number.
    pub malformed: u32,
    pub busy: u32,
    /// Calls withdrawn because their request could not be sent (`cancel`).
    pub not_sent: u32,
}

/// The client side of one service with at most `N` calls in flight.
#[derive(Clone, Debug)]
pub struct Client<const N: usize> {
    timeout: Nanos,
    next: u16,
    pending: [Option<(u16, Nanos)>; N],
    consecutive_timeouts: u32,
    pub counters: ClientCounters,
}

impl<const N: usize> Client<N> {
    /// `timeout`: the service's timeout from robot.toml (ns).
    pub const fn new(timeout: Nanos) -> Self {
        Client {
            timeout,
            next: 0,
            pending: [None; N],
            consecutive_timeouts: 0,
            counters: ClientCounters {
                calls: 0,
                replies: 0,
                timeouts: 0,
                late_or_unknown: 0,
                malformed: 0,
                busy: 0,
                not_sent: 0,
            },
        }
    }

    /// Starts a call: frames `request` into `out` (returns its length) and records the
    /// deadline `now + timeout`.
    pub fn call(
        &mut self,
        now: Nanos,
        request: &[u8],
        out: &mut [u8],
    ) -> Result<(CallId, usize), CallError> {
        let n = request.len() + 2;
        let Some(dst) = out.get_mut(..n) else {
            return Err(CallError::TooLong);
        };
        let Some(slot) = self.pending.iter_mut().find(|p| p.is_none()) else {
            self.counters.busy = self.counters.busy.saturating_add(1);
            return Err(CallError::Busy);
        };
        let id = self.next;
        self.next = self.next.wrapping_add(1);
        *slot = Some((id, now.saturating_add(self.timeout)));
        let (head, body) = dst.split_at_mut(2);
        head.copy_from_slice(&id.to_le_bytes());
        body.copy_from_slice(request);
        self.counters.calls = self.counters.calls.saturating_add(1);
        Ok((CallId(id), n))
    }

    /// A reply arrived: the call it answers and its payload, or `None` (late, unknown or
    /// malformed: counted). A reply at or after the deadline is late even if `poll`
    /// has not run yet.
    pub fn on_reply<'b>(&mut self, now: Nanos, frame: &'b [u8]) -> Option<(CallId, &'b [u8])> {
        let (Some(&[a, b]), Some(body)) = (frame.get(..2), frame.get(2..)) else {
            self.counters.malformed = self.counters.malformed.saturating_add(1);
            return None;
        };
        let id = u16::from_le_bytes([a, b]);
        let slot = self
            .pending
            .iter_mut()
            .find(|p| p.is_some_and(|(i, d)| i == id && now < d));
        match slot {
            Some(s) => {
                *s = None;
                self.consecutive_timeouts = 0;
                self.counters.replies = self.counters.replies.saturating_add(1);
                Some((CallId(id), body))
            }
            None => {
                self.counters.late_or_unknown = self.counters.late_or_unknown.saturating_add(1);
                None
            }
        }
    }

    /// Expires calls whose deadline passed; calls `expired` for each.
    pub fn poll(&mut self, now: Nanos, mut expired: impl FnMut(CallId)) {
        for p in self.pending.iter_mut() {
            if let Some((id, d)) = *p {
                if now >= d {
                    *p = None;
                    self.counters.timeouts = self.counters.timeouts.saturating_add(1);
                    self.consecutive_timeouts = self.consecutive_timeouts.saturating_add(1);
                    expired(CallId(id));
                }
            }
        }
    }

    /// Expires the call with the earliest passed deadline, if any (one at a time, for a
    /// caller that reports each timeout as an event).
    pub fn expire_one(&mut self, now: Nanos) -> Option<CallId> {
        let slot = self
            .pending
            .iter_mut()
            .filter(|p| p.is_some_and(|(_, d)| now >= d))
            .min_by_key(|p| p.map_or(Nanos::MAX, |(_, d)| d))?;
        let (id, _) = slot.take()?;
        self.counters.timeouts = self.counters.timeouts.saturating_add(1);
        self.consecutive_timeouts = self.consecutive_timeouts.saturating_add(1);
        Some(CallId(id))
    }

    /// Withdraws a call whose request could not be sent (e.g. the queue towards the
    /// engine was full): not a timeout, counted as `not_sent`. False if not in flight.
    pub fn cancel(&mut self, id: CallId) -> bool {
        match self
            .pending
            .iter_mut()
            .find(|p| p.is_some_and(|(i, _)| i == id.0))
        {
            Some(p) => {
                *p = None;
                self.counters.not_sent = self.counters.not_sent.saturating_add(1);
                true
            }
            None => false,
        }
    }

    /// The timeout every call gets (ns).
    pub fn timeout(&self) -> Nanos {
        self.timeout
    }

    /// Calls in flight.
    pub fn in_flight(&self) -> usize {
        self.pending.iter().filter(|p| p.is_some()).count()
    }

    /// `ABSENT_AFTER_TIMEOUTS` calls in a row timed out, and no reply since.
    pub fn server_absent(&self) -> bool {
        self.consecutive_timeouts >= ABSENT_AFTER_TIMEOUTS
    }

    /// The earliest deadline in flight (when to `poll` next).
    pub fn next_deadline(&self) -> Option<Nanos> {
        self.pending.iter().flatten().map(|&(_, d)| d).min()
    }
}

/// The server side: answers a framed request with `handler(request, reply_body) ->
/// reply length`; `None` (counted by the caller) for a frame without a call number or a
/// reply that does not fit `out`.
pub fn serve(
    frame: &[u8],
    out: &mut [u8],
    handler: impl FnOnce(&[u8], &mut [u8]) -> usize,
) -> Option<usize> {
    let head = frame.get(..2)?;
    let body = frame.get(2..)?;
    let (oh, ob) = out.split_at_mut_checked(2)?;
    oh.copy_from_slice(head);
    let n = handler(body, ob);
    (n <= ob.len()).then_some(n + 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Nanos = 1_000_000;

    /// The sonar service of the issue: request = sensor index, reply = range in mm.
    fn sonar(req: &[u8], out: &mut [u8]) -> usize {
        let i = req.first().copied().unwrap_or(0);
        out[..2].copy_from_slice(&(100u16 * u16::from(i)).to_le_bytes());
        2
    }

    #[test]
    fn call_reply_exact_frames() {
        let mut c = Client::<2>::new(20 * MS);
        let mut req = [0u8; 8];
        let (id, n) = c.call(0, &[3], &mut req).unwrap();
        assert_eq!((id, &req[..n]), (CallId(0), &[0, 0, 3][..]));
        let mut rep = [0u8; 8];
        let m = serve(&req[..n], &mut rep, sonar).unwrap();
        assert_eq!(&rep[..m], &[0, 0, 44, 1]);
        assert_eq!(
            c.on_reply(5 * MS, &rep[..m]),
            Some((CallId(0), &[44, 1][..]))
        );
        assert_eq!(c.in_flight(), 0);
        // The same reply again: unknown now, counted, not delivered twice.
        assert_eq!(c.on_reply(6 * MS, &rep[..m]), None);
        assert_eq!(c.counters.late_or_unknown, 1);
        assert_eq!(c.on_reply(6 * MS, &[1]), None);
        assert_eq!(c.counters.malformed, 1);
        assert_eq!(serve(&[1], &mut rep, sonar), None);
        assert_eq!(c.call(0, &[0; 7], &mut req), Err(CallError::TooLong));
    }

    #[test]
    fn concurrent_calls_lost_replies_and_server_absence() {
        let mut c = Client::<3>::new(20 * MS);
        let mut bufs = [[0u8; 4]; 4];
        let (a, _) = c.call(0, &[1], &mut bufs[0]).unwrap();
        let (b, _) = c.call(MS, &[2], &mut bufs[1]).unwrap();
        let (d, _) = c.call(2 * MS, &[3], &mut bufs[2]).unwrap();
        assert_eq!(c.call(3 * MS, &[4], &mut bufs[3]), Err(CallError::Busy));
        assert_eq!(c.counters.busy, 1);
        // Replies out of order; b's reply is lost.
        let mut rep = [0u8; 4];
        let n = serve(&bufs[2][..3], &mut rep, sonar).unwrap();
        assert_eq!(c.on_reply(4 * MS, &rep[..n]).map(|r| r.0), Some(d));
        let n = serve(&bufs[0][..3], &mut rep, sonar).unwrap();
        assert_eq!(c.on_reply(5 * MS, &rep[..n]).map(|r| r.0), Some(a));
        assert_eq!(c.next_deadline(), Some(21 * MS));
        let mut gone = Vec::new();
        c.poll(20 * MS, |id| gone.push(id));
        assert!(gone.is_empty(), "b's deadline is 21 ms");
        c.poll(21 * MS, |id| gone.push(id));
        assert_eq!(gone, [b]);
        // b's reply arriving now is late: counted, not delivered.
        let n = serve(&bufs[1][..3], &mut rep, sonar).unwrap();
        assert_eq!(c.on_reply(22 * MS, &rep[..n]), None);
        assert_eq!(c.counters.late_or_unknown, 1);
        assert!(!c.server_absent());
        // The server goes away: b's timeout and two more in a row (a late reply does not
        // count as the server answering in time) → absent; a reply clears it.
        let mut t = 30 * MS;
        for k in 0..2 {
            assert!(!c.server_absent(), "after {} timeouts", k + 1);
            c.call(t, &[5], &mut [0u8; 4]).unwrap();
            t += 25 * MS;
            c.poll(t, |_| {});
        }
        assert!(c.server_absent());
        assert_eq!(c.counters.timeouts, 3);
        // It is back: the next reply clears the absence.
        let mut fr = [0u8; 4];
        let (_, n) = c.call(t, &[6], &mut fr).unwrap();
        let mut rep = [0u8; 4];
        let m = serve(&fr[..n], &mut rep, sonar).unwrap();
        assert!(c.on_reply(t + MS, &rep[..m]).is_some());
        assert!(!c.server_absent());
        assert_eq!(c.counters.calls, 6);
        assert_eq!(c.counters.replies, 3);
    }

    #[test]
    fn expire_one_takes_the_earliest_passed_deadline_and_cancel_is_not_a_timeout() {
        let mut c = Client::<3>::new(10);
        let mut f = [0u8; 2];
        let (a, _) = c.call(5, &[], &mut f).unwrap();
        let (b, _) = c.call(0, &[], &mut f).unwrap();
        let (d, _) = c.call(7, &[], &mut f).unwrap();
        assert_eq!(c.expire_one(9), None);
        assert!(c.cancel(d));
        assert!(!c.cancel(d));
        assert_eq!(c.expire_one(20), Some(b));
        assert_eq!(c.expire_one(20), Some(a));
        assert_eq!(c.expire_one(20), None);
        assert_eq!((c.counters.timeouts, c.counters.not_sent), (2, 1));
        assert_eq!(c.in_flight(), 0);
        assert_eq!(c.timeout(), 10);
    }

    #[test]
    fn reply_exactly_at_the_deadline_is_late() {
        let mut c = Client::<1>::new(10);
        let mut f = [0u8; 2];
        let (id, _) = c.call(100, &[], &mut f).unwrap();
        assert_eq!(c.on_reply(110, &id.0.to_le_bytes()), None);
        assert_eq!(c.counters.late_or_unknown, 1);
    }

    #[test]
    fn call_numbers_wrap_without_confusion() {
        let mut c = Client::<1>::new(10);
        c.next = u16::MAX;
        let mut f = [0u8; 2];
        let (a, _) = c.call(0, &[], &mut f).unwrap();
        assert_eq!(a, CallId(u16::MAX));
        assert!(c.on_reply(1, &f).is_some());
        let (b, _) = c.call(2, &[], &mut f).unwrap();
        assert_eq!(b, CallId(0));
    }
}
