//! The accumulated log-likelihood ratio of one auxiliary filter and its
//! windowed decision statistic (seed 004 eqs. 10, 13 and 15).
//!
//! Each epoch adds s_k(q) = ln p_q(y_k | Y_{k-1}) - ln p_A(y_k | Y_{k-1})
//! (eq. 9 with eqs. 11-12, each filter's density of its own data, see
//! `fdi` and docs/PF.md). The
//! accumulated LLR from j to k is S_j^k(q) = sum_{i=j..k} s_i(q) (eq. 10)
//! and the decision statistic is max over k - U < j <= k of S_j^k(q)
//! (eq. 13): the largest recent suffix sum.

use super::config::MAX_WINDOW;

/// The last [`MAX_WINDOW`] per-epoch LLRs of one auxiliary filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LlrWindow {
    values: [f64; MAX_WINDOW],
    len: usize,
    head: usize,
}

impl Default for LlrWindow {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl LlrWindow {
    /// No history (all zero).
    pub const EMPTY: Self = LlrWindow {
        values: [0.0; MAX_WINDOW],
        len: 0,
        head: 0,
    };

    /// Forgets the history (after a reinitialisation or an exclusion).
    pub fn clear(&mut self) {
        self.len = 0;
        self.head = 0;
    }

    /// Epochs stored.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when nothing is stored.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Appends this epoch's LLR s_k.
    pub fn push(&mut self, s: f64) {
        if let Some(v) = self.values.get_mut(self.head) {
            *v = s;
        }
        self.head = (self.head + 1) % MAX_WINDOW;
        self.len = (self.len + 1).min(MAX_WINDOW);
    }

    /// max over the last `u` start epochs j of S_j^k (eq. 13); -inf when
    /// empty. A NaN LLR makes the statistic NaN (which the monitor treats
    /// as an alarm, never as "all clear").
    pub fn windowed_max(&self, u: usize) -> f64 {
        let n = self.len.min(u);
        let mut sum = 0.0;
        let mut best = f64::NEG_INFINITY;
        for back in 0..n {
            let i = (self.head + MAX_WINDOW - 1 - back) % MAX_WINDOW;
            // i < MAX_WINDOW (a remainder), the ring's length.
            #[allow(clippy::indexing_slicing)]
            let v = self.values[i];
            sum += v;
            if sum > best || sum.is_nan() {
                best = sum;
            }
            if best.is_nan() {
                return f64::NAN;
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The windowed statistic against a brute-force max over all suffix
    /// sums of the last U values.
    #[test]
    fn windowed_max_is_the_best_recent_suffix_sum() {
        let seq = [1.0, -2.0, 3.0, -0.5, 2.0, -4.0, 1.5, 0.25];
        let mut w = LlrWindow::default();
        for (k, &s) in seq.iter().enumerate() {
            w.push(s);
            for u in 1..6 {
                let lo = (k + 1).saturating_sub(u);
                let brute = (lo..=k)
                    .map(|j| seq[j..=k].iter().sum::<f64>())
                    .fold(f64::NEG_INFINITY, f64::max);
                assert!((w.windowed_max(u) - brute).abs() < 1e-12, "k {k} u {u}");
            }
        }
        w.push(f64::NAN);
        assert!(w.windowed_max(3).is_nan());
        w.clear();
        assert_eq!(w.windowed_max(3), f64::NEG_INFINITY);
    }

    /// The ring wraps past MAX_WINDOW values.
    #[test]
    fn window_wraps() {
        let mut w = LlrWindow::default();
        for i in 0..(MAX_WINDOW + 5) {
            w.push(i as f64);
        }
        assert_eq!(w.len(), MAX_WINDOW);
        let last = (MAX_WINDOW + 4) as f64;
        assert_eq!(w.windowed_max(1), last);
        assert_eq!(w.windowed_max(2), last + last - 1.0);
    }
}
