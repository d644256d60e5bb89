//! A time series kept in bounded memory: every sample while there is room, then every
//! second one, every fourth, … (the stride doubles each time the buffer fills), and
//! always the latest. Plots and tables of a long run stay the same size.

/// Samples kept at most (the latest comes on top).
pub const KEEP: usize = 4096;

/// A decimated series.
#[derive(Clone, Debug, PartialEq)]
pub struct Decimated<T> {
    kept: Vec<T>,
    stride: u64,
    seen: u64,
    last: Option<T>,
}

impl<T> Default for Decimated<T> {
    fn default() -> Self {
        Decimated {
            kept: Vec::new(),
            stride: 1,
            seen: 0,
            last: None,
        }
    }
}

impl<T: Clone> Decimated<T> {
    /// Offers the next sample.
    pub fn push(&mut self, v: T) {
        if self.seen.is_multiple_of(self.stride) {
            if self.kept.len() == KEEP {
                // Keep samples 0, 2, 4, … (indices multiple of the doubled stride).
                let mut i = 0;
                self.kept.retain(|_| {
                    i += 1;
                    i % 2 == 1
                });
                self.stride *= 2;
            }
            if self.seen.is_multiple_of(self.stride) {
                self.kept.push(v.clone());
            }
        }
        self.seen += 1;
        self.last = Some(v);
    }

    /// Samples offered.
    pub fn seen(&self) -> u64 {
        self.seen
    }

    /// The kept samples in order, ending with the latest.
    pub fn into_vec(self) -> Vec<T> {
        let mut v = self.kept;
        let stride = self.stride;
        if let Some(l) = self.last {
            // The latest is already the last kept one when its index is on the stride.
            if !(self.seen - 1).is_multiple_of(stride) {
                v.push(l);
            }
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_everything_then_every_other_and_the_latest() {
        let mut d = Decimated::default();
        for k in 0..100u64 {
            d.push(k);
        }
        assert_eq!(d.clone().into_vec(), (0..100).collect::<Vec<_>>());
        let mut d = Decimated::default();
        let n = 10 * KEEP as u64 + 3;
        for k in 0..n {
            d.push(k);
        }
        assert_eq!(d.seen(), n);
        let v = d.into_vec();
        assert!(v.len() <= KEEP + 1, "{}", v.len());
        assert!(v.len() > KEEP / 2);
        assert_eq!(v.first(), Some(&0));
        assert_eq!(v.last(), Some(&(n - 1)));
        // Evenly spaced (the stride) but for the latest.
        let stride = v[1] - v[0];
        assert!(v
            .windows(2)
            .take(v.len() - 2)
            .all(|w| w[1] - w[0] == stride));
        assert_eq!(stride, 16);
    }
}
