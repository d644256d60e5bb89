//! SRT/NRT transmit queue: EDF by absolute deadline, fixed capacity, O(log n).
//!
//! A binary min-heap on `(key, seq)`: `seq` is an insertion counter compared by wrapping
//! distance, so items with equal keys leave in insertion order (FIFO).
//! The 2014 C code kept a sorted linked list whose insert compared the wrong node after
//! commit 27d8cde (original-rtcan-code.md §5); a heap with an explicit tie-break cannot
//! get that order wrong.
use heapless::Vec;

/// Heap entry: the ordering key and where the item lives. Items never move while
/// queued; sifting swaps these 16-byte entries only (swapping whole items cost a
/// `memcpy` call per level on Cortex-M3).
#[derive(Clone, Copy, Debug)]
struct Entry {
    key: u64,
    seq: u32,
    slot: u8,
}

impl Entry {
    fn before(&self, other: &Self) -> bool {
        // `seq` wraps after 2^32 pushes; compare by wrapping distance so FIFO among
        // equal keys holds for any two entries less than 2^31 pushes apart.
        self.key < other.key
            || (self.key == other.key && (self.seq.wrapping_sub(other.seq) as i32) < 0)
    }
}

/// A min-queue on `key` (absolute bus-time deadline; NRT uses `u64::MAX`), FIFO among
/// equal keys, capacity `N` (at most 256), no allocation.
pub struct EdfQueue<T, const N: usize> {
    heap: Vec<Entry, N>,
    items: [Option<T>; N],
    seq: u32,
}

impl<T: Copy, const N: usize> EdfQueue<T, N> {
    /// Empty queue.
    pub const fn new() -> Self {
        EdfQueue {
            heap: Vec::new(),
            items: [None; N],
            seq: 0,
        }
    }
    /// Inserts; `Err(item)` when full (reported to the caller, never dropped silently).
    pub fn push(&mut self, key: u64, item: T) -> Result<(), T> {
        let Some(slot) = self
            .items
            .iter()
            .position(Option::is_none)
            .filter(|&s| s <= u8::MAX as usize)
        else {
            return Err(item);
        };
        let entry = Entry {
            key,
            seq: self.seq,
            slot: slot as u8,
        };
        if self.heap.push(entry).is_err() {
            return Err(item);
        }
        if let Some(place) = self.items.get_mut(slot) {
            *place = Some(item);
        }
        self.seq = self.seq.wrapping_add(1);
        self.sift_up(self.heap.len() - 1);
        Ok(())
    }
    /// Smallest key and its item.
    pub fn peek(&self) -> Option<(u64, &T)> {
        let e = self.heap.first()?;
        Some((e.key, self.items.get(e.slot as usize)?.as_ref()?))
    }
    /// Removes the smallest.
    pub fn pop(&mut self) -> Option<(u64, T)> {
        self.remove_at(0)
    }
    /// Removes and returns the smallest-key item satisfying `pred` (O(n) scan; used
    /// near window ends, where the most urgent frame may not fit but a shorter one does).
    pub fn pop_first_matching(
        &mut self,
        mut pred: impl FnMut(u64, &T) -> bool,
    ) -> Option<(u64, T)> {
        let mut best: Option<(usize, Entry)> = None;
        for (i, e) in self.heap.iter().enumerate() {
            if best.is_some_and(|(_, b)| !e.before(&b)) {
                continue;
            }
            if let Some(Some(item)) = self.items.get(e.slot as usize) {
                if pred(e.key, item) {
                    best = Some((i, *e));
                }
            }
        }
        let i = best.map(|(i, _)| i)?;
        self.remove_at(i)
    }
    /// Number of items.
    pub fn len(&self) -> usize {
        self.heap.len()
    }
    /// True if empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// True if full.
    pub fn is_full(&self) -> bool {
        self.heap.is_full()
    }
    /// Removes everything.
    pub fn clear(&mut self) {
        self.heap.clear();
        self.items = [None; N];
    }
    /// Items in heap order (not sorted).
    pub fn iter(&self) -> impl Iterator<Item = (u64, &T)> {
        self.heap
            .iter()
            .filter_map(|e| Some((e.key, self.items.get(e.slot as usize)?.as_ref()?)))
    }

    fn remove_at(&mut self, i: usize) -> Option<(u64, T)> {
        let last = self.heap.len().checked_sub(1)?;
        if i > last {
            return None;
        }
        self.swap(i, last);
        let e = self.heap.pop()?;
        if i < self.heap.len() {
            let i = self.sift_down(i);
            self.sift_up(i);
        }
        let item = self.items.get_mut(e.slot as usize)?.take()?;
        Some((e.key, item))
    }

    /// Exchanges two heap entries by value: `slice::swap` is the only user of the
    /// `memmove` routine in a firmware image (1.6 KiB on Cortex-M3).
    fn swap(&mut self, a: usize, b: usize) {
        // Two disjoint borrows, so the copy is a plain 16-byte move, never `memmove`.
        let (lo, hi) = (a.min(b), a.max(b));
        if lo == hi {
            return;
        }
        let (left, right) = self.heap.split_at_mut(hi);
        if let (Some(x), Some(y)) = (left.get_mut(lo), right.first_mut()) {
            core::mem::swap(x, y);
        }
    }

    fn before(&self, a: usize, b: usize) -> bool {
        match (self.heap.get(a), self.heap.get(b)) {
            (Some(x), Some(y)) => x.before(y),
            _ => false,
        }
    }

    fn sift_up(&mut self, mut i: usize) {
        while i > 0 {
            let parent = (i - 1) / 2;
            if !self.before(i, parent) {
                break;
            }
            self.swap(i, parent);
            i = parent;
        }
    }

    fn sift_down(&mut self, mut i: usize) -> usize {
        loop {
            let (l, r) = (2 * i + 1, 2 * i + 2);
            let mut m = i;
            if self.before(l, m) {
                m = l;
            }
            if self.before(r, m) {
                m = r;
            }
            if m == i {
                return i;
            }
            self.swap(i, m);
            i = m;
        }
    }
}

impl<T: Copy, const N: usize> Default for EdfQueue<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drain<const N: usize>(q: &mut EdfQueue<u32, N>) -> std::vec::Vec<(u64, u32)> {
        core::iter::from_fn(|| q.pop()).collect()
    }

    #[test]
    fn pops_in_deadline_order_fifo_among_equal_keys() {
        let mut q: EdfQueue<u32, 16> = EdfQueue::new();
        let keys = [50u64, 10, 30, 10, u64::MAX, 30, 10, 0, u64::MAX, 20];
        for (i, &k) in keys.iter().enumerate() {
            q.push(k, i as u32).unwrap();
        }
        assert_eq!(q.len(), 10);
        assert_eq!(q.peek(), Some((0, &7)));
        assert_eq!(
            drain(&mut q),
            [
                (0, 7),
                (10, 1),
                (10, 3),
                (10, 6),
                (20, 9),
                (30, 2),
                (30, 5),
                (50, 0),
                (u64::MAX, 4),
                (u64::MAX, 8)
            ]
        );
        assert!(q.is_empty());
        assert_eq!(q.pop(), None);
        assert_eq!(q.peek(), None);
    }

    #[test]
    fn full_queue_returns_the_item() {
        let mut q: EdfQueue<u32, 3> = EdfQueue::new();
        for i in 0..3 {
            assert_eq!(q.push(5, i), Ok(()));
        }
        assert!(q.is_full());
        assert_eq!(q.push(1, 99), Err(99));
        assert_eq!(q.len(), 3);
        assert_eq!(q.pop(), Some((5, 0)));
        assert_eq!(q.push(1, 99), Ok(()));
        assert_eq!(drain(&mut q), [(1, 99), (5, 1), (5, 2)]);
    }

    #[test]
    fn pop_first_matching_takes_the_most_urgent_match_and_keeps_heap_order() {
        let mut q: EdfQueue<u32, 8> = EdfQueue::default();
        // item = frame length in bits; only short ones fit the window end.
        for (k, bits) in [
            (10u64, 130u32),
            (20, 60),
            (20, 70),
            (5, 120),
            (40, 50),
            (20, 65),
        ] {
            q.push(k, bits).unwrap();
        }
        assert_eq!(q.pop_first_matching(|_, &b| b <= 70), Some((20, 60)));
        assert_eq!(q.pop_first_matching(|_, &b| b <= 70), Some((20, 70)));
        assert_eq!(q.pop_first_matching(|_, &b| b < 10), None);
        assert_eq!(q.pop_first_matching(|k, _| k > 30), Some((40, 50)));
        assert_eq!(drain(&mut q), [(5, 120), (10, 130), (20, 65)]);
    }

    #[test]
    fn matches_a_sorted_model_under_random_operations() {
        // xorshift: deterministic, no extra dev-dependency needed here.
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut q: EdfQueue<u32, 16> = EdfQueue::new();
        let mut model: std::vec::Vec<(u64, u64, u32)> = std::vec::Vec::new(); // (key, seq, item)
        let mut seq = 0;
        for step in 0..20_000u32 {
            match rnd() % 4 {
                0 | 1 => {
                    let k = rnd() % 8;
                    let r = q.push(k, step);
                    if model.len() < 16 {
                        assert_eq!(r, Ok(()));
                        model.push((k, seq, step));
                        seq += 1;
                    } else {
                        assert_eq!(r, Err(step));
                    }
                }
                2 => {
                    model.sort();
                    let want = (!model.is_empty())
                        .then(|| model.remove(0))
                        .map(|(k, _, i)| (k, i));
                    assert_eq!(q.pop(), want);
                }
                _ => {
                    let m = (rnd() % 3) as u32;
                    model.sort();
                    let pos = model.iter().position(|e| e.2 % 3 == m);
                    let want = pos.map(|p| model.remove(p)).map(|(k, _, i)| (k, i));
                    assert_eq!(q.pop_first_matching(|_, &i| i % 3 == m), want);
                }
            }
            assert_eq!(q.len(), model.len());
        }
    }
}
