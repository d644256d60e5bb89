//! The subscribing side: each subscriber owns one queue slot of the topic (slot
//! numbers are assigned at compile time by the generated code).
use core::future::Future;
use core::pin::Pin;
use core::task::{Context, Poll};

use rtcan_core::time::Nanos;

use crate::handle::Msg;
use crate::message::Message;
use crate::topic::{RecvError, Topic};

/// Handle of subscriber slot `id` of a topic. Use one handle per slot: the slot has
/// one waker, so two tasks awaiting the same slot would steal each other's wake-ups.
pub struct Subscriber<'a, T: Message, const N: usize, const S: usize, const Q: usize> {
    topic: &'a Topic<T, N, S, Q>,
    id: u8,
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> Topic<T, N, S, Q> {
    /// Subscriber slot `I` (checked at compile time: `I < S`).
    pub const fn subscriber<const I: usize>(&self) -> Subscriber<'_, T, N, S, Q> {
        const { assert!(I < S, "subscriber slot out of range") };
        Subscriber {
            topic: self,
            id: I as u8,
        }
    }

    /// Subscriber slot `i`, `None` if `i >= S`.
    pub const fn subscriber_at(&self, i: usize) -> Option<Subscriber<'_, T, N, S, Q>> {
        if i < S {
            Some(Subscriber {
                topic: self,
                id: i as u8,
            })
        } else {
            None
        }
    }
}

impl<'a, T: Message, const N: usize, const S: usize, const Q: usize> Subscriber<'a, T, N, S, Q> {
    /// The oldest queued message, without waiting.
    #[inline]
    pub fn try_recv(&self) -> Option<Msg<'a, T, N, S, Q>> {
        let (idx, stamp) = self.topic.pop(self.id, None)?;
        Some(Msg {
            topic: self.topic,
            idx,
            stamp,
        })
    }

    /// Waits for the next message (RTIC 2 async tasks or any executor).
    pub fn recv(&self) -> Recv<'_, 'a, T, N, S, Q> {
        Recv { sub: self }
    }

    /// The oldest queued message; when none is queued, `Stale` if the last message is
    /// older than `max_age` at `now` (or none ever came), else `Empty`. A node uses it
    /// to notice that an HRT stream stopped.
    pub fn try_recv_or_stale(
        &self,
        now: Nanos,
        max_age: Nanos,
    ) -> Result<Msg<'a, T, N, S, Q>, RecvError> {
        let (idx, stamp) = self.topic.pop_or_stale(self.id, now, max_age)?;
        Ok(Msg {
            topic: self.topic,
            idx,
            stamp,
        })
    }

    /// Stamp of the last message taken from the queue.
    pub fn last_rx_time(&self) -> Option<Nanos> {
        self.topic.last_rx(self.id)
    }

    /// Messages this subscriber lost because its queue was full (oldest dropped).
    pub fn overflows(&self) -> u32 {
        self.topic.overflows(self.id)
    }

    /// Messages waiting in the queue.
    pub fn queued(&self) -> usize {
        self.topic.queued(self.id)
    }
}

/// Future of [`Subscriber::recv`].
pub struct Recv<'s, 'a, T: Message, const N: usize, const S: usize, const Q: usize> {
    sub: &'s Subscriber<'a, T, N, S, Q>,
}

impl<'a, T: Message, const N: usize, const S: usize, const Q: usize> Future
    for Recv<'_, 'a, T, N, S, Q>
{
    type Output = Msg<'a, T, N, S, Q>;
    fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Self::Output> {
        // Pop or register the waker in one critical section: a publish between the two
        // cannot be missed.
        match self.sub.topic.pop(self.sub.id, Some(cx.waker())) {
            Some((idx, stamp)) => Poll::Ready(Msg {
                topic: self.sub.topic,
                idx,
                stamp,
            }),
            None => Poll::Pending,
        }
    }
}
