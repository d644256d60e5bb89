//! The publishing side of a topic: alloc (a block from the pool), fill, publish.
//!
//! Publisher classes (R2P §3.4.5) follow the topic's [`Remote`](crate::Remote):
//! HRT latches the latest value for the engine's slot and raises a flag when a slot
//! found nothing; SRT queues for `Engine::submit` and raises a flag on a deadline miss;
//! SRT and NRT refuse while the queue towards the engine is full (`publish` hands the
//! loan back in [`WouldBlock`], `send` says [`SendError::QueueFull`] for SRT and
//! [`SendError::WouldBlock`] for NRT; `publish_wait().await` waits for room). Local
//! subscribers never block any class.
use core::future::Future;
use core::pin::Pin;
use core::task::{Context, Poll};

use rtcan_core::time::Nanos;

use crate::handle::Loan;
use crate::message::Message;
use crate::topic::{Remote, Topic, TopicStats};

/// `alloc` found the pool empty (counted in `TopicStats::pool_exhausted`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PoolExhausted;

/// An SRT or NRT topic's queue towards the engine is full: the message is handed back,
/// not dropped (and not published to the local subscribers either).
#[derive(Debug)]
pub struct WouldBlock<L>(pub L);

/// Why `send` did not publish.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SendError {
    /// No free block.
    PoolExhausted,
    /// NRT back-pressure (the block was released).
    WouldBlock,
    /// SRT: the queue towards the engine is full, the message was not published (the
    /// block was released; counted in `TopicStats::remote_overflows`). Messages
    /// published earlier are still waiting for the engine: publish less often, size
    /// the queue deeper, or wait (`publish_wait`).
    QueueFull,
}

/// Handle for the node that publishes on a topic (one per topic).
pub struct Publisher<'a, T: Message, const N: usize, const S: usize, const Q: usize> {
    topic: &'a Topic<T, N, S, Q>,
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> Topic<T, N, S, Q> {
    /// The publisher of this topic.
    pub const fn publisher(&self) -> Publisher<'_, T, N, S, Q> {
        Publisher { topic: self }
    }
}

impl<'a, T: Message, const N: usize, const S: usize, const Q: usize> Publisher<'a, T, N, S, Q> {
    /// Takes a block from the pool holding `value`; modify it in place through the loan.
    #[inline]
    pub fn alloc(&self, value: T) -> Result<Loan<'a, T, N, S, Q>, PoolExhausted> {
        match self.topic.alloc_idx(value, None) {
            Some(idx) => Ok(Loan {
                topic: self.topic,
                idx,
            }),
            None => Err(PoolExhausted),
        }
    }

    /// Publishes `loan` stamped `now`: queued to every local subscriber, latched for
    /// the HRT slot or queued for the engine. SRT and NRT topics refuse while their
    /// queue towards the engine is full, handing the loan back.
    #[inline]
    pub fn publish(
        &self,
        loan: Loan<'a, T, N, S, Q>,
        now: Nanos,
    ) -> Result<(), WouldBlock<Loan<'a, T, N, S, Q>>> {
        if self.topic.publish_idx(loan.idx, now, None) {
            let _ = loan.into_idx();
            Ok(())
        } else {
            Err(WouldBlock(loan))
        }
    }

    /// `alloc` + `publish`.
    #[inline]
    pub fn send(&self, value: T, now: Nanos) -> Result<(), SendError> {
        if self.topic.remote() == Remote::None {
            return if self.topic.send_local(value, now) {
                Ok(())
            } else {
                Err(SendError::PoolExhausted)
            };
        }
        let loan = self.alloc(value).map_err(|_| SendError::PoolExhausted)?;
        self.publish(loan, now)
            .map_err(|_| match self.topic.remote() {
                Remote::Srt => SendError::QueueFull,
                _ => SendError::WouldBlock,
            })
    }

    /// Waits for a free block (NRT publishers that must not drop).
    pub fn alloc_wait(&self, value: T) -> AllocWait<'a, T, N, S, Q> {
        AllocWait {
            topic: self.topic,
            value,
        }
    }

    /// Publishes, waiting while an SRT or NRT topic's queue towards the engine is full.
    pub fn publish_wait(
        &self,
        loan: Loan<'a, T, N, S, Q>,
        now: Nanos,
    ) -> PublishWait<'a, T, N, S, Q> {
        PublishWait {
            loan: Some(loan),
            now,
        }
    }

    /// HRT: whether a reserved slot found nothing to send since the last call (clears).
    pub fn take_nothing_sent(&self) -> bool {
        self.topic.take_nothing_flag()
    }

    /// SRT: whether a message missed its deadline since the last call (clears).
    pub fn take_deadline_missed(&self) -> bool {
        self.topic.take_miss_flag()
    }

    /// The topic's counters (deadline misses, empty slots, pool exhaustion, ...).
    pub fn stats(&self) -> TopicStats {
        self.topic.stats()
    }
}

/// Future of [`Publisher::alloc_wait`].
pub struct AllocWait<'a, T: Message, const N: usize, const S: usize, const Q: usize> {
    topic: &'a Topic<T, N, S, Q>,
    value: T,
}

impl<'a, T: Message, const N: usize, const S: usize, const Q: usize> Future
    for AllocWait<'a, T, N, S, Q>
{
    type Output = Loan<'a, T, N, S, Q>;
    fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Self::Output> {
        // Check and waker registration happen in one critical section: no lost wake-up.
        match self.topic.alloc_idx(self.value, Some(cx.waker())) {
            Some(idx) => Poll::Ready(Loan {
                topic: self.topic,
                idx,
            }),
            None => Poll::Pending,
        }
    }
}

/// Future of [`Publisher::publish_wait`].
pub struct PublishWait<'a, T: Message, const N: usize, const S: usize, const Q: usize> {
    loan: Option<Loan<'a, T, N, S, Q>>,
    now: Nanos,
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> Future
    for PublishWait<'_, T, N, S, Q>
{
    type Output = ();
    fn poll(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<()> {
        let now = self.now;
        let Some(loan) = self.loan.take() else {
            return Poll::Ready(());
        };
        if loan.topic.publish_idx(loan.idx, now, Some(cx.waker())) {
            let _ = loan.into_idx();
            Poll::Ready(())
        } else {
            self.loan = Some(loan);
            Poll::Pending
        }
    }
}
