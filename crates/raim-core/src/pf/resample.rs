//! Resampling on fixed arrays: systematic resampling done in place, and
//! the genetic operators of seed 004 step 4 (SPEC §10).

use crate::real::Real;

use super::model::DIM;
use super::rng::{self, PfRng};

/// Systematic resampling (one uniform offset, N evenly spaced pointers):
/// writes into `counts` how many copies of each particle survive. Each
/// particle gets floor(N w_i) or ceil(N w_i) copies, so the expected count
/// is exactly N w_i. `weights` are normalised (sum 1); the counts sum to N.
pub fn systematic_counts<T: Real>(weights: &[T], u0: f64, counts: &mut [u16]) {
    let n = weights.len().min(counts.len());
    let step = 1.0 / n.max(1) as f64;
    let mut pointer = u0.clamp(0.0, 1.0) * step;
    let mut cum = 0.0f64;
    let mut assigned = 0usize;
    for (w, c) in weights.iter().zip(counts.iter_mut()) {
        cum += w.to_f64();
        let mut k = 0u16;
        while assigned < n && pointer < cum {
            k = k.saturating_add(1);
            assigned += 1;
            pointer += step;
        }
        *c = k;
    }
    // Rounding may leave the last pointers unassigned: give them to the
    // last particle with weight, so the population stays N.
    if assigned < n {
        let missing = (n - assigned) as u16;
        if let Some((c, _)) = counts
            .iter_mut()
            .zip(weights.iter())
            .rev()
            .find(|(_, w)| w.to_f64() > 0.0)
        {
            *c = c.saturating_add(missing);
        } else if let Some(c) = counts.first_mut() {
            *c = c.saturating_add(missing);
        }
    }
}

/// Applies `counts` in place: a particle with k > 1 copies overwrites
/// k - 1 particles with 0 copies. No second particle buffer is needed.
pub fn apply_counts<T: Copy>(particles: &mut [[T; DIM]], counts: &[u16]) {
    let n = particles.len().min(counts.len());
    let mut hole = 0usize;
    for (src, &k) in counts.iter().enumerate().take(n) {
        for _ in 1..k {
            while hole < n && counts.get(hole) != Some(&0) {
                hole += 1;
            }
            if hole >= n {
                return;
            }
            if let Some(p) = particles.get(src).copied() {
                if let Some(dst) = particles.get_mut(hole) {
                    *dst = p;
                }
            }
            hole += 1;
        }
    }
}

/// The weight of rank round(N/3) in ascending order (seed 004 eqs. 3-4):
/// particles strictly below it are the "low" set.
pub fn rank_threshold<T: Real, const P: usize>(weights: &[T; P]) -> T {
    let mut sorted = *weights;
    let k = libm::round(P as f64 / 3.0) as usize;
    let k = k.min(P.saturating_sub(1));
    if P == 0 {
        return T::zero();
    }
    kth_smallest(&mut sorted, k).unwrap_or(T::zero())
}

/// The k-th smallest value of `v` (0-based), by quickselect with the
/// middle element as pivot (Lomuto partition), reordering `v`; `None` when
/// k >= v.len(). Every access is checked, so no input can make it panic
/// (`core`'s `select_nth_unstable_by` carries panic paths into the
/// firmware; docs/EVIDENCE.md "Panic sites"). A NaN compares as not less:
/// it never reaches here (the filter's collapse check), and it could only
/// change which value is returned, not end the loop, since every pass
/// shrinks the range by at least the pivot.
pub fn kth_smallest<T: Real>(v: &mut [T], k: usize) -> Option<T> {
    let less = |a: T, b: T| a.partial_cmp(&b) == Some(core::cmp::Ordering::Less);
    let (mut lo, mut hi) = (0usize, v.len());
    if k >= hi {
        return None;
    }
    while hi - lo > 1 {
        let last = hi - 1;
        swap(v, lo + (hi - lo) / 2, last);
        let pivot = *v.get(last)?;
        let mut store = lo;
        for i in lo..last {
            let x = *v.get(i)?;
            if less(x, pivot) {
                swap(v, i, store);
                store += 1;
            }
        }
        swap(v, store, last);
        match k.cmp(&store) {
            core::cmp::Ordering::Equal => break,
            core::cmp::Ordering::Less => hi = store,
            core::cmp::Ordering::Greater => lo = store + 1,
        }
    }
    v.get(k).copied()
}

/// `v.swap(a, b)` when both are in range (always, in `kth_smallest`).
fn swap<T>(v: &mut [T], a: usize, b: usize) {
    if a < v.len() && b < v.len() {
        v.swap(a, b);
    }
}

/// Metropolis acceptance of a candidate with log-likelihood `cand` against
/// the reference `against` (seed 004 step 4): always when better, else
/// with probability exp(cand - against). One uniform is drawn every call so
/// the random stream does not depend on the outcome.
pub fn metropolis<T: Real>(cand: T, against: T, rng: &mut PfRng) -> bool {
    let u = rng::uniform(rng);
    if !cand.is_finite() {
        return false;
    }
    cand >= against || u < libm::exp((cand - against).to_f64())
}

/// Crossover (seed 004 eqs. 5-6): x_m' = a x_m + (1 - a) x_n and x_n' =
/// a x_n + (1 - a) x_m, a ~ U(0, 1).
pub fn crossover<T: Real>(xm: &[T; DIM], xn: &[T; DIM], a: T) -> ([T; DIM], [T; DIM]) {
    let b = T::one() - a;
    let mut m = [T::zero(); DIM];
    let mut n = [T::zero(); DIM];
    for (((m, n), &pm), &pn) in m.iter_mut().zip(n.iter_mut()).zip(xm).zip(xn) {
        *m = a * pm + b * pn;
        *n = a * pn + b * pm;
    }
    (m, n)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    /// Weights that sum short of 1 (rounding, or a caller's error) leave
    /// pointers past the cumulative sum: they go to the last particle with
    /// weight, so the population stays N (weights 0.3, 0.3, 0.3, 0 with the
    /// pointers at 0.2475, 0.4975, 0.7475, 0.9975: one each, then the
    /// fourth to particle 2). All-zero weights give all N to the first.
    #[test]
    fn short_weights_keep_the_population() {
        let mut counts = [0u16; 4];
        systematic_counts(&[0.3f64, 0.3, 0.3, 0.0], 0.99, &mut counts);
        assert_eq!(counts, [1, 1, 2, 0]);
        systematic_counts(&[0.0f64; 4], 0.5, &mut counts);
        assert_eq!(counts, [4, 0, 0, 0]);
    }

    /// Counts that sum past the population (not produced by
    /// `systematic_counts`) fill the holes there are and stop: particle 0
    /// with 3 copies has one hole (index 2) to fill.
    #[test]
    fn excess_counts_stop_at_the_last_hole() {
        let mut p = [[0.0f64; DIM]; 3];
        for (i, row) in p.iter_mut().enumerate() {
            row[0] = i as f64 + 1.0;
        }
        apply_counts(&mut p, &[3, 1, 0]);
        assert_eq!(p.map(|r| r[0]), [1.0, 2.0, 1.0]);
    }

    /// The empty population's rank threshold is 0, and a rank at or past
    /// the length has no value.
    #[test]
    fn empty_and_out_of_range_ranks() {
        assert_eq!(rank_threshold::<f64, 0>(&[]), 0.0);
        let mut v = [3.0f64, 1.0, 2.0];
        assert_eq!(kth_smallest(&mut v, 3), None);
        assert_eq!(kth_smallest(&mut v, 2), Some(3.0));
        assert_eq!(kth_smallest::<f64>(&mut [], 0), None);
    }

    /// Systematic resampling: every count is floor or ceil of N w_i, the
    /// counts sum to N, and over many offsets the mean count is N w_i
    /// (the unbiasedness the filter relies on), to 0.01 copies.
    #[test]
    fn systematic_counts_match_expected_copies() {
        const N: usize = 10;
        const TOL_COPIES: f64 = 0.01;
        let raw = [0.3, 0.05, 0.05, 0.2, 0.0, 0.1, 0.1, 0.07, 0.08, 0.05];
        let sum: f64 = raw.iter().sum();
        let w: [f64; N] = core::array::from_fn(|i| raw[i] / sum);
        let mut mean = [0.0; N];
        let trials = 10_000;
        let mut counts = [0u16; N];
        for t in 0..trials {
            let u = (t as f64 + 0.5) / trials as f64;
            systematic_counts(&w, u, &mut counts);
            assert_eq!(counts.iter().map(|&c| c as usize).sum::<usize>(), N);
            for i in 0..N {
                let e = N as f64 * w[i];
                let c = counts[i] as f64;
                assert!(
                    c >= e.floor() - 1e-9 && c <= e.ceil() + 1e-9,
                    "{i}: {c} vs {e}"
                );
                mean[i] += c / trials as f64;
            }
        }
        for i in 0..N {
            assert!((mean[i] - N as f64 * w[i]).abs() < TOL_COPIES, "{i}");
        }
    }

    /// In-place application reproduces the multiset of copies.
    #[test]
    fn apply_counts_in_place() {
        let mut p: [[f64; DIM]; 5] = core::array::from_fn(|i| [i as f64; DIM]);
        let counts = [0u16, 3, 0, 1, 1];
        apply_counts(&mut p, &counts);
        let mut ids: [f64; 5] = core::array::from_fn(|i| p[i][0]);
        ids.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(ids, [1.0, 1.0, 1.0, 3.0, 4.0]);
    }

    /// The quickselect gives the value sorting gives, at every rank tried,
    /// with ties, and on an ascending input.
    #[test]
    fn kth_smallest_equals_the_sorted_order() {
        let mut rng = crate::testutil::Rng::new(7);
        for n in [1usize, 2, 3, 7, 100, 301] {
            let v: std::vec::Vec<f64> = (0..n)
                .map(|i| if i % 5 == 0 { 1.0 } else { rng.normal() })
                .collect();
            let mut sorted = v.clone();
            sorted.sort_by(|a, b| a.partial_cmp(b).unwrap());
            for k in [0, n / 3, n / 2, n - 1] {
                let mut w = v.clone();
                assert_eq!(kth_smallest(&mut w, k), Some(sorted[k]), "n {n} k {k}");
            }
            let mut w = v.clone();
            assert_eq!(kth_smallest(&mut w, n), None);
        }
        let mut ascending: std::vec::Vec<f64> = (0..200).map(f64::from).collect();
        assert_eq!(kth_smallest(&mut ascending, 66), Some(66.0));
    }

    /// The rank threshold is the weight of rank round(N/3) ascending, so
    /// round(N/3) particles are strictly below it (distinct weights).
    #[test]
    fn rank_threshold_is_the_third() {
        let w: [f64; 9] = [0.9, 0.1, 0.5, 0.3, 0.7, 0.2, 0.8, 0.4, 0.6];
        let t = rank_threshold(&w);
        assert_eq!(t, 0.4);
        assert_eq!(w.iter().filter(|&&x| x < t).count(), 3);
    }

    /// Crossover keeps the pair's sum (a convex exchange) and Metropolis
    /// accepts a worse candidate at the rate exp(d) (within 0.01).
    ///
    /// Verifies: SPEC-10
    #[test]
    fn crossover_and_metropolis() {
        let a = [1.0f64; DIM];
        let b = [3.0; DIM];
        let (m, n) = crossover(&a, &b, 0.25);
        assert!((m[0] - 2.5).abs() < 1e-12 && (n[0] - 1.5).abs() < 1e-12);
        let mut rng = rng::seeded(3);
        let trials = 40_000;
        let acc = (0..trials)
            .filter(|_| metropolis(-1.0f64, 0.0, &mut rng))
            .count();
        assert!((acc as f64 / trials as f64 - (-1.0f64).exp()).abs() < 0.01);
        assert!(metropolis(1.0f64, 0.0, &mut rng));
        assert!(!metropolis(f64::NAN, 0.0, &mut rng));
    }
}
