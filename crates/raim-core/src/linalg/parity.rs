//! Parity space by Householder QR (SPEC §2, seed 000 eqs. 4-5, seed 001 eq. 2).
//!
//! Works on the whitened model (z~ = C^-1/2 z, H~ = C^-1/2 H), so the parity
//! vector is N(U2^T f, I). `U` is never formed: `p` is the tail of `U^T z`;
//! `S_ii = 1 - ||T1^-T h_i||^2`, and the least-squares gain
//! `A = (H^T H)^-1 H^T` has columns `T1^-1 T1^-T h_i`.

use crate::error::RaimError;
use crate::linalg::qr::{dot, Householder};
use crate::measurement::MAX_STATES;
use crate::real::Real;

/// Parity-space quantities of one (whitened) linear model, in precision
/// `T` (`f64` by default; f32 on the device).
#[derive(Debug, Clone)]
pub struct Parity<const N: usize, T: Real = f64> {
    n: usize,
    m: usize,
    qr: Householder<N, T>,
    /// U^T z; entries m..n are the parity vector p = U2^T z.
    utz: [T; N],
    /// Diagonal of S = I - H (H^T H)^-1 H^T.
    s_ii: [T; N],
    /// Residuals r = S z (whitened).
    residual: [T; N],
    /// Rows 0..3 of the gain A = (H^T H)^-1 H^T (the position states).
    gain: [[T; N]; 3],
    /// Least-squares state correction dx = A z.
    dx: [T; MAX_STATES],
}

/// S_ii = 1 - leverage clamped for rounding: it is in [0, 1]
/// mathematically (NaN stays NaN).
#[inline(always)]
fn clamp_unit<T: Real>(v: T) -> T {
    if v < T::zero() {
        T::zero()
    } else if v > T::one() {
        T::one()
    } else {
        v
    }
}

impl<const N: usize, T: Real> Parity<N, T> {
    /// An empty parity (0 x 0), to be filled by [`Self::compute`].
    pub const fn empty() -> Self {
        Parity {
            n: 0,
            m: 0,
            qr: Householder::empty(),
            utz: [T::ZERO; N],
            s_ii: [T::ZERO; N],
            residual: [T::ZERO; N],
            gain: [[T::ZERO; N]; 3],
            dx: [T::ZERO; MAX_STATES],
        }
    }

    /// Factor the whitened column-major `h` (n x m) and project `z`.
    /// Needs n > m (at least one redundant measurement).
    pub fn new(
        h: &[[T; N]; MAX_STATES],
        z: &[T; N],
        n: usize,
        m: usize,
    ) -> Result<Self, RaimError> {
        let mut p = Self::empty();
        p.compute(h, z, n, m)?;
        Ok(p)
    }

    /// [`Self::new`] into existing storage: nothing N-sized is built on the
    /// stack (the firmware's stack budget, BENCHMARKS.md).
    pub fn compute(
        &mut self,
        h: &[[T; N]; MAX_STATES],
        z: &[T; N],
        n: usize,
        m: usize,
    ) -> Result<(), RaimError> {
        if n <= m {
            return Err(RaimError::TooFewSatellites {
                have: n,
                need: m + 1,
            });
        }
        let p = self;
        p.qr.factor_from(h, n, m)?;
        p.n = n;
        p.m = m;
        p.utz = *z;
        // `s_ii`, `residual` and `gain` are not cleared (fourth
        // pass): the row loops below write every row < n of each, and
        // nothing reads a row >= n (the accessors end at n).
        p.qr.apply_ut(&mut p.utz);
        let mut rhs = [T::zero(); MAX_STATES];
        for (r, u) in rhs.iter_mut().zip(p.utz.iter()).take(m) {
            *r = *u;
        }
        p.dx = p.qr.solve_t(&rhs);
        // The per-row solves with the state count fixed at compile time for
        // the usual models (one or two constellations, where the
        // loops' overhead is a large share of a clean epoch); the
        // same operations in the same order, so the same bits.
        match m {
            4 => p.rows_fixed::<4>(h, z),
            5 => p.rows_fixed::<5>(h, z),
            _ => p.rows_general(h, z),
        }
        Ok(())
    }

    /// S_ii, residuals and gain columns for every row, with M = m states:
    /// per row i, g = T1^-T h_i, S_ii = 1 - |g|^2, the gain column
    /// T1^-1 g and the fitted value h_i^T dx ([`Self::rows_general`]'s
    /// operations, in its order).
    #[inline(never)]
    fn rows_fixed<const M: usize>(&mut self, h: &[[T; N]; MAX_STATES], z: &[T; N]) {
        let (t, d) = self.qr.triangle::<M>();
        let mut dx = [T::zero(); M];
        for (x, v) in dx.iter_mut().zip(self.dx.iter()) {
            *x = *v;
        }
        // : a counted loop over rows whose body is
        // straight-line code (every index below `n <= N`, so no access can
        // fail and no store is conditional), which the compiler vectorises
        // across rows; the operations per row are the same as before.
        let n = self.n.min(N);
        for i in 0..n {
            let mut hi = [T::zero(); M];
            for (dst, col) in hi.iter_mut().zip(h.iter()) {
                // i < n = min(self.n, N), and a column has N rows.
                #[allow(clippy::indexing_slicing)]
                let v = col[i];
                *dst = v;
            }
            // Forward substitution T1^T g = h_i (as `solve_tt`).
            let mut g = [T::zero(); M];
            for (k, (col, &dk)) in t.iter().zip(d.iter()).enumerate() {
                let dot = dot(g.iter().take(k), col.iter());
                if let (Some(gk), Some(hk)) = (g.get_mut(k), hi.get(k)) {
                    *gk = (*hk - dot) / dk;
                }
            }
            let leverage = dot(g.iter(), g.iter());
            // Back substitution T1 a = g (as `solve_t`).
            let mut a = g;
            for (j, (col, &dj)) in t.iter().zip(d.iter()).enumerate().rev() {
                let Some(aj) = a.get_mut(j) else {
                    continue;
                };
                *aj /= dj;
                let v = *aj;
                for (ai, tij) in a.iter_mut().zip(col.iter()).take(j) {
                    *ai -= *tij * v;
                }
            }
            let fitted = dot(hi.iter(), dx.iter());
            if let Some(s) = self.s_ii.get_mut(i) {
                *s = clamp_unit(T::one() - leverage);
            }
            if let (Some(r), Some(zi)) = (self.residual.get_mut(i), z.get(i)) {
                *r = *zi - fitted;
            }
            for (row, ak) in self.gain.iter_mut().zip(a.iter()) {
                if let Some(v) = row.get_mut(i) {
                    *v = *ak;
                }
            }
        }
    }

    /// The per-row quantities for any m (see [`Self::rows_fixed`]).
    fn rows_general(&mut self, h: &[[T; N]; MAX_STATES], z: &[T; N]) {
        let (n, m) = (self.n.min(N), self.m);
        let p = self;
        for i in 0..n {
            let mut hi = [T::zero(); MAX_STATES];
            for (dst, col) in hi.iter_mut().zip(h.iter()).take(m) {
                // i < n = min(self.n, N), and a column has N rows.
                #[allow(clippy::indexing_slicing)]
                let v = col[i];
                *dst = v;
            }
            let g = p.qr.solve_tt(&hi);
            let leverage = dot(g.iter().take(m), g.iter().take(m));
            let a = p.qr.solve_t(&g);
            let fitted = dot(hi.iter().take(m), p.dx.iter().take(m));
            if let Some(s) = p.s_ii.get_mut(i) {
                *s = clamp_unit(T::one() - leverage);
            }
            if let (Some(r), Some(zi)) = (p.residual.get_mut(i), z.get(i)) {
                *r = *zi - fitted;
            }
            for (row, ak) in p.gain.iter_mut().zip(a.iter()) {
                if let Some(v) = row.get_mut(i) {
                    *v = *ak;
                }
            }
        }
    }

    /// Number of measurement rows n.
    pub fn rows(&self) -> usize {
        self.n
    }

    /// Number of states m (3 + clocks).
    pub fn states(&self) -> usize {
        self.m
    }

    /// Degrees of freedom of the test, n - m (the parity dimension).
    pub fn dof(&self) -> usize {
        self.n - self.m
    }

    /// The parity vector p = U2^T z (length n - m).
    // m < n <= N once computed, 0 = m = n before: `compute` sets them
    // only after `factor_from` accepted n <= N and m <= n. The `min`s
    // change nothing then, and let the build prove the slice in bounds.
    #[allow(clippy::indexing_slicing)]
    pub fn p(&self) -> &[T] {
        let n = self.n.min(N);
        &self.utz[self.m.min(n)..n]
    }

    /// Weighted sum of squared residuals, p^T p = ||S z||^2.
    pub fn sse(&self) -> T {
        dot(self.p().iter(), self.p().iter())
    }

    /// S_ii for the active rows.
    // n <= N, as for `p`.
    #[allow(clippy::indexing_slicing)]
    pub fn s_ii(&self) -> &[T] {
        &self.s_ii[..self.n.min(N)]
    }

    /// Whitened residuals r = S z.
    // n <= N, as for `p`.
    #[allow(clippy::indexing_slicing)]
    pub fn residuals(&self) -> &[T] {
        &self.residual[..self.n.min(N)]
    }

    /// The rows E, N, U of the position gain A (each of length n).
    // n <= N, as for `p`.
    #[allow(clippy::indexing_slicing)]
    pub fn gains(&self) -> [&[T]; 3] {
        let [e, n, u] = &self.gain;
        let len = self.n.min(N);
        [&e[..len], &n[..len], &u[..len]]
    }

    /// Least-squares state correction dx (first m entries meaningful).
    pub fn dx(&self) -> &[T; MAX_STATES] {
        &self.dx
    }

    /// The factorisation, for applying U or U^T (MCUSUM transport, SPEC §7.3).
    pub fn qr(&self) -> &Householder<N, T> {
        &self.qr
    }

    /// U2 y for a parity-space vector y (length n - m): lifts it into
    /// measurement space, indexed like the rows.
    pub fn lift(&self, y: &[T]) -> [T; N] {
        let mut x = [T::zero(); N];
        for (dst, v) in x
            .iter_mut()
            .skip(self.m)
            .zip(y.iter())
            .take(self.n - self.m)
        {
            *dst = *v;
        }
        self.qr.apply_u(&mut x);
        x
    }

    /// U2^T x for a measurement-space vector x: its parity coordinates,
    /// written into `out` (length n - m). Returns the number written.
    pub fn project(&self, x: &[T; N], out: &mut [T]) -> usize {
        let mut y = *x;
        for v in y.iter_mut().skip(self.n) {
            *v = T::zero();
        }
        self.qr.apply_ut(&mut y);
        let mut k = 0;
        for (dst, v) in out
            .iter_mut()
            .zip(y.iter().skip(self.m).take(self.n - self.m))
        {
            *dst = *v;
            k += 1;
        }
        k
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use nalgebra::{DMatrix, DVector};
    use proptest::prelude::*;
    use std::vec::Vec;

    const N: usize = 16;

    /// Column-major buffer from a dense matrix.
    fn buffer(h: &DMatrix<f64>) -> [[f64; N]; MAX_STATES] {
        let mut b = [[0.0; N]; MAX_STATES];
        for j in 0..h.ncols() {
            for i in 0..h.nrows() {
                b[j][i] = h[(i, j)];
            }
        }
        b
    }

    /// U2 as a dense n x (n-m) matrix, column j = U2 e_j.
    fn u2(p: &Parity<N>) -> DMatrix<f64> {
        let (n, d) = (p.rows(), p.dof());
        let mut out = DMatrix::zeros(n, d);
        for j in 0..d {
            let mut e = std::vec![0.0; d];
            e[j] = 1.0;
            let col = p.lift(&e);
            for i in 0..n {
                out[(i, j)] = col[i];
            }
        }
        out
    }

    /// A random GNSS-like geometry: rows [-u, clock one-hot], 1-2 clocks.
    fn geometry() -> impl Strategy<Value = (DMatrix<f64>, DVector<f64>)> {
        (6usize..=N, 1usize..=2).prop_flat_map(|(n, clocks)| {
            let m = 3 + clocks;
            (
                proptest::collection::vec((0.0..360.0f64, 5.0..90.0f64, 0.3..3.0f64), n),
                proptest::collection::vec(-20.0..20.0f64, n),
            )
                .prop_map(move |(sky, z)| {
                    let mut h = DMatrix::zeros(n, m);
                    for (i, (az, el, sigma)) in sky.iter().enumerate() {
                        let (az, el) = (az.to_radians(), el.to_radians());
                        let w = 1.0 / sigma;
                        h[(i, 0)] = -el.cos() * az.sin() * w;
                        h[(i, 1)] = -el.cos() * az.cos() * w;
                        h[(i, 2)] = -el.sin() * w;
                        h[(i, 3 + (i % clocks).min(m - 4))] = w;
                    }
                    (h, DVector::from_vec(z))
                })
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// SPEC §2 identities on random geometries: U2 orthonormal, U2^T H = 0,
        /// S = U2 U2^T idempotent and equal to I - H (H^T H)^-1 H^T (computed
        /// densely by nalgebra, independently), p^T p = z^T S z, S_ii and
        /// residuals, and seed 000 eq. 8: b_i = S_i^T z / S_ii minimises J(b).
        ///
        /// Verifies: SPEC-2
        #[test]
        fn parity_identities((h, z) in geometry()) {
            let (n, m) = (h.nrows(), h.ncols());
            let hb = buffer(&h);
            let mut zb = [0.0; N];
            zb[..n].copy_from_slice(z.as_slice());
            let p = match Parity::<N>::new(&hb, &zb, n, m) {
                Ok(p) => p,
                // Random geometries can be degenerate; that is a typed error.
                Err(RaimError::RankDeficient { .. }) => return Ok(()),
                Err(e) => panic!("{e:?}"),
            };
            const ID_TOL: f64 = 1e-9; // dimensionless (orthonormality, projector entries)
            let u2 = u2(&p);
            let gram = u2.transpose() * &u2;
            prop_assert!((gram - DMatrix::identity(n - m, n - m)).amax() < ID_TOL);
            prop_assert!((u2.transpose() * &h).amax() < ID_TOL * h.amax());
            let s = &u2 * u2.transpose();
            prop_assert!((&s * &s - &s).amax() < ID_TOL);
            let hth = h.transpose() * &h;
            let dense = DMatrix::identity(n, n) - &h * hth.clone().try_inverse().unwrap() * h.transpose();
            prop_assert!((&dense - &s).amax() < 1e-7, "{}", (&dense - &s).amax());
            let pz: f64 = p.p().iter().map(|v| v * v).sum();
            let zsz = (z.transpose() * &dense * &z)[(0, 0)];
            prop_assert!((pz - zsz).abs() < 1e-8 * (1.0 + zsz));
            prop_assert!((p.sse() - zsz).abs() < 1e-8 * (1.0 + zsz));
            let r = &dense * &z;
            for i in 0..n {
                prop_assert!((p.s_ii()[i] - dense[(i, i)]).abs() < 1e-8);
                prop_assert!((p.residuals()[i] - r[i]).abs() < 1e-7 * (1.0 + r.amax()));
                // Eq. 8 for identifiable satellites (S_ii >= 1e-3; the core
                // declares S_ii < 1e-4 unidentifiable): b_i = S_i^T z / S_ii
                // with S from the dense projector; b_i minimises J(b) =
                // S_ii b^2 - 2 b S_i^T z + z^T S z; and J(b_i) = |p - b_i
                // U2^T e_i|^2 (seed 000 eqs. 6-7).
                if dense[(i, i)] < 1e-3 {
                    continue;
                }
                let b_hat = p.residuals()[i] / p.s_ii()[i];
                let b_dense = r[i] / dense[(i, i)];
                prop_assert!((b_hat - b_dense).abs() < 1e-6 * (1.0 + b_dense.abs()));
                let j = |b: f64| dense[(i, i)] * b * b - 2.0 * b * r[i] + zsz;
                let delta = 1e-3 * (1.0 + b_hat.abs());
                let slack = 1e-9 * (1.0 + zsz + b_hat * b_hat);
                prop_assert!(j(b_hat) <= j(b_hat + delta) + slack && j(b_hat) <= j(b_hat - delta) + slack);
                let a_i: Vec<f64> = (0..n - m).map(|k| u2[(i, k)]).collect();
                let jp: f64 = p.p().iter().zip(a_i.iter()).map(|(pk, ak)| (pk - b_hat * ak).powi(2)).sum();
                prop_assert!((jp - j(b_hat)).abs() < 1e-7 * (1.0 + zsz + b_hat * b_hat));
            }
            // Gain rows reproduce the least-squares position: A z = dx.
            let x = hth.try_inverse().unwrap() * h.transpose() * &z;
            for k in 0..3 {
                let ax: f64 = p.gains()[k].iter().zip(z.iter()).map(|(a, b)| a * b).sum();
                prop_assert!((ax - x[k]).abs() < 1e-7 * (1.0 + x.amax()));
                prop_assert!((p.dx()[k] - x[k]).abs() < 1e-7 * (1.0 + x.amax()));
            }
        }
    }

    /// Seed 002 (Zhang, Cui, Feng 2014), table "eigenvalues and eigenvectors
    /// of the projection matrix": the four eigenvectors of eigenvalue 0 span
    /// the column space of H, so they serve as a 7 x 4 geometry. 30 m on
    /// satellites 2, 6 and 7 (modes E1, E2, E3) must give the printed
    /// residual vectors and statistics 560.1, 4.5 and 340.7 (SPEC §8.5).
    #[test]
    fn seed_002_residuals_and_statistics() {
        let v0: [[f64; 7]; 4] = [
            [-0.633, -0.056, -0.014, -0.360, -0.568, 0.370, -0.083],
            [0.384, -0.115, -0.476, -0.412, 0.220, 0.600, 0.188],
            [0.0, 0.021, 0.444, 0.495, 0.160, 0.701, -0.202],
            [0.0, 0.601, 0.287, -0.080, -0.069, 0.083, 0.734],
        ];
        let mut h = [[0.0; N]; MAX_STATES];
        for (j, col) in v0.iter().enumerate() {
            h[j][..7].copy_from_slice(col);
        }
        let cases: [(usize, [f64; 7], f64); 3] = [
            (1, [0.25, 18.67, -7.12, -0.90, 0.94, 0.74, -12.59], 560.1),
            (5, [0.12, 0.74, -1.33, 1.20, -0.83, 0.15, -0.05], 4.5),
            (6, [-3.75, -12.59, -0.98, 6.18, -0.17, -0.05, 11.36], 340.7),
        ];
        // The eigenvectors are printed to 3 decimals (+-5e-4 per entry), so
        // S = I - V0 V0^T carries errors of ~1e-3 and a 30 m fault's
        // residuals move by up to ~0.02 m; the residuals themselves are
        // printed to 0.01 m. The statistics are printed to 0.1 (E2's 4.5 is
        // +-1.1 %), hence 1 % relative.
        const RESIDUAL_TOL_M: f64 = 0.02;
        const STATISTIC_REL_TOL: f64 = 0.01;
        for (sat, printed_r, printed_stat) in cases {
            let mut z = [0.0; N];
            z[sat] = 30.0;
            let p = Parity::<N>::new(&h, &z, 7, 4).unwrap();
            for (i, (ours, theirs)) in p.residuals().iter().zip(printed_r.iter()).enumerate() {
                assert!(
                    (ours - theirs).abs() < RESIDUAL_TOL_M,
                    "sat {sat} row {i}: {ours} vs {theirs}"
                );
            }
            let stat = p.sse();
            assert!(
                ((stat - printed_stat) / printed_stat).abs() < STATISTIC_REL_TOL,
                "sat {sat}: {stat} vs {printed_stat}"
            );
        }
    }

    /// A random whitened sky of `n` satellites and `clocks` clock columns
    /// (elevations 5-90 deg, sigmas 0.3-3 m, unit-sigma noise) with a
    /// 20-sigma fault on satellite `faulty`.
    fn random_whitened_sky(
        rng: &mut crate::testutil::Rng,
        n: usize,
        clocks: usize,
        faulty: usize,
    ) -> ([[f64; N]; MAX_STATES], [f64; N]) {
        let mut h = [[0.0f64; N]; MAX_STATES];
        let mut z = [0.0f64; N];
        for i in 0..n {
            let az = rng.uniform() * 2.0 * core::f64::consts::PI;
            let el = (5.0 + 85.0 * rng.uniform()).to_radians();
            let w = 1.0 / (0.3 + 2.7 * rng.uniform());
            h[0][i] = -el.cos() * az.sin() * w;
            h[1][i] = -el.cos() * az.cos() * w;
            h[2][i] = -el.sin() * w;
            h[3 + (i % clocks)][i] = w;
            z[i] = rng.normal();
        }
        z[faulty] += 20.0;
        (h, z)
    }

    /// The fixed-size row loops (m = 4, 5) perform the general loop's
    /// operations in its order: the same bits for S_ii, residuals and
    /// gains, in f64 and f32, on 500 random skies each (n = 5..16, one or
    /// two clocks, sigmas 0.3-3 m, a 20-sigma fault).
    #[test]
    fn fixed_row_loops_equal_the_general_loop_bit_for_bit() {
        fn check<T: Real>(h: &[[T; N]; MAX_STATES], z: &[T; N], n: usize, m: usize) -> bool {
            let Ok(fast) = Parity::<N, T>::new(h, z, n, m) else {
                return false;
            };
            let mut slow = fast.clone();
            slow.rows_general(h, z);
            let bits = |v: &[T]| v.iter().map(|x| x.to_f64().to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(fast.s_ii()), bits(slow.s_ii()), "S_ii, n {n} m {m}");
            assert_eq!(
                bits(fast.residuals()),
                bits(slow.residuals()),
                "r, n {n} m {m}"
            );
            for axis in 0..3 {
                assert_eq!(
                    bits(fast.gains()[axis]),
                    bits(slow.gains()[axis]),
                    "gain {axis}"
                );
            }
            true
        }
        let mut rng = crate::testutil::Rng::new(10);
        let mut checked = [0usize; 2];
        for trial in 0..1000 {
            let n = 5 + trial % 12;
            let clocks = 1 + (trial / 12) % 2;
            let m = 3 + clocks;
            let (h, z) = random_whitened_sky(&mut rng, n, clocks, trial % n);
            let hs = h.map(|c| c.map(|v| v as f32));
            let zs = z.map(|v| v as f32);
            checked[0] += usize::from(check(&h, &z, n, m));
            checked[1] += usize::from(check(&hs, &zs, n, m));
        }
        assert!(checked[0] > 900 && checked[1] > 900, "{checked:?}");
    }

    /// Verifies: SPEC-2, WIRE-TooFewSatellites
    #[test]
    fn needs_redundancy() {
        let h = [[0.0; N]; MAX_STATES];
        let z = [0.0; N];
        assert!(matches!(
            Parity::<N>::new(&h, &z, 4, 4),
            Err(RaimError::TooFewSatellites { have: 4, need: 5 })
        ));
    }

    /// The precision policy (src/real.rs): the same parity code at f32
    /// against f64 on 2,000 random whitened skies (n = 6..16, 1-2 clocks,
    /// sigmas 0.3-3 m, unit-sigma noise and a 20-sigma fault on one
    /// satellite). Measured worst cases (printed): D^2 5.6e-5 relative,
    /// S_ii 1.4e-5 absolute, w_i 1.2e-2 sigma (on |w| ~ 20), gain rows
    /// 3.2e-5 relative to their largest entry; the worst cases are the
    /// ill-conditioned skies (n = 6 with two clocks, sigma ratios of 10),
    /// where the f32 error is eps x cond(H). Stated tolerances: D^2 1e-4
    /// relative, S_ii 3e-5, w_i 2e-2 sigma, gains 1e-4 relative. (The
    /// Python study in firmware/tools found 1e-6 for D^2 on unit-sigma
    /// skies of n >= 8; the random weights here are harsher.)
    #[test]
    fn f32_parity_agrees_with_f64() {
        const SSE_REL_TOL: f64 = 1e-4;
        const S_II_TOL: f64 = 3e-5;
        const W_TOL: f64 = 2e-2;
        const GAIN_REL_TOL: f64 = 1e-4;
        let mut rng = crate::testutil::Rng::new(2026);
        let mut worst = [0.0f64; 4];
        let mut compared = 0;
        for trial in 0..2000 {
            let n = 6 + trial % 11;
            let clocks = 1 + trial % 2;
            let m = 3 + clocks;
            let (h, z) = random_whitened_sky(&mut rng, n, clocks, trial % n);
            let Ok(d) = Parity::<N, f64>::new(&h, &z, n, m) else {
                continue;
            };
            let hs = h.map(|c| c.map(|v| v as f32));
            let zs = z.map(|v| v as f32);
            let s = Parity::<N, f32>::new(&hs, &zs, n, m).unwrap();
            compared += 1;
            let rel_sse = ((s.sse() as f64 - d.sse()) / d.sse()).abs();
            worst[0] = worst[0].max(rel_sse);
            for i in 0..n {
                let (sd, ss) = (d.s_ii()[i], s.s_ii()[i] as f64);
                worst[1] = worst[1].max((sd - ss).abs());
                if sd > 1e-3 {
                    let wd = d.residuals()[i] / sd.sqrt();
                    let ws = s.residuals()[i] as f64 / ss.sqrt();
                    worst[2] = worst[2].max((wd - ws).abs());
                }
            }
            for axis in 0..3 {
                let scale = d.gains()[axis].iter().fold(0.0f64, |a, v| a.max(v.abs()));
                for (gd, gs) in d.gains()[axis].iter().zip(s.gains()[axis]) {
                    worst[3] = worst[3].max((gd - *gs as f64).abs() / scale);
                }
            }
        }
        std::println!("f32 vs f64 parity, worst of {compared}: D^2 {:.1e} rel, S_ii {:.1e}, w {:.1e}, gain {:.1e} rel", worst[0], worst[1], worst[2], worst[3]);
        assert!(compared > 1900, "{compared}");
        assert!(worst[0] < SSE_REL_TOL, "{worst:?}");
        assert!(worst[1] < S_II_TOL, "{worst:?}");
        assert!(worst[2] < W_TOL, "{worst:?}");
        assert!(worst[3] < GAIN_REL_TOL, "{worst:?}");
    }

    /// Seed 002's published residuals and statistics reproduce at f32 too
    /// (same tolerances as the f64 test), and an f32 rank deficiency is
    /// caught by the f32 rank tolerance.
    #[test]
    fn seed_002_and_rank_deficiency_at_f32() {
        let v0: [[f32; 7]; 4] = [
            [-0.633, -0.056, -0.014, -0.360, -0.568, 0.370, -0.083],
            [0.384, -0.115, -0.476, -0.412, 0.220, 0.600, 0.188],
            [0.0, 0.021, 0.444, 0.495, 0.160, 0.701, -0.202],
            [0.0, 0.601, 0.287, -0.080, -0.069, 0.083, 0.734],
        ];
        let mut h = [[0.0f32; N]; MAX_STATES];
        for (j, col) in v0.iter().enumerate() {
            h[j][..7].copy_from_slice(col);
        }
        const RESIDUAL_TOL_M: f64 = 0.02;
        const STATISTIC_REL_TOL: f64 = 0.01;
        for (sat, printed_stat) in [(1usize, 560.1f64), (5, 4.5), (6, 340.7)] {
            let mut z = [0.0f32; N];
            z[sat] = 30.0;
            let p = Parity::<N, f32>::new(&h, &z, 7, 4).unwrap();
            let stat = p.sse() as f64;
            assert!(
                ((stat - printed_stat) / printed_stat).abs() < STATISTIC_REL_TOL,
                "{stat}"
            );
            let mut hd = [[0.0f64; N]; MAX_STATES];
            for j in 0..4 {
                for i in 0..7 {
                    hd[j][i] = h[j][i] as f64;
                }
            }
            let pd = Parity::<N, f64>::new(&hd, &z.map(|v| v as f64), 7, 4).unwrap();
            for (a, b) in p.residuals().iter().zip(pd.residuals()) {
                assert!((*a as f64 - b).abs() < RESIDUAL_TOL_M);
            }
        }
        // Two columns equal up to f32 rounding: rank deficient in f32.
        let mut h = [[0.0f32; N]; MAX_STATES];
        let col = |f: &dyn Fn(usize) -> f32| {
            core::array::from_fn::<f32, N, _>(|i| if i < 6 { f(i) } else { 0.0 })
        };
        h[0] = col(&|i| 1.0 + i as f32);
        h[1] = col(&|i| (1.0 + i as f32) * 3.0);
        h[2] = col(&|i| ((i * 7) % 5) as f32);
        assert!(matches!(
            Parity::<N, f32>::new(&h, &[1.0f32; N], 6, 3),
            Err(RaimError::RankDeficient { column: 1, .. })
        ));
    }
}

#[cfg(test)]
#[path = "parity_cov_tests.rs"]
mod cov_tests;
