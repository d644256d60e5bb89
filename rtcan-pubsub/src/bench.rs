//! Plain, non-inlined entry points for measuring the hot path: the host criterion
//! bench and the Cortex-M3 instruction counts under QEMU (boards helper) call these.
use rtcan_core::time::Nanos;

use crate::message::Message;
use crate::topic::Topic;

/// One local publish of `value` (alloc + fill + publish to every subscriber).
/// `false` if the pool was exhausted.
#[inline(never)]
pub fn bench_publish_local<T: Message, const N: usize, const S: usize, const Q: usize>(
    topic: &Topic<T, N, S, Q>,
    value: T,
    now: Nanos,
) -> bool {
    topic.publisher().send(value, now).is_ok()
}

/// Takes and releases one message from every subscriber; returns how many were taken.
#[inline(never)]
pub fn bench_drain<T: Message, const N: usize, const S: usize, const Q: usize>(
    topic: &Topic<T, N, S, Q>,
) -> usize {
    let mut n = 0;
    for i in 0..S {
        if let Some(sub) = topic.subscriber_at(i) {
            if sub.try_recv().is_some() {
                n += 1;
            }
        }
    }
    n
}
