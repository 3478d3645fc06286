//! Householder QR on fixed stack buffers (SPEC §2).
//!
//! `H = U T = [U1 U2] [T1; 0]`, with `n` active rows out of a capacity of `N`
//! and `m <= MAX_STATES` columns. The reflections are kept (LAPACK style, one
//! unit vector per column) so that `U` is never formed: `U^T x` and `U x` are
//! applied on demand. nalgebra's `QR` needs a heap for dynamic sizes and its
//! `solve` panics on non-square systems, hence this small routine.

use crate::error::RaimError;
use crate::measurement::MAX_STATES;
use crate::real::Real;

/// A column whose Householder pivot falls below this fraction of the
/// column's own norm is treated as linearly dependent (rank deficiency).
/// 1e-9 keeps condition numbers up to ~1e9 (GDOP in the hundreds of
/// thousands), far beyond anything a protection level could use.
pub const RANK_TOLERANCE: f64 = 1e-9;

/// The rank tolerance in precision `T`: [`RANK_TOLERANCE`], but never below
/// 100 machine epsilons (1.2e-5 in f32), under which a pivot is rounding
/// noise: in f32 a dependent column leaves a pivot of ~1e-7, which 1e-9
/// would accept.
pub fn rank_tolerance<T: Real>() -> T {
    let floor = 100.0 * T::EPS.to_f64();
    T::of(if floor > RANK_TOLERANCE {
        floor
    } else {
        RANK_TOLERANCE
    })
}

/// The factorisation of an `n x m` matrix, column-major, in precision `T`
/// (the engine's on the statistics path, f32 on the device; `f64` by
/// default).
#[derive(Debug, Clone)]
pub struct Householder<const N: usize, T: Real = f64> {
    n: usize,
    m: usize,
    /// Column k holds the unit Householder vector v_k in rows k..n, and the
    /// strictly upper part of T in rows 0..k of later columns.
    a: [[T; N]; MAX_STATES],
    /// Diagonal of T.
    diag: [T; MAX_STATES],
}

impl<const N: usize, T: Real> Householder<N, T> {
    /// An empty factorisation (0 x 0), to be filled by [`Self::factor_from`].
    pub const fn empty() -> Self {
        Householder {
            n: 0,
            m: 0,
            a: [[T::ZERO; N]; MAX_STATES],
            diag: [T::ZERO; MAX_STATES],
        }
    }

    /// Factor the first `n` rows and `m` columns of the column-major `h`.
    pub fn factor(h: &[[T; N]; MAX_STATES], n: usize, m: usize) -> Result<Self, RaimError> {
        let mut qr = Self::empty();
        qr.factor_from(h, n, m)?;
        Ok(qr)
    }

    /// [`Self::factor`] into existing storage (no N-sized value on the stack).
    pub fn factor_from(
        &mut self,
        h: &[[T; N]; MAX_STATES],
        n: usize,
        m: usize,
    ) -> Result<(), RaimError> {
        if n > N {
            return Err(RaimError::CapacityExceeded {
                have: n,
                capacity: N,
            });
        }
        if m > MAX_STATES || m == 0 || n < m {
            return Err(RaimError::TooFewSatellites {
                have: n,
                need: m.max(1),
            });
        }
        self.n = n;
        self.m = m;
        self.a = *h;
        self.diag = [T::zero(); MAX_STATES];
        // The usual models (one or two constellations) with the column
        // count fixed at compile time, where the column loop unrolls
        // : the same steps, so the same
        // bits. In the f64 (host) engine only, with the lanes: on the M4F
        // each copy would cost flash.
        if T::LANE_SUMS {
            match m {
                4 => return self.columns(4, n),
                5 => return self.columns(5, n),
                _ => {}
            }
        }
        self.columns(m, n)
    }

    /// The Householder steps over columns 0..m of the copied matrix.
    #[inline(always)]
    fn columns(&mut self, m: usize, n: usize) -> Result<(), RaimError> {
        for k in 0..m {
            let (left, right) = self.a.split_at_mut(k + 1);
            let Some(col) = left.last_mut() else {
                return Err(RaimError::RankDeficient {
                    column: k,
                    pivot: 0.0,
                });
            };
            let (head, rest) = col.split_at_mut(k);
            let Some(tail) = rest.get_mut(..n - k) else {
                return Err(RaimError::TooFewSatellites { have: n, need: m });
            };
            let (alpha, full_norm, ok) = make_reflector(tail, head);
            if !ok {
                return Err(RaimError::RankDeficient {
                    column: k,
                    pivot: if full_norm > T::zero() {
                        (alpha / full_norm).to_f64()
                    } else {
                        0.0
                    },
                });
            }
            if let Some(d) = self.diag.get_mut(k) {
                *d = alpha;
            }
            for other in right.iter_mut().take(m - k - 1) {
                reflect(col, other, k, n);
            }
        }
        Ok(())
    }

    /// Number of rows n of the factored matrix.
    pub fn rows(&self) -> usize {
        self.n
    }

    /// Number of columns m of the factored matrix.
    pub fn cols(&self) -> usize {
        self.m
    }

    /// x <- U^T x (first n entries). Entries m..n are then the parity
    /// vector U2^T x (SPEC §2).
    pub fn apply_ut(&self, x: &mut [T; N]) {
        for col in self.a.iter().take(self.m).enumerate() {
            reflect(col.1, x, col.0, self.n);
        }
    }

    /// x <- U x (first n entries): the inverse of [`Self::apply_ut`].
    pub fn apply_u(&self, x: &mut [T; N]) {
        for (k, col) in self.a.iter().take(self.m).enumerate().rev() {
            reflect(col, x, k, self.n);
        }
    }

    /// `T1[i][j]` for i <= j < m, zero below the diagonal.
    // In range: i <= j < m, and `factor_from` sets m only with
    // m <= MAX_STATES (the columns, the diagonal) and m <= n <= N (the rows).
    #[allow(clippy::indexing_slicing)]
    pub fn t(&self, i: usize, j: usize) -> T {
        if i > j || j >= self.m {
            T::zero()
        } else if i == j {
            self.diag[i]
        } else {
            self.a[j][i]
        }
    }

    /// The first `M` columns of T1, dense: `(t, d)` with `t[j][i]` =
    /// T1[i][j] for i < j (zero elsewhere) and `d` its diagonal. For
    /// the fixed-size row loops of [`crate::linalg::parity`],
    /// which perform [`Self::solve_tt`]'s and [`Self::solve_t`]'s
    /// operations in the same order on these copies.
    pub(crate) fn triangle<const M: usize>(&self) -> ([[T; M]; M], [T; M]) {
        let mut t = [[T::zero(); M]; M];
        let mut d = [T::zero(); M];
        for (j, ((dst, src), (dj, sj))) in t
            .iter_mut()
            .zip(self.a.iter())
            .zip(d.iter_mut().zip(self.diag.iter()))
            .enumerate()
        {
            for (x, y) in dst.iter_mut().zip(src.iter()).take(j) {
                *x = *y;
            }
            *dj = *sj;
        }
        (t, d)
    }

    /// Solve T1 x = y for the first m entries (column-oriented back
    /// substitution: column j of T1 above the diagonal is stored in `a[j][..j]`).
    pub fn solve_t(&self, y: &[T; MAX_STATES]) -> [T; MAX_STATES] {
        let mut x = *y;
        for j in (0..self.m).rev() {
            let (Some(col), Some(&d)) = (self.a.get(j), self.diag.get(j)) else {
                continue;
            };
            let (head, tail) = x.split_at_mut(j);
            let Some(xj) = tail.first_mut() else {
                continue;
            };
            // The diagonal was checked non-zero in `factor`.
            *xj /= d;
            let v = *xj;
            for (xi, t) in head.iter_mut().zip(col.iter()) {
                *xi -= *t * v;
            }
        }
        for v in x.iter_mut().skip(self.m) {
            *v = T::zero();
        }
        x
    }

    /// Solve T1^T x = y (forward substitution: row i of T1^T is column i
    /// of T1, stored in `a[i][..i]`).
    pub fn solve_tt(&self, y: &[T; MAX_STATES]) -> [T; MAX_STATES] {
        let mut x = [T::zero(); MAX_STATES];
        for (i, (col, &d)) in self.a.iter().zip(self.diag.iter()).take(self.m).enumerate() {
            let Some((head, tail)) = x.split_at_mut_checked(i) else {
                break;
            };
            let dot = dot(head.iter(), col.iter());
            if let (Some(xi), Some(yi)) = (tail.first_mut(), y.get(i)) {
                *xi = (*yi - dot) / d;
            }
        }
        x
    }
}

/// sum a_i b_i, left to right (the order of the f64 `Iterator::sum` it
/// replaces, so f64 results are unchanged).
#[inline(always)]
pub(crate) fn dot<'a, T: Real>(
    a: impl Iterator<Item = &'a T>,
    b: impl Iterator<Item = &'a T>,
) -> T {
    a.zip(b).fold(T::zero(), |acc, (x, y)| acc + *x * *y)
}

/// The scaled 2-norm (overflow- and underflow-safe, one or two divisions
/// per element): the fallback of [`make_reflector`] outside the range of
/// its unscaled sum of squares.
fn norm<'a, T: Real>(it: impl Iterator<Item = &'a T>) -> T {
    // Scaled to avoid overflow on huge (ECEF-sized) entries.
    let mut scale = T::zero();
    let mut ssq = T::one();
    for &v in it {
        let a = v.abs();
        if a > T::zero() {
            if scale < a {
                ssq = T::one() + ssq * (scale / a) * (scale / a);
                scale = a;
            } else {
                ssq += (a / scale) * (a / scale);
            }
        }
    }
    scale * ssq.sqrt()
}

/// sum x_i^2, unscaled: left to right, or in lanes ([`dot_lanes`]) where
/// [`Kernels::LANE_SUMS`](crate::linalg::Kernels::LANE_SUMS).
#[inline(always)]
fn sum_sq<T: Real>(x: &[T]) -> T {
    if T::LANE_SUMS {
        return dot_lanes(x, x);
    }
    x.iter().fold(T::zero(), |acc, v| acc + *v * *v)
}

/// The number of interleaved partial sums of [`dot_lanes`].
const LANES: usize = 4;

/// sum a_i b_i over the shorter of the two slices, in [`LANES`] partial
/// sums: term i goes to sum i mod 4 (for the first multiple of 4 terms),
/// the sums are added pairwise, (s0 + s2) + (s1 + s3), then the remaining
/// terms left to right. The same sum as [`dot`] up to rounding (each order
/// is within n eps sum |a_i b_i| of the exact value), in a loop the
/// compiler vectorises (the reflections'
/// sequential sums were a fifth of a clean epoch's QR).
#[inline(always)]
pub(crate) fn dot_lanes<T: Real>(a: &[T], b: &[T]) -> T {
    let (ca, ra) = a.as_chunks::<LANES>();
    let (cb, rb) = b.as_chunks::<LANES>();
    let mut acc = [T::zero(); LANES];
    for (x, y) in ca.iter().zip(cb.iter()) {
        for ((s, xi), yi) in acc.iter_mut().zip(x.iter()).zip(y.iter()) {
            *s += *xi * *yi;
        }
    }
    let [s0, s1, s2, s3] = acc;
    let mut sum = (s0 + s2) + (s1 + s3);
    // The tails: equal lengths (the callers' case) leave both remainders
    // aligned; unequal lengths stop at the shorter chunked part.
    let done = ca.len().min(cb.len()) * LANES;
    if ca.len() == cb.len() {
        for (x, y) in ra.iter().zip(rb.iter()) {
            sum += *x * *y;
        }
    } else if let (Some(x), Some(y)) = (a.get(done..), b.get(done..)) {
        for (x, y) in x.iter().zip(y.iter()) {
            sum += *x * *y;
        }
    }
    sum
}

/// Whether an unscaled sum of squares can be used as it is: finite, at
/// most `T::MAX / 8` (so that 2 sigma (sigma + |x0|) <= 4 sigma^2 stays
/// finite), and at least `T::MIN_POSITIVE / T::EPS` (so that every term
/// lost to underflow, each below `T::MIN_POSITIVE`, is below an epsilon of
/// the sum). In f32 that is a column norm between 3.3e-16 and 6.5e18, in
/// f64 between 1.0e-146 and 1.5e154.
#[inline(always)]
fn ssq_in_range<T: Real>(ssq: T) -> bool {
    ssq >= T::MIN_POSITIVE / T::EPS && ssq <= T::MAX / T::of(8.0)
}

/// sqrt(a^2 + b^2) for a, b >= 0 without overflow: the larger times
/// sqrt(1 + (smaller / larger)^2); exactly `b` when `a` is zero.
fn hypot_nonneg<T: Real>(a: T, b: T) -> T {
    let (big, small) = if a > b { (a, b) } else { (b, a) };
    if !(big > T::zero()) || !(small > T::zero()) {
        return big;
    }
    let q = small / big;
    big * (T::one() + q * q).sqrt()
}

/// Turn `x` (rows k..n of a column) into the unit Householder vector v with
/// (I - 2 v v^T) x = alpha e1 (SPEC §2). `head` is the column's rows 0..k
/// (the entries of T1 already formed), so the column's full norm, the
/// scale of the rank test, is that of head and x together: the reflections
/// before k are orthogonal and leave it unchanged.
///
/// In f64 ([`Kernels::ONE_PASS_QR`](crate::linalg::Kernels::ONE_PASS_QR)): one unscaled
/// pass of sum x_i^2 gives sigma = ||x||, the full norm
/// sqrt(|head|^2 + sigma^2), and ||v|| comes in closed form,
/// ||x - alpha e1||^2 = 2 sigma (sigma + |x0|) (alpha = -sign(x0) sigma),
/// instead of two scaled passes with two divisions per element. The
/// whitened GNSS rows are O(1/sigma_i): entries at most 1/sigma_i in
/// magnitude (unit lines of sight and unit clock entries divided by the
/// pseudorange sigma), so the sums are far inside [`ssq_in_range`] for any
/// sigma between 1e-140 m and 1e140 m; outside that range (and for a zero
/// column) the scaled two-pass form, [`make_reflector_scaled`], is used.
/// Both give the same quantities up to rounding, and the rank test is the
/// same test ([`rank_tolerance`] against the full norm). The f32 engine
/// keeps the scaled form bit for bit (see [`Kernels::ONE_PASS_QR`](crate::linalg::Kernels::ONE_PASS_QR)).
/// Returns alpha, the column's norm and whether the pivot is usable.
fn make_reflector<T: Real>(x: &mut [T], head: &[T]) -> (T, T, bool) {
    if !T::ONE_PASS_QR {
        return make_reflector_scaled(x, norm(head.iter()));
    }
    let ssq = sum_sq(x);
    let total = sum_sq(head) + ssq;
    if !(ssq_in_range(ssq) && total <= T::MAX / T::of(8.0)) {
        return make_reflector_scaled(x, norm(head.iter()));
    }
    let sigma = ssq.sqrt();
    let full_norm = total.sqrt();
    let Some(x0) = x.first_mut() else {
        return (T::zero(), full_norm, false);
    };
    let a0 = x0.abs();
    let alpha = if *x0 >= T::zero() { -sigma } else { sigma };
    if !(sigma > rank_tolerance::<T>() * full_norm) {
        return (sigma, full_norm, false);
    }
    // v = x - alpha e1, then normalise by ||v|| in closed form.
    *x0 -= alpha;
    // A division per element, not a multiplication by 1 / ||v||: the same
    // instruction count, and half an ulp per entry instead of up to one and
    // a half (tried in f32: the slopes of the test
    // `protection_levels_match_brute_force_worst_bias` moved 5x more).
    let vnorm = (T::of(2.0) * sigma * (sigma + a0)).sqrt();
    for v in x.iter_mut() {
        *v /= vnorm;
    }
    (alpha, full_norm, true)
}

/// [`make_reflector`] by the scaled norms (two passes, a division per
/// element): in f32, and in f64 for columns whose sum of squares would
/// overflow or underflow.
/// `head_norm` is the norm of the column's rows 0..k, so the full norm is
/// hypot(head_norm, sigma).
fn make_reflector_scaled<T: Real>(x: &mut [T], head_norm: T) -> (T, T, bool) {
    let sigma = norm(x.iter());
    let full_norm = hypot_nonneg(head_norm, sigma);
    let Some(x0) = x.first_mut() else {
        return (T::zero(), full_norm, false);
    };
    let alpha = if *x0 >= T::zero() { -sigma } else { sigma };
    if !(sigma > rank_tolerance::<T>() * full_norm) || !sigma.is_finite() {
        return (sigma, full_norm, false);
    }
    // v = x - alpha e1, then normalise.
    *x0 -= alpha;
    let vnorm = norm(x.iter());
    if !(vnorm > T::zero()) {
        return (sigma, full_norm, false);
    }
    for v in x.iter_mut() {
        *v /= vnorm;
    }
    (alpha, full_norm, true)
}

/// y[k..n] <- (I - 2 v v^T) y[k..n] with v stored in col[k..n].
#[inline(always)]
fn reflect<const N: usize, T: Real>(col: &[T; N], y: &mut [T; N], k: usize, n: usize) {
    // On the slices k..n directly (`take(n).skip(k)` over the
    // whole buffer cost a third more instructions); the same operations.
    let (Some(v), Some(w)) = (col.get(k..n), y.get_mut(k..n)) else {
        return;
    };
    let d = if T::LANE_SUMS {
        dot_lanes(v, w)
    } else {
        v.iter()
            .zip(w.iter())
            .fold(T::zero(), |acc, (v, w)| acc + *v * *w)
    };
    let f = d + d;
    for (v, w) in v.iter().zip(w.iter_mut()) {
        *w -= f * *v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reproduces_a_small_least_squares_solution() {
        // Fit y = a + b t through (0,1),(1,3),(2,5),(3,7.5): normal equations
        // give b = 2.15, a = 0.9 (computed by hand: sum t = 6, sum t^2 = 14,
        // sum y = 16.5, sum t y = 35.5).
        let mut h = [[0.0; 8]; MAX_STATES];
        h[0][..4].copy_from_slice(&[1.0, 1.0, 1.0, 1.0]);
        h[1][..4].copy_from_slice(&[0.0, 1.0, 2.0, 3.0]);
        let qr = Householder::<8>::factor(&h, 4, 2).unwrap();
        let mut y = [0.0; 8];
        y[..4].copy_from_slice(&[1.0, 3.0, 5.0, 7.5]);
        qr.apply_ut(&mut y);
        let mut rhs = [0.0; MAX_STATES];
        rhs[..2].copy_from_slice(&y[..2]);
        let x = qr.solve_t(&rhs);
        assert!((x[0] - 0.9).abs() < 1e-12, "{x:?}");
        assert!((x[1] - 2.15).abs() < 1e-12, "{x:?}");
        // Residual sum of squares = |y[2..4]|^2: residuals 0.1,-0.05,-0.2,0.15
        let rss = y[2] * y[2] + y[3] * y[3];
        assert!((rss - 0.075).abs() < 1e-12, "{rss}");
        // U U^T x = x
        let mut v = [0.0; 8];
        v[..4].copy_from_slice(&[0.3, -1.0, 2.0, 4.0]);
        let orig = v;
        qr.apply_ut(&mut v);
        qr.apply_u(&mut v);
        for i in 0..4 {
            assert!((v[i] - orig[i]).abs() < 1e-12);
        }
    }

    /// The rank test's column norm from the head and the pivot:
    /// hypot(a, b) against the direct sqrt(a^2 + b^2) (1 ulp-level, f64),
    /// exactly b for a = 0, and no overflow where a^2 would overflow.
    #[test]
    fn column_norm_from_head_and_pivot() {
        const REL_TOL: f64 = 4.0 * f64::EPSILON;
        let mut rng = crate::testutil::Rng::new(3);
        for _ in 0..1000 {
            let (a, b) = (rng.uniform() * 10.0, rng.uniform() * 1e-3);
            let direct = (a * a + b * b).sqrt();
            assert!((hypot_nonneg(a, b) - direct).abs() <= REL_TOL * direct);
            assert!((hypot_nonneg(b, a) - direct).abs() <= REL_TOL * direct);
            assert_eq!(hypot_nonneg(0.0, b), b);
        }
        assert_eq!(hypot_nonneg(0.0f64, 0.0), 0.0);
        let big = hypot_nonneg(3e200f64, 4e200);
        assert!((big - 5e200).abs() <= REL_TOL * 5e200, "{big}");
        let big32 = hypot_nonneg(3e30f32, 4e30);
        assert!((big32 / 5e30 - 1.0).abs() < 1e-6, "{big32}");
    }

    /// The unscaled one-pass reflector and the scaled two-pass fallback
    /// (taken when the column's sum of squares would overflow or underflow)
    /// agree up to rounding: the same matrix scaled by powers of two (exact)
    /// into and out of the unscaled range gives T1 scaled by the same power
    /// and the same unit Householder vectors, in f64 and f32; a dependent
    /// column is still `RankDeficient` at every scale.
    #[test]
    fn reflector_fallback_agrees_with_the_unscaled_pass() {
        fn check<T: Real>(exponents: &[i32], rel_tol: f64) {
            let mut rng = crate::testutil::Rng::new(11);
            let (n, m) = (9, 5);
            let mut h = [[T::zero(); 12]; MAX_STATES];
            for col in h.iter_mut().take(m) {
                for v in col.iter_mut().take(n) {
                    *v = T::of(rng.uniform() * 2.0 - 1.0);
                }
            }
            let base = Householder::<12, T>::factor(&h, n, m).unwrap();
            for &e in exponents {
                let s = T::of(2f64.powi(e));
                let mut hs = h;
                for col in hs.iter_mut() {
                    for v in col.iter_mut() {
                        *v *= s;
                    }
                }
                let big = T::MAX / T::of(8.0);
                let tiny = T::MIN_POSITIVE / T::EPS;
                let norm2 = sum_sq(&hs[0][..n]);
                assert!(
                    !(norm2 >= tiny && norm2 <= big),
                    "2^{e} must take the fallback"
                );
                let q = Householder::<12, T>::factor(&hs, n, m).unwrap();
                for j in 0..m {
                    for i in 0..=j {
                        let (a, b) = (q.t(i, j) / s, base.t(i, j));
                        let err = (a - b).abs().to_f64();
                        assert!(
                            err <= rel_tol * base.t(j, j).abs().to_f64().max(1.0),
                            "2^{e} T[{i}][{j}] {a:?} {b:?}"
                        );
                    }
                    for i in j..n {
                        let err = (q.a[j][i] - base.a[j][i]).abs().to_f64();
                        assert!(err <= rel_tol, "2^{e} v[{j}][{i}]");
                    }
                }
                let mut dep = hs;
                dep[1] = dep[0];
                assert!(matches!(
                    Householder::<12, T>::factor(&dep, n, m),
                    Err(RaimError::RankDeficient { column: 1, .. })
                ));
            }
        }
        // Dimensionless: a few tens of epsilons of the factors' magnitudes.
        const REL_TOL_F64: f64 = 1e-13;
        const REL_TOL_F32: f64 = 2e-5;
        check::<f64>(&[520, -540, 1000, -1000], REL_TOL_F64);
        check::<f32>(&[70, -60, 100, -100], REL_TOL_F32);
    }

    /// Shapes the factorisation cannot take are typed errors with the
    /// counts: more rows than N (`CapacityExceeded`), no column, more
    /// columns than MAX_STATES or than rows (`TooFewSatellites`). A zero
    /// column is `RankDeficient` at its index with pivot 0, and so is a
    /// NaN column (its norm fails the rank test), in f64 and f32.
    #[test]
    fn shapes_and_degenerate_columns_are_refused() {
        fn check<T: Real>() {
            let mut h = [[T::zero(); 8]; MAX_STATES];
            for (j, col) in h.iter_mut().enumerate() {
                for (i, v) in col.iter_mut().enumerate() {
                    *v = T::of(((i * 7 + j * 3) % 5) as f64 + (i == j) as u8 as f64);
                }
            }
            let fac = |h: &[[T; 8]; MAX_STATES], n, m| Householder::<8, T>::factor(h, n, m).err();
            assert_eq!(
                fac(&h, 9, 4),
                Some(RaimError::CapacityExceeded {
                    have: 9,
                    capacity: 8
                })
            );
            assert_eq!(
                fac(&h, 6, 0),
                Some(RaimError::TooFewSatellites { have: 6, need: 1 })
            );
            assert_eq!(
                fac(&h, 8, MAX_STATES + 1),
                Some(RaimError::TooFewSatellites {
                    have: 8,
                    need: MAX_STATES + 1
                })
            );
            assert_eq!(
                fac(&h, 3, 4),
                Some(RaimError::TooFewSatellites { have: 3, need: 4 })
            );
            let mut zero = h;
            zero[0] = [T::zero(); 8];
            assert_eq!(
                fac(&zero, 8, 3),
                Some(RaimError::RankDeficient {
                    column: 0,
                    pivot: 0.0
                })
            );
            let mut nan = h;
            nan[2][1] = T::of(f64::NAN);
            assert!(matches!(
                fac(&nan, 8, 3),
                Some(RaimError::RankDeficient { column: 2, .. })
            ));
        }
        check::<f64>();
        check::<f32>();
    }

    /// The factor's shape and T1 against an independent reference:
    /// `rows`/`cols` are n and m; `t(i, j)` is zero below the diagonal and
    /// beyond column m; T1^T T1 = H^T H (Q is orthogonal) to 1e-12
    /// relative, against nalgebra's product; and `solve_tt` solves
    /// T1^T x = y (T1^T x multiplied back gives y).
    #[test]
    fn triangle_matches_the_gram_matrix() {
        const REL_TOL: f64 = 1e-12;
        let (n, m) = (7, 4);
        let mut rng = crate::testutil::Rng::new(17);
        let mut h = [[0.0f64; 8]; MAX_STATES];
        for col in h.iter_mut().take(m) {
            for v in col.iter_mut().take(n) {
                *v = rng.uniform() * 2.0 - 1.0;
            }
        }
        let qr = Householder::<8>::factor(&h, n, m).unwrap();
        assert_eq!((qr.rows(), qr.cols()), (n, m));
        let dense = nalgebra::DMatrix::from_fn(n, m, |i, j| h[j][i]);
        let gram = dense.transpose() * &dense;
        for i in 0..MAX_STATES {
            for j in 0..MAX_STATES {
                if i > j || j >= m {
                    assert_eq!(qr.t(i, j), 0.0, "{i} {j}");
                }
            }
        }
        for i in 0..m {
            for j in 0..m {
                let tt: f64 = (0..m).map(|k| qr.t(k, i) * qr.t(k, j)).sum();
                let scale = gram[(i, i)].max(gram[(j, j)]);
                assert!((tt - gram[(i, j)]).abs() <= REL_TOL * scale, "{i} {j}");
            }
        }
        let mut y = [0.0; MAX_STATES];
        y[..m].copy_from_slice(&[0.5, -1.5, 2.0, 0.25]);
        let x = qr.solve_tt(&y);
        for (i, yi) in y.iter().enumerate().take(m) {
            let back: f64 = (0..m).map(|k| qr.t(k, i) * x[k]).sum();
            assert!((back - yi).abs() < REL_TOL * 10.0, "{i}: {back} {yi}");
        }
    }

    /// [`dot_lanes`] against the left-to-right [`dot`], for every length
    /// 0..=40 (every remainder mod 4) and unequal lengths (the shorter
    /// decides): within a few epsilons of sum |a_i b_i| (both orders are
    /// within n eps of it), and exactly equal on integers.
    #[test]
    fn lane_sums_agree_with_the_sequential_sum() {
        // Dimensionless, relative to sum |a_i b_i|: 2 n eps covers both
        // orders' rounding for n <= 40.
        const REL_TOL: f64 = 80.0 * f64::EPSILON;
        let mut rng = crate::testutil::Rng::new(5);
        for len in 0..=40 {
            let a: [f64; 40] = core::array::from_fn(|_| rng.uniform() * 2.0 - 1.0);
            let b: [f64; 40] = core::array::from_fn(|_| rng.uniform() * 2.0 - 1.0);
            let seq = dot(a[..len].iter(), b[..len].iter());
            let abs: f64 = a[..len]
                .iter()
                .zip(&b[..len])
                .map(|(x, y)| (x * y).abs())
                .sum();
            let lanes = dot_lanes(&a[..len], &b[..len]);
            assert!((lanes - seq).abs() <= REL_TOL * abs, "len {len}");
            for extra in [1, 3, 5] {
                let longer = (len + extra).min(40);
                assert_eq!(
                    dot_lanes(&a[..len], &b[..longer]).to_bits(),
                    lanes.to_bits(),
                    "len {len} + {extra}"
                );
                assert_eq!(
                    dot_lanes(&a[..longer], &b[..len]).to_bits(),
                    lanes.to_bits()
                );
            }
            let ia: [f64; 40] = core::array::from_fn(|i| (i as f64) - 7.0);
            assert_eq!(
                dot_lanes(&ia[..len], &ia[..len]),
                dot(ia[..len].iter(), ia[..len].iter())
            );
        }
    }

    /// The factorisation with m = 4 and 5 fixed at compile time (the f64
    /// engine's) is the general column loop's, bit for bit.
    #[test]
    fn fixed_column_counts_equal_the_general_loop() {
        let mut rng = crate::testutil::Rng::new(17);
        for (n, m) in [(6, 4), (9, 5), (16, 5), (12, 4)] {
            let mut h = [[0.0f64; 16]; MAX_STATES];
            for col in h.iter_mut().take(m) {
                for v in col.iter_mut().take(n) {
                    *v = rng.uniform() * 2.0 - 1.0;
                }
            }
            let fixed = Householder::<16>::factor(&h, n, m).unwrap();
            let mut general = Householder::<16>::empty();
            general.n = n;
            general.m = m;
            general.a = h;
            // A column count the compiler cannot see: the general loop.
            general.columns(core::hint::black_box(m), n).unwrap();
            for j in 0..MAX_STATES {
                for i in 0..16 {
                    assert_eq!(fixed.a[j][i].to_bits(), general.a[j][i].to_bits());
                }
                assert_eq!(fixed.diag[j].to_bits(), general.diag[j].to_bits());
            }
        }
    }

    /// Verifies: SPEC-2, WIRE-DegenerateGeometry
    #[test]
    fn rejects_rank_deficiency() {
        let mut h = [[0.0; 8]; MAX_STATES];
        h[0][..4].copy_from_slice(&[1.0, 1.0, 1.0, 1.0]);
        h[1][..4].copy_from_slice(&[2.0, 2.0, 2.0, 2.0]);
        let err = Householder::<8>::factor(&h, 4, 2).unwrap_err();
        assert!(
            matches!(err, RaimError::RankDeficient { column: 1, .. }),
            "{err:?}"
        );
        let zero = [[0.0; 8]; MAX_STATES];
        assert!(matches!(
            Householder::<8>::factor(&zero, 4, 1),
            Err(RaimError::RankDeficient { column: 0, .. })
        ));
        assert!(matches!(
            Householder::<8>::factor(&h, 9, 2),
            Err(RaimError::CapacityExceeded {
                have: 9,
                capacity: 8
            })
        ));
    }
}
