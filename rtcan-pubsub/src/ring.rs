//! Fixed-capacity FIFO of pool block indices (one per subscriber queue and one for
//! the blocks handed to the engine). Always used inside a critical section.

/// FIFO of at most `Q` (≤ 255) block indices.
pub(crate) struct Ring<const Q: usize> {
    buf: [u8; Q],
    head: u8,
    len: u8,
}

impl<const Q: usize> Ring<Q> {
    pub(crate) const EMPTY: Self = Ring {
        buf: [0; Q],
        head: 0,
        len: 0,
    };

    pub(crate) fn len(&self) -> usize {
        usize::from(self.len)
    }

    pub(crate) fn is_full(&self) -> bool {
        usize::from(self.len) >= Q
    }

    /// `false` (and nothing stored) when full.
    #[inline(always)]
    pub(crate) fn push(&mut self, v: u8) -> bool {
        if self.is_full() {
            return false;
        }
        // head < Q and len < Q, so one subtraction wraps (no division on Cortex-M3).
        let mut pos = usize::from(self.head) + usize::from(self.len);
        if pos >= Q {
            pos -= Q;
        }
        match self.buf.get_mut(pos) {
            Some(slot) => {
                *slot = v;
                self.len += 1;
                true
            }
            None => false,
        }
    }

    pub(crate) fn peek(&self) -> Option<u8> {
        if self.len == 0 {
            return None;
        }
        self.buf.get(usize::from(self.head)).copied()
    }

    #[inline(always)]
    pub(crate) fn pop(&mut self) -> Option<u8> {
        let v = self.peek()?;
        self.head += 1;
        if usize::from(self.head) >= Q {
            self.head = 0;
        }
        self.len -= 1;
        Some(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fifo_order_and_wrap() {
        let mut r = Ring::<3>::EMPTY;
        assert!(r.push(1) && r.push(2) && r.push(3));
        assert!(!r.push(4), "full ring refuses");
        assert_eq!(r.pop(), Some(1));
        assert!(r.push(4));
        assert_eq!(
            [r.pop(), r.pop(), r.pop(), r.pop()],
            [Some(2), Some(3), Some(4), None]
        );
        assert_eq!(r.len(), 0);
    }
}
