//! SRT/NRT transmit queue: EDF by absolute deadline, fixed capacity, O(log n).
//! OWNER: scheduling helper. Signatures fixed.

/// A min-queue on `key` (absolute bus-time deadline; NRT uses `u64::MAX`), FIFO among
/// equal keys, capacity `N`, no allocation.
pub struct EdfQueue<T, const N: usize> {
    _p: core::marker::PhantomData<T>,
}

impl<T: Copy, const N: usize> EdfQueue<T, N> {
    /// Empty queue.
    pub const fn new() -> Self {
        todo!()
    }
    /// Inserts; `Err(item)` when full (reported to the caller, never dropped silently).
    pub fn push(&mut self, key: u64, item: T) -> Result<(), T> {
        let _ = (key, item);
        todo!()
    }
    /// Smallest key and its item.
    pub fn peek(&self) -> Option<(u64, &T)> {
        todo!()
    }
    /// Removes the smallest.
    pub fn pop(&mut self) -> Option<(u64, T)> {
        todo!()
    }
    /// Removes and returns the smallest-key item satisfying `pred` (O(n) scan; used
    /// near window ends, where the most urgent frame may not fit but a shorter one does).
    pub fn pop_first_matching(&mut self, pred: impl FnMut(u64, &T) -> bool) -> Option<(u64, T)> {
        let _ = pred;
        todo!()
    }
    /// Number of items.
    pub fn len(&self) -> usize {
        todo!()
    }
    /// True if empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl<T: Copy, const N: usize> Default for EdfQueue<T, N> {
    fn default() -> Self {
        Self::new()
    }
}
