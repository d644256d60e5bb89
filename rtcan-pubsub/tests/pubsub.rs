//! Local publish/subscribe: order, pool accounting, isolation, async, publisher classes.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
mod common;

use std::task::Poll;

use common::{counting_waker, poll_once, wakes};
use rtcan_core::driver::{Token, TxOutcome};
use rtcan_pubsub::{
    pool_blocks, PoolExhausted, RecvError, Remote, SendError, Topic, TopicCells, TxPort,
};

#[test]
fn delivery_order_is_publish_order_for_every_subscriber() {
    let t = Topic::<u32, 8, 2, 3>::new(cells(), Remote::None, None);
    let p = t.publisher();
    for (v, now) in [(10, 100), (20, 200), (30, 300)] {
        p.send(v, now).unwrap();
    }
    for sub in [t.subscriber::<0>(), t.subscriber::<1>()] {
        let got: Vec<(u32, u64)> =
            std::iter::from_fn(|| sub.try_recv().map(|m| (*m, m.stamp()))).collect();
        assert_eq!(got, vec![(10, 100), (20, 200), (30, 300)]);
    }
    assert_eq!(t.stats().published, 3);
}

#[test]
fn local_delivery_is_zero_copy_all_subscribers_share_the_block() {
    let t = Topic::<[u8; 16], 4, 2, 2>::new(cells(), Remote::None, None);
    let p = t.publisher();
    let mut loan = p.alloc([0; 16]).unwrap();
    loan[3] = 7; // filled in place, in the pool block
    p.publish(loan, 1).unwrap();
    let a = t.subscriber::<0>().try_recv().unwrap();
    let b = t.subscriber::<1>().try_recv().unwrap();
    assert_eq!(a.block(), b.block());
    assert!(
        std::ptr::eq(&*a, &*b),
        "both handles point at the same pool block"
    );
    assert_eq!(a[3], 7);
}

#[test]
fn pool_exhaustion_is_reported_not_a_panic() {
    let t = Topic::<u16, 2, 1, 4>::new(cells(), Remote::None, None);
    let p = t.publisher();
    let a = p.alloc(1).unwrap();
    let _b = p.alloc(2).unwrap();
    assert_eq!(p.alloc(3).unwrap_err(), PoolExhausted);
    assert_eq!(p.send(3, 0), Err(SendError::PoolExhausted));
    assert_eq!(t.stats().pool_exhausted, 2);
    drop(a); // an unpublished loan goes back to the pool
    assert_eq!(t.free_blocks(), 1);
    assert!(p.alloc(4).is_ok());
}

#[test]
fn memory_returns_to_the_pool_when_the_last_holder_releases() {
    let t = Topic::<u32, 4, 2, 2>::new(cells(), Remote::None, None);
    t.publisher().send(5, 0).unwrap();
    assert_eq!(t.free_blocks(), 3);
    let m0 = t.subscriber::<0>().try_recv().unwrap();
    drop(m0);
    assert_eq!(t.free_blocks(), 3, "subscriber 1 still has it queued");
    let m1 = t.subscriber::<1>().try_recv().unwrap();
    assert_eq!(t.free_blocks(), 3, "held by subscriber 1");
    drop(m1);
    assert_eq!(t.free_blocks(), 4);
}

#[test]
fn publish_without_room_anywhere_frees_the_block_at_once() {
    let t = Topic::<u32, 2, 0, 1>::new(cells(), Remote::None, None);
    for i in 0..10 {
        t.publisher().send(i, 0).unwrap();
    }
    assert_eq!(t.free_blocks(), 2);
}

#[test]
fn slow_subscriber_overflows_alone_and_keeps_the_newest() {
    const N: usize = pool_blocks(2, 2, 0, 1);
    let t = Topic::<u32, N, 2, 2>::new(cells(), Remote::None, None);
    let p = t.publisher();
    let fast = t.subscriber::<0>();
    let slow = t.subscriber::<1>();
    let mut fast_got = vec![];
    for v in 1..=5 {
        p.send(v, u64::from(v)).unwrap();
        fast_got.push(*fast.try_recv().unwrap());
    }
    assert_eq!(fast_got, vec![1, 2, 3, 4, 5]);
    assert_eq!(fast.overflows(), 0);
    assert_eq!(slow.overflows(), 3);
    assert_eq!(slow.queued(), 2);
    assert_eq!(
        [*slow.try_recv().unwrap(), *slow.try_recv().unwrap()],
        [4, 5]
    );
    assert_eq!(t.stats().pool_exhausted, 0);
    assert_eq!(t.free_blocks(), N, "dropped messages were released");
}

#[test]
fn async_recv_is_woken_by_publish() {
    let t = Topic::<u32, 4, 1, 2>::new(cells(), Remote::None, None);
    let sub = t.subscriber::<0>();
    let (count, waker) = counting_waker();
    let mut fut = sub.recv();
    assert!(poll_once(&mut fut, &waker).is_pending());
    assert!(
        poll_once(&mut fut, &waker).is_pending(),
        "re-poll keeps one registration"
    );
    assert_eq!(wakes(&count), 0);
    t.publisher().send(42, 9).unwrap();
    assert_eq!(wakes(&count), 1);
    match poll_once(&mut fut, &waker) {
        Poll::Ready(m) => assert_eq!((*m, m.stamp()), (42, 9)),
        Poll::Pending => panic!("message was published"),
    }
    t.publisher().send(43, 10).unwrap();
    assert_eq!(wakes(&count), 1, "no waker registered any more");
}

#[test]
fn stale_stream_is_noticed() {
    let t = Topic::<u32, 4, 1, 2>::new(cells(), Remote::None, None);
    let sub = t.subscriber::<0>();
    assert_eq!(
        sub.try_recv_or_stale(0, 100).unwrap_err(),
        RecvError::Stale,
        "nothing ever came"
    );
    assert_eq!(sub.last_rx_time(), None);
    t.publisher().send(1, 1_000).unwrap();
    assert_eq!(*sub.try_recv_or_stale(1_010, 100).unwrap(), 1);
    assert_eq!(sub.last_rx_time(), Some(1_000));
    assert_eq!(
        sub.try_recv_or_stale(1_100, 100).unwrap_err(),
        RecvError::Empty
    );
    assert_eq!(
        sub.try_recv_or_stale(1_101, 100).unwrap_err(),
        RecvError::Stale
    );
}

#[test]
fn nrt_back_pressure_returns_the_message_then_waits_for_room() {
    let t = Topic::<u32, 8, 1, 2>::new(cells(), Remote::Nrt, None);
    let p = t.publisher();
    let sub = t.subscriber::<0>();
    p.send(1, 0).unwrap();
    p.send(2, 0).unwrap();
    let mut got: Vec<u32> = std::iter::from_fn(|| sub.try_recv().map(|m| *m)).collect();
    let loan = p.alloc(3).unwrap();
    let loan = p.publish(loan, 0).unwrap_err().0;
    assert_eq!(*loan, 3, "handed back, not dropped");
    assert_eq!(sub.queued(), 0, "not half-published to local subscribers");
    assert_eq!(p.send(4, 0), Err(SendError::WouldBlock));

    let (count, waker) = counting_waker();
    let mut fut = p.publish_wait(loan, 5);
    assert!(poll_once(&mut fut, &waker).is_pending());
    // The glue hands the oldest message to the engine: room for one more.
    let tok = t.pending().unwrap();
    t.pending_done(tok, true);
    assert_eq!(wakes(&count), 1);
    assert!(poll_once(&mut fut, &waker).is_ready());
    got.extend(std::iter::from_fn(|| sub.try_recv().map(|m| *m)));
    assert_eq!(got, vec![1, 2, 3]);
    assert_eq!(t.stats().remote_overflows, 0);
}

#[test]
fn alloc_wait_is_woken_when_a_block_returns() {
    let t = Topic::<u32, 1, 1, 1>::new(cells(), Remote::None, None);
    let p = t.publisher();
    let held = p.alloc(1).unwrap();
    let (count, waker) = counting_waker();
    let mut fut = p.alloc_wait(2);
    assert!(poll_once(&mut fut, &waker).is_pending());
    drop(held);
    assert_eq!(wakes(&count), 1);
    match poll_once(&mut fut, &waker) {
        Poll::Ready(l) => assert_eq!(*l, 2),
        Poll::Pending => panic!("block was freed"),
    };
}

#[test]
fn hrt_latches_latest_and_signals_empty_slots() {
    let t = Topic::<u32, 4, 1, 2>::new(cells(), Remote::Hrt, None);
    let p = t.publisher();
    p.send(0x0102_0304, 0).unwrap();
    p.send(0x0A0B_0C0D, 1).unwrap();
    assert_eq!(t.stats().hrt_replaced, 1);
    let tok = t.hrt_sample().unwrap();
    assert_eq!(
        t.payload(tok),
        &[0x0D, 0x0C, 0x0B, 0x0A],
        "latest value, little endian, in place"
    );
    t.tx_done(Some(tok), TxOutcome::Sent);
    assert_eq!(
        t.payload(tok),
        &[] as &[u8],
        "released block has no payload"
    );

    assert!(!p.take_nothing_sent());
    assert_eq!(t.hrt_sample(), None, "no publish since the last slot");
    t.tx_done(None, TxOutcome::NothingToSend);
    assert!(p.take_nothing_sent());
    assert!(!p.take_nothing_sent(), "flag clears when read");
    let s = t.stats();
    assert_eq!((s.nothing_to_send, s.sent), (1, 1));
    drop(t.subscriber::<0>().try_recv());
    drop(t.subscriber::<0>().try_recv());
    assert_eq!(t.free_blocks(), 4);
}

#[test]
fn srt_deadline_miss_is_signalled_and_the_block_released() {
    let t = Topic::<u16, 4, 0, 2>::new(cells(), Remote::Srt, None);
    let p = t.publisher();
    p.send(7, 0).unwrap();
    p.send(8, 0).unwrap();
    let first = t.pending().unwrap();
    t.pending_done(first, true);
    let second = t.pending().unwrap();
    t.pending_done(second, true);
    assert_eq!(t.pending(), None);
    t.tx_done(Some(first), TxOutcome::Sent);
    assert!(!p.take_deadline_missed());
    t.tx_done(Some(second), TxOutcome::DeadlineMissed);
    assert!(p.take_deadline_missed());
    assert!(!p.take_deadline_missed());
    let s = p.stats();
    assert_eq!((s.sent, s.deadline_misses), (1, 1));
    assert_eq!(t.free_blocks(), 4);
}

#[test]
fn srt_full_engine_queue_is_reported_to_the_caller() {
    let t = Topic::<u16, 8, 1, 1>::new(cells(), Remote::Srt, None);
    let p = t.publisher();
    let sub = t.subscriber::<0>();
    p.send(1, 0).unwrap();
    // The queue towards the engine (depth 1) is full: the caller is told, nothing is
    // half-published (the local subscriber does not get it either), the block returns.
    assert_eq!(p.send(2, 0), Err(SendError::QueueFull));
    let loan = p.alloc(3).unwrap();
    let loan = p.publish(loan, 0).unwrap_err().0;
    assert_eq!(*loan, 3, "handed back, not dropped");
    drop(loan);
    assert_eq!(t.stats().remote_overflows, 2);
    assert_eq!(t.stats().published, 1);
    assert_eq!(sub.overflows(), 0);
    assert_eq!(*sub.try_recv().unwrap(), 1);
    assert_eq!(sub.try_recv().map(|m| *m), None);
    assert_eq!(t.free_blocks(), 7, "one block waits for the engine");
    // The engine takes the queued one: room again, and a waiting publisher is woken.
    let (count, waker) = counting_waker();
    let mut fut = p.publish_wait(p.alloc(4).unwrap(), 1);
    assert!(poll_once(&mut fut, &waker).is_pending());
    let tok = t.pending().unwrap();
    t.pending_done(tok, true);
    assert_eq!(wakes(&count), 1);
    assert!(poll_once(&mut fut, &waker).is_ready());
    assert_eq!(*sub.try_recv().unwrap(), 4);
    assert_eq!(p.send(5, 2), Err(SendError::QueueFull));
}

#[test]
fn kick_runs_when_a_message_is_queued_for_the_engine() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static KICKS: AtomicUsize = AtomicUsize::new(0);
    fn kick() {
        KICKS.fetch_add(1, Ordering::SeqCst);
    }
    let t = Topic::<u8, 4, 0, 1>::new(cells(), Remote::Srt, Some(kick));
    t.publisher().send(1, 0).unwrap();
    // Queue full: refused, nothing new for the engine.
    assert_eq!(t.publisher().send(2, 0), Err(SendError::QueueFull));
    assert_eq!(KICKS.load(Ordering::SeqCst), 1);
}

#[test]
fn stale_or_foreign_tokens_do_not_corrupt_the_pool() {
    let t = Topic::<u32, 4, 1, 2>::new(cells(), Remote::Srt, None);
    t.publisher().send(1, 0).unwrap();
    let tok = t.pending().unwrap();
    t.pending_done(Token(3), true); // not the head: ignored
    assert_eq!(t.pending(), Some(tok));
    t.pending_done(tok, true);
    t.tx_done(Some(tok), TxOutcome::Sent);
    let m = t.subscriber::<0>().try_recv().unwrap();
    t.tx_done(Some(tok), TxOutcome::Sent); // engine bug: same token twice
    t.tx_done(Some(Token(999)), TxOutcome::Sent);
    assert_eq!(t.free_blocks(), 3, "the subscriber still holds its block");
    assert_eq!(*m, 1);
    drop(m);
    assert_eq!(t.free_blocks(), 4);
}

#[test]
fn statics_work_and_threads_share_a_topic_without_losing_blocks() {
    static CELLS: TopicCells<u64, 8, 2, 4> = TopicCells::new();
    static T: Topic<u64, 8, 2, 4> = Topic::new(&CELLS, Remote::None, None);
    let producer = std::thread::spawn(|| {
        let p = T.publisher();
        let mut sent = 0u64;
        let mut v = 0;
        while sent < 20_000 {
            if p.send(v, v).is_ok() {
                sent += 1;
            }
            v += 1;
        }
    });
    let consumers: Vec<_> = [0usize, 1]
        .into_iter()
        .map(|i| {
            std::thread::spawn(move || {
                let sub = T.subscriber_at(i).unwrap();
                let mut last = None;
                let mut n = 0u32;
                for _ in 0..200_000 {
                    if let Some(m) = sub.try_recv() {
                        assert!(last.is_none_or(|l| *m > l), "order kept under contention");
                        last = Some(*m);
                        n += 1;
                    }
                }
                n
            })
        })
        .collect();
    producer.join().unwrap();
    for c in consumers {
        c.join().unwrap();
    }
    for i in 0..2 {
        let sub = T.subscriber_at(i).unwrap();
        while sub.try_recv().is_some() {}
    }
    assert_eq!(
        T.free_blocks(),
        8,
        "every block back after all holders released"
    );
}

#[test]
fn bad_bus_payload_is_counted() {
    use rtcan_pubsub::RxPort;
    let t = Topic::<u32, 2, 1, 1>::new(cells(), Remote::None, None);
    t.deliver(&[1, 2, 3], 0);
    assert_eq!(t.stats().rx_decode_errors, 1);
    assert!(t.subscriber::<0>().try_recv().is_none());
    t.deliver(&[1, 0, 0, 0], 77);
    let m = t.subscriber::<0>().try_recv().unwrap();
    assert_eq!((*m, m.stamp()), (1, 77));
}

#[test]
fn nrt_engine_round_trip_returns_blocks() {
    let t = Topic::<[u8; 8], 10, 0, 4>::new(cells(), Remote::Nrt, None);
    for i in 0..4u8 {
        t.publisher().send([i; 8], 40).unwrap();
    }
    assert_eq!(t.free_blocks(), 6);
    while let Some(block) = t.pending() {
        t.pending_done(block, true);
        t.tx_done(Some(block), TxOutcome::Sent);
    }
    assert_eq!(t.free_blocks(), 10);
}

#[test]
fn reset_returns_every_topic_held_block_but_not_live_handles() {
    // 2 subscribers (queue 2), SRT remote: blocks sit in both queues and the bus side.
    let t = Topic::<u32, 8, 2, 2>::new(cells(), Remote::Srt, None);
    let p = t.publisher();
    p.send(1, 10).unwrap();
    p.send(2, 20).unwrap();
    let held = t.subscriber::<0>().try_recv().unwrap(); // a live handle on block of `1`
    let engine_tok = t.pending().unwrap();
    t.pending_done(engine_tok, true); // block of `1` now held by "the engine" too
    assert!(t.free_blocks() < 8);
    t.reset();
    assert_eq!(*held, 1, "a live handle still reads its block");
    assert_eq!(
        t.free_blocks(),
        7,
        "only the handle's block stays allocated"
    );
    assert_eq!(t.stats(), Default::default());
    assert_eq!(t.pending(), None);
    assert!(t.subscriber::<1>().try_recv().is_none());
    assert_eq!(t.subscriber::<0>().last_rx_time(), None);
    // A stale engine completion after the reset must not free anything twice.
    t.tx_done(Some(engine_tok), TxOutcome::Sent);
    assert_eq!(t.free_blocks(), 7);
    drop(held);
    assert_eq!(t.free_blocks(), 8);
}

/// A waker whose `wake()` publishes on the topic it waits on (a task woken inline by an
/// executor that runs it at once). Publishes once, so a wake-up cannot recurse forever.
struct PublishingWaker {
    topic: &'static Topic<u32, 8, 1, 4>,
    value: u32,
    calls: std::sync::atomic::AtomicUsize,
}

impl std::task::Wake for PublishingWaker {
    fn wake(self: std::sync::Arc<Self>) {
        self.wake_by_ref();
    }
    fn wake_by_ref(self: &std::sync::Arc<Self>) {
        use std::sync::atomic::Ordering;
        if self.calls.fetch_add(1, Ordering::SeqCst) == 0 {
            self.topic.publisher().send(self.value, 7).unwrap();
        }
    }
}

fn publishing_waker(
    topic: &'static Topic<u32, 8, 1, 4>,
    value: u32,
) -> (std::sync::Arc<PublishingWaker>, std::task::Waker) {
    let w = std::sync::Arc::new(PublishingWaker {
        topic,
        value,
        calls: std::sync::atomic::AtomicUsize::new(0),
    });
    (w.clone(), std::task::Waker::from(w))
}

#[test]
fn subscriber_waker_that_publishes_to_the_same_topic_does_not_panic() {
    static CELLS: TopicCells<u32, 8, 1, 4> = TopicCells::new();
    static T: Topic<u32, 8, 1, 4> = Topic::new(&CELLS, Remote::None, None);
    let sub = T.subscriber::<0>();
    let (w, waker) = publishing_waker(&T, 2);
    let mut fut = sub.recv();
    assert!(poll_once(&mut fut, &waker).is_pending());
    T.publisher().send(1, 5).unwrap();
    assert_eq!(w.calls.load(std::sync::atomic::Ordering::SeqCst), 1);
    // Both messages queued, in order: the one that woke, then the one the wake sent.
    let got: Vec<(u32, u64)> =
        std::iter::from_fn(|| sub.try_recv().map(|m| (*m, m.stamp()))).collect();
    assert_eq!(got, vec![(1, 5), (2, 7)]);
    assert_eq!(T.free_blocks(), 8);
}

#[test]
fn publisher_waker_that_publishes_when_a_block_returns_does_not_panic() {
    static CELLS: TopicCells<u32, 8, 1, 4> = TopicCells::new();
    static T: Topic<u32, 8, 1, 4> = Topic::new(&CELLS, Remote::None, None);
    let p = T.publisher();
    let loans: Vec<_> = (0..8).map(|i| p.alloc(i).unwrap()).collect();
    let (w, waker) = publishing_waker(&T, 42);
    let mut fut = p.alloc_wait(9);
    assert!(poll_once(&mut fut, &waker).is_pending());
    // Returning a block wakes the publisher, whose wake publishes into that block.
    drop(loans);
    assert_eq!(w.calls.load(std::sync::atomic::Ordering::SeqCst), 1);
    let sub = T.subscriber::<0>();
    assert_eq!(sub.try_recv().map(|m| *m), Some(42));
    assert_eq!(T.free_blocks(), 8);
}

#[test]
fn engine_side_wake_that_publishes_does_not_panic() {
    // NRT back-pressure: the publisher waits for room in the engine queue; handing the
    // queued message to the engine wakes it, and the wake publishes again.
    static CELLS: TopicCells<u32, 8, 1, 4> = TopicCells::new();
    static T: Topic<u32, 8, 1, 4> = Topic::new(&CELLS, Remote::Nrt, None);
    let p = T.publisher();
    for v in 0..4 {
        p.send(v, 0).unwrap();
    }
    let (w, waker) = publishing_waker(&T, 77);
    let loan = p.alloc(5).unwrap();
    let mut fut = p.publish_wait(loan, 1);
    assert!(poll_once(&mut fut, &waker).is_pending());
    let tok = T.pending().unwrap();
    T.pending_done(tok, true);
    assert_eq!(w.calls.load(std::sync::atomic::Ordering::SeqCst), 1);
    assert_eq!(T.stats().published, 5, "the wake's publish went through");
}

/// Fresh cells for a topic made inside a test (leaked: a topic's cells are `'static`).
fn cells<T: rtcan_pubsub::Message, const N: usize, const S: usize, const Q: usize>(
) -> &'static TopicCells<T, N, S, Q> {
    Box::leak(Box::new(TopicCells::new()))
}
