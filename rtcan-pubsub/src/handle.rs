//! Handles to pool blocks: `Loan` (owned by the publisher before publish, mutable) and
//! `Msg` (a subscriber's shared reference). Dropping either returns the reference; the
//! block goes back to the pool with the last one.
use core::ops::{Deref, DerefMut};

use rtcan_core::time::Nanos;

use crate::message::Message;
use crate::topic::Topic;

/// A block allocated by a publisher, filled and not yet published.
pub struct Loan<'a, T: Message, const N: usize, const S: usize, const Q: usize> {
    pub(crate) topic: &'a Topic<T, N, S, Q>,
    pub(crate) idx: u8,
}

impl<'a, T: Message, const N: usize, const S: usize, const Q: usize> Loan<'a, T, N, S, Q> {
    /// Gives up ownership without releasing (the caller transfers the reference).
    pub(crate) fn into_idx(self) -> u8 {
        let idx = self.idx;
        core::mem::forget(self);
        idx
    }
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> Deref for Loan<'_, T, N, S, Q> {
    type Target = T;
    fn deref(&self) -> &T {
        // SAFETY: initialised by `alloc_idx`; the loan is the only reference.
        unsafe { (*self.topic.value_cell(self.idx).get()).assume_init_ref() }
    }
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> DerefMut for Loan<'_, T, N, S, Q> {
    fn deref_mut(&mut self) -> &mut T {
        // SAFETY: as in `deref`, and `&mut self` makes this access exclusive.
        unsafe { (*self.topic.value_cell(self.idx).get()).assume_init_mut() }
    }
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> Drop for Loan<'_, T, N, S, Q> {
    fn drop(&mut self) {
        self.topic.release(self.idx);
    }
}

/// A received message: a shared, refcounted reference to the block the publisher
/// filled (zero copy). Hold it as long as needed; drop it to release.
pub struct Msg<'a, T: Message, const N: usize, const S: usize, const Q: usize> {
    pub(crate) topic: &'a Topic<T, N, S, Q>,
    pub(crate) idx: u8,
    pub(crate) stamp: Nanos,
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> Msg<'_, T, N, S, Q> {
    /// Local time of publication (start of frame for a message from the bus).
    pub fn stamp(&self) -> Nanos {
        self.stamp
    }
    /// Pool block index (diagnostics and tests).
    pub fn block(&self) -> u8 {
        self.idx
    }
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> Deref for Msg<'_, T, N, S, Q> {
    type Target = T;
    fn deref(&self) -> &T {
        // SAFETY: published blocks are initialised and never written while referenced.
        unsafe { (*self.topic.value_cell(self.idx).get()).assume_init_ref() }
    }
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> Drop for Msg<'_, T, N, S, Q> {
    fn drop(&mut self) {
        self.topic.release(self.idx);
    }
}

impl<T: Message + core::fmt::Debug, const N: usize, const S: usize, const Q: usize> core::fmt::Debug
    for Msg<'_, T, N, S, Q>
{
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Msg")
            .field("value", &**self)
            .field("stamp", &self.stamp)
            .finish()
    }
}

impl<T: Message + core::fmt::Debug, const N: usize, const S: usize, const Q: usize> core::fmt::Debug
    for Loan<'_, T, N, S, Q>
{
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Loan")
            .field("value", &**self)
            .field("block", &self.idx)
            .finish()
    }
}
