//! The servo's two delays as fixed rings of timed samples, shared by the bench and
//! the simulator: the output angle's history (the sensing delay: the loop and Present
//! Position see the angle `sensing_delay` ago) and the goals sent but not yet in
//! force (the bus delay).

/// A ring of (time, value) samples, oldest first, with its room reserved when it is
/// made: pushing within that room never allocates (the simulator's step sizes it from
/// the delay and its time step). Pushed past its room it grows (the bench's variable
/// steps), so no sample a delay still needs is dropped.
#[derive(Debug, Clone, Default)]
pub struct Samples {
    buf: Vec<(f64, f64)>,
    start: usize,
    len: usize,
}

impl Samples {
    pub fn with_capacity(n: usize) -> Samples {
        Samples {
            buf: vec![(0.0, 0.0); n.max(1)],
            start: 0,
            len: 0,
        }
    }

    /// The room for `delay` seconds of samples taken every `dt`, and a margin: a
    /// ring trimmed by [`Samples::forget_before`] at `delay + 2 dt` holds at most
    /// `delay / dt + 5` samples just after a push.
    pub fn for_delay(delay: f64, dt: f64) -> Samples {
        let n = if delay > 0.0 && dt > 0.0 {
            (delay / dt).ceil() as usize + 8
        } else {
            2
        };
        Samples::with_capacity(n)
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn clear(&mut self) {
        self.start = 0;
        self.len = 0;
    }

    /// The `i`-th sample, oldest first (`i` below the ring's room).
    pub fn get(&self, i: usize) -> (f64, f64) {
        // A compare, not `%`: an integer division in every look-up of the bench's step.
        let k = self.start + i;
        let n = self.buf.len();
        self.buf[if k >= n { k - n } else { k }]
    }

    pub fn front(&self) -> Option<(f64, f64)> {
        (self.len > 0).then(|| self.get(0))
    }

    pub fn pop_front(&mut self) -> Option<(f64, f64)> {
        let s = self.front()?;
        self.start = if self.start + 1 == self.buf.len() {
            0
        } else {
            self.start + 1
        };
        self.len -= 1;
        Some(s)
    }

    pub fn push_back(&mut self, t: f64, x: f64) {
        if self.len == self.buf.len() {
            // Out of room: lay the ring out in order in one twice the size.
            let mut grown = Vec::with_capacity(2 * self.buf.len());
            grown.extend((0..self.len).map(|i| self.get(i)));
            grown.resize(2 * self.buf.len(), (0.0, 0.0));
            self.buf = grown;
            self.start = 0;
        }
        let (k, n) = (self.start + self.len, self.buf.len());
        self.buf[if k >= n { k - n } else { k }] = (t, x);
        self.len += 1;
    }

    /// Drop the samples older than the one at or before `keep` (two are always kept:
    /// the interpolation at `keep` needs the one before it).
    pub fn forget_before(&mut self, keep: f64) {
        while self.len > 2 && self.get(1).0 < keep {
            self.pop_front();
        }
    }

    /// The value at time `at`, linear between samples, `now` being the newest
    /// (time, value) not yet pushed; before the oldest sample (or at a NaN time), the
    /// oldest value. The times must not decrease.
    pub fn value_at(&self, at: f64, now: (f64, f64)) -> f64 {
        use std::cmp::Ordering::{Equal, Less};
        if self.len == 0 {
            return now.1;
        }
        // At or before `at`: not after it, nor unordered with it (a NaN time).
        let at_or_before = |t: f64| matches!(t.partial_cmp(&at), Some(Less | Equal));
        let (mut t, mut x) = self.get(0);
        if !at_or_before(t) {
            return x;
        }
        // The newest sample at or before `at`, searched from the oldest: a ring
        // trimmed by `forget_before` holds `at` near its start (one or two steps
        // instead of the delay's length).
        let mut k = 0;
        while k + 1 < self.len {
            let next = self.get(k + 1);
            if !at_or_before(next.0) {
                break;
            }
            (t, x) = next;
            k += 1;
        }
        let later = if k + 1 < self.len {
            self.get(k + 1)
        } else {
            now
        };
        let w = if later.0 > t {
            (at - t) / (later.0 - t)
        } else {
            0.0
        };
        x + w * (later.1 - x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ring_interpolates_and_grows_in_order() {
        let mut s = Samples::with_capacity(3);
        for k in 0..5 {
            s.push_back(k as f64, 10.0 * k as f64);
        }
        assert_eq!(s.len(), 5);
        assert_eq!(s.front(), Some((0.0, 0.0)));
        assert!((s.value_at(2.25, (5.0, 50.0)) - 22.5).abs() < 1e-12);
        assert!((s.value_at(4.5, (5.0, 50.0)) - 45.0).abs() < 1e-12);
        assert_eq!(s.value_at(-1.0, (5.0, 50.0)), 0.0);
        s.forget_before(3.0);
        assert_eq!(s.front(), Some((2.0, 20.0)));
        let mut r = Samples::with_capacity(4);
        for k in 0..40 {
            r.push_back(k as f64, k as f64);
            r.forget_before(k as f64 - 1.0);
        }
        assert!(r.len() <= 3 && r.buf.len() == 4);
    }
}
