//! Error reconstruction under constraints (SPEC §8.2-8.4, seed 002).
//!
//! Everything here works on the whitened residual model: the projector
//! S = I - H (H^T H)^-1 H^T (n x n, symmetric, idempotent) and the residuals
//! r = S z, so the noise is N(0, S) and the statistics are chi-square. The
//! kernels are generic over [`Real`] (SPEC precision policy, `real.rs`).
//!
//! - A group constrains m satellites to be fault-free; the others, F, are
//!   reconstructed from S[:, F] e_F = r. Since S is a symmetric projector,
//!   S[:, F]^T S[:, F] = S[F, F] and S[:, F]^T r = r_F, so the (exact, r lies
//!   in range S) solution is e_F = S[F, F]^-1 r_F with covariance
//!   Cov(e_F) = S[F, F]^-1 (sigma units). S[F, F] is non-singular iff the
//!   constrained rows of H have rank m, so the rank check is the Cholesky
//!   of S[F, F]: a satellite whose column is dependent on the ones before it
//!   is moved into the constrained set ("swapped in", reported).
//! - The seed's statistic Q = ||e_F||^2 - max_i e_i^2 (seed 002, "Q value").
//! - The subset statistic of a candidate fault set T (SPEC §8.4):
//!   RSS_T = min_b ||r - S[:, T] b||^2 = D^2 - r_T^T S[T, T]^-1 r_T with
//!   D^2 = ||r||^2, and the bias estimate b_T = S[T, T]^-1 r_T (sigma
//!   units). RSS_T ~ chi2(n - m - |T|) when every fault is in T.

use super::covering::{members, SatSet, MAX_FAULTS, MAX_SATS};
use super::error::MultifaultError;
use crate::linalg::parity::Parity;
use crate::real::Real;

/// A column whose part independent of the columns before it carries less
/// than this share of its energy (S_jj) is rank-dependent: reconstructing it
/// would amplify the noise by more than 1 / sqrt(RANK_TOL) = 1000.
pub const RANK_TOL: f64 = 1e-6;

/// The rank tolerance in precision T: [`RANK_TOL`], or 1000 epsilon if
/// larger (f32: 1.2e-4), so rounding in S is never taken for rank.
pub fn rank_tol<T: Real>() -> T {
    let floor = T::EPS * T::of(1000.0);
    let tol = T::of(RANK_TOL);
    if tol > floor {
        tol
    } else {
        floor
    }
}

/// The whitened residual model of one epoch: S and r for n satellites.
#[derive(Debug, Clone)]
pub struct ResidualModel<T, const N: usize> {
    n: usize,
    s: [[T; N]; N],
    r: [T; N],
    d2: T,
}

impl<T: Real, const N: usize> Default for ResidualModel<T, N> {
    fn default() -> Self {
        Self::empty()
    }
}

impl<T: Real, const N: usize> ResidualModel<T, N> {
    /// An empty model (n = 0), to be filled.
    pub const fn empty() -> Self {
        ResidualModel {
            n: 0,
            s: [[T::ZERO; N]; N],
            r: [T::ZERO; N],
            d2: T::ZERO,
        }
    }

    /// From an explicit projector `s(i, j)` and residuals (f64, converted
    /// to T): the seed's test case, and host references.
    pub fn from_projector(
        n: usize,
        s: impl Fn(usize, usize) -> f64,
        r: &[f64],
    ) -> Result<Self, MultifaultError> {
        let mut model = Self::empty();
        if n > N || n > MAX_SATS || r.len() < n {
            return Err(MultifaultError::CapacityExceeded {
                have: n.max(r.len()),
                capacity: N.min(MAX_SATS),
            });
        }
        model.n = n;
        for (i, row) in model.s.iter_mut().enumerate().take(n) {
            for (j, v) in row.iter_mut().enumerate().take(n) {
                *v = T::of(s(i, j));
            }
        }
        for (dst, v) in model.r.iter_mut().zip(r.iter()).take(n) {
            *dst = T::of(*v);
        }
        model.d2 = model.r.iter().take(n).fold(T::zero(), |a, v| a + *v * *v);
        Ok(model)
    }

    /// From a parity space (SPEC §2) through its public accessors only: the
    /// column S e_j = U2 (U2^T e_j), the residuals, and D^2 = p^T p.
    /// `P` is the parity space's precision (the engine's); its values are
    /// converted to `T` here.
    pub fn fill_from_parity<P: Real>(
        &mut self,
        parity: &Parity<N, P>,
    ) -> Result<(), MultifaultError> {
        let n = parity.rows();
        if n > MAX_SATS {
            return Err(MultifaultError::CapacityExceeded {
                have: n,
                capacity: MAX_SATS,
            });
        }
        self.n = n;
        let mut e = [P::zero(); N];
        let mut y = [P::zero(); N];
        for j in 0..n {
            if let Some(v) = e.get_mut(j) {
                *v = P::one();
            }
            let k = parity.project(&e, &mut y);
            // `project` writes at most y.len() entries.
            let col = parity.lift(y.get(..k).unwrap_or(&[]));
            if let Some(v) = e.get_mut(j) {
                *v = P::zero();
            }
            for (row, c) in self.s.iter_mut().zip(col.iter()).take(n) {
                if let Some(v) = row.get_mut(j) {
                    *v = T::of(c.to_f64());
                }
            }
        }
        for (dst, v) in self.r.iter_mut().zip(parity.residuals()) {
            *dst = T::of(v.to_f64());
        }
        self.d2 = T::of(parity.sse().to_f64());
        Ok(())
    }

    /// Number of satellites n in the model.
    pub fn n(&self) -> usize {
        self.n
    }

    /// S_ij, for satellites i, j < [`Self::n`].
    // In range: every caller passes satellites it checked against n(), and
    // n <= N (`fill_from_parity` sets it to the parity's row count). Out
    // of range would be NaN, which no test passes.
    fn s(&self, i: usize, j: usize) -> T {
        self.s
            .get(i)
            .and_then(|row| row.get(j))
            .copied()
            .unwrap_or(T::of(f64::NAN))
    }

    /// r_i, for a satellite i < [`Self::n`].
    // In range: as for `s`.
    fn residual(&self, i: usize) -> T {
        self.r.get(i).copied().unwrap_or(T::of(f64::NAN))
    }

    /// D^2 = ||r||^2, the all-in-view statistic.
    pub fn d2(&self) -> T {
        self.d2
    }
}

/// One group's reconstruction (SPEC §8.2).
#[derive(Debug, Clone)]
pub struct GroupFit<T, const N: usize> {
    /// The identifiable set actually reconstructed (the design's F minus
    /// the satellites moved into the constrained set for rank).
    pub identifiable: SatSet,
    /// Satellites moved from F into the constrained set because the
    /// constrained rows lacked rank m without them (or S_ii < min_s_ii).
    pub swapped: SatSet,
    /// e_F by satellite, sigma units (0 outside F).
    pub error: [T; N],
    /// The diagonal of Cov(e_F) = S[F, F]^-1, sigma^2 units (0 outside F).
    pub variance: [T; N],
    /// The seed's Q = ||e_F||^2 - max_i e_i^2, sigma^2 units.
    pub q: T,
}

impl<T: Real, const N: usize> Default for GroupFit<T, N> {
    fn default() -> Self {
        Self::empty()
    }
}

impl<T: Real, const N: usize> GroupFit<T, N> {
    /// An empty fit, to be filled.
    pub const fn empty() -> Self {
        GroupFit {
            identifiable: 0,
            swapped: 0,
            error: [T::ZERO; N],
            variance: [T::ZERO; N],
            q: T::ZERO,
        }
    }
}

/// Scratch for one group: the Cholesky factor of S[F, F] (row a holds the
/// satellite `idx[a]`). Kept by the caller so nothing N x N lands on the
/// stack per group.
#[derive(Debug, Clone)]
pub struct Workspace<T, const N: usize> {
    l: [[T; N]; N],
    idx: [usize; N],
    k: usize,
}

impl<T: Real, const N: usize> Default for Workspace<T, N> {
    fn default() -> Self {
        Self::empty()
    }
}

impl<T: Real, const N: usize> Workspace<T, N> {
    /// An empty workspace.
    pub const fn empty() -> Self {
        Workspace {
            l: [[T::ZERO; N]; N],
            idx: [0; N],
            k: 0,
        }
    }
}

// In range: a, b < k, and k <= n <= N (one row per distinct satellite
// j < n that `reconstruct` admits); out of range would be NaN.
impl<T: Real, const N: usize> Workspace<T, N> {
    fn l(&self, a: usize, b: usize) -> T {
        self.l
            .get(a)
            .and_then(|row| row.get(b))
            .copied()
            .unwrap_or(T::of(f64::NAN))
    }

    /// Solves L y = rhs in place over the first k rows.
    fn forward(&self, y: &mut [T; N]) {
        for a in 0..self.k.min(N) {
            let mut v = y.get(a).copied().unwrap_or(T::of(f64::NAN));
            for (b, yb) in y.iter().enumerate().take(a) {
                v -= self.l(a, b) * *yb;
            }
            if let Some(dst) = y.get_mut(a) {
                *dst = v / self.l(a, a);
            }
        }
    }

    /// Solves L^T x = y in place over the first k rows.
    fn backward(&self, y: &mut [T; N]) {
        for a in (0..self.k.min(N)).rev() {
            let mut v = y.get(a).copied().unwrap_or(T::of(f64::NAN));
            for (b, &yb) in y.iter().enumerate().take(self.k).skip(a + 1) {
                v -= self.l(b, a) * yb;
            }
            if let Some(dst) = y.get_mut(a) {
                *dst = v / self.l(a, a);
            }
        }
    }
}

/// Reconstructs e_F for the identifiable set `f` (SPEC §8.2) into `out`.
/// Satellites with S_jj < `min_s_ii`, or whose S-column is dependent on
/// those before them (rank of the constrained set < m), are moved into the
/// constrained set and listed in `out.swapped`.
pub fn reconstruct<T: Real, const N: usize>(
    model: &ResidualModel<T, N>,
    f: SatSet,
    min_s_ii: T,
    ws: &mut Workspace<T, N>,
    out: &mut GroupFit<T, N>,
) {
    let tol = rank_tol::<T>();
    let (sats, count) = members(f);
    ws.k = 0;
    out.identifiable = 0;
    out.swapped = 0;
    out.error = [T::zero(); N];
    out.variance = [T::zero(); N];
    out.q = T::zero();
    let mut l_row = [T::zero(); N];
    // count <= 64 = MAX_SATS, the bits of a u64 set.
    let sats = sats.get(..count).unwrap_or(&[]);
    for &j in sats {
        let j = usize::from(j);
        if j >= model.n() {
            out.swapped |= 1u64 << j;
            continue;
        }
        let s_jj = model.s(j, j);
        if !(s_jj >= min_s_ii) {
            out.swapped |= 1u64 << j;
            continue;
        }
        // Row k of L: L[k, ..k] solves L l = S[idx, j]; pivot d = S_jj - |l|^2.
        for (v, &idx_a) in l_row.iter_mut().zip(ws.idx.iter()).take(ws.k) {
            *v = model.s(idx_a, j);
        }
        ws.forward(&mut l_row);
        let energy = l_row
            .iter()
            .take(ws.k)
            .fold(T::zero(), |acc, v| acc + *v * *v);
        let d = s_jj - energy;
        if !(d > tol * s_jj) {
            out.swapped |= 1u64 << j;
            continue;
        }
        let k = ws.k;
        if let Some(row) = ws.l.get_mut(k) {
            for (dst, v) in row.iter_mut().zip(l_row.iter()).take(k) {
                *dst = *v;
            }
            if let Some(diag) = row.get_mut(k) {
                *diag = d.sqrt();
            }
        }
        if let Some(dst) = ws.idx.get_mut(k) {
            *dst = j;
        }
        ws.k += 1;
        out.identifiable |= 1u64 << j;
    }
    // e_F = S[F, F]^-1 r_F by two triangular solves.
    let mut e = [T::zero(); N];
    for (v, &sat) in e.iter_mut().zip(ws.idx.iter()).take(ws.k) {
        *v = model.residual(sat);
    }
    ws.forward(&mut e);
    ws.backward(&mut e);
    let mut total = T::zero();
    let mut largest = T::zero();
    for (v, &sat) in e.iter().zip(ws.idx.iter()).take(ws.k) {
        if let Some(dst) = out.error.get_mut(sat) {
            *dst = *v;
        }
        let e2 = *v * *v;
        total += e2;
        if e2 > largest {
            largest = e2;
        }
    }
    out.q = total - largest;
    // diag(S[F, F]^-1)_c = |L^-1 e_c|^2.
    for (c, &sat) in ws.idx.iter().enumerate().take(ws.k) {
        let mut w = [T::zero(); N];
        if let Some(v) = w.get_mut(c) {
            *v = T::one();
        }
        ws.forward(&mut w);
        let var = w.iter().take(ws.k).fold(T::zero(), |acc, v| acc + *v * *v);
        if let Some(dst) = out.variance.get_mut(sat) {
            *dst = var;
        }
    }
}

/// A candidate fault set with its subset statistic and bias estimates.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SubsetFit<T> {
    /// The satellites of T as a bit set.
    pub set: SatSet,
    /// |T|.
    pub count: usize,
    /// RSS_T = D^2 - r_T^T S[T, T]^-1 r_T (>= 0), chi2(n - m - |T|) if every
    /// fault is in T.
    pub rss: T,
    /// b_T = S[T, T]^-1 r_T, sigma units, in increasing satellite order.
    pub bias: [T; MAX_FAULTS],
}

/// The subset statistic and biases of the candidate set `set` (1 to 3
/// satellites), or None when S[T, T] is singular within [`rank_tol`] (the
/// rows left without T lack rank m: T is not identifiable).
pub fn fit_subset<T: Real, const N: usize>(
    model: &ResidualModel<T, N>,
    set: SatSet,
) -> Option<SubsetFit<T>> {
    let (sats, count) = members(set);
    if count == 0 || count > MAX_FAULTS {
        return None;
    }
    let idx: [usize; MAX_FAULTS] = [
        usize::from(sats[0]),
        usize::from(sats[1]),
        usize::from(sats[2]),
    ];
    let tol = rank_tol::<T>();
    let zero = T::zero();
    // Cholesky of S[T, T] (<= 3 x 3).
    let mut l = [[zero; MAX_FAULTS]; MAX_FAULTS];
    for a in 0..count {
        let ia = idx.get(a).copied()?;
        if ia >= model.n() {
            return None;
        }
        for b in 0..=a {
            let ib = idx.get(b).copied()?;
            let mut v = model.s(ia, ib);
            for c in 0..b {
                v -= l.get(a)?.get(c).copied()? * l.get(b)?.get(c).copied()?;
            }
            if a == b {
                let s_aa = model.s(ia, ia);
                if !(v > tol * s_aa) {
                    return None;
                }
                *l.get_mut(a)?.get_mut(a)? = v.sqrt();
            } else {
                *l.get_mut(a)?.get_mut(b)? = v / l.get(b)?.get(b).copied()?;
            }
        }
    }
    let mut y = [zero; MAX_FAULTS];
    for a in 0..count {
        let mut v = model.residual(idx.get(a).copied()?);
        for b in 0..a {
            v -= l.get(a)?.get(b).copied()? * y.get(b).copied()?;
        }
        *y.get_mut(a)? = v / l.get(a)?.get(a).copied()?;
    }
    // r_T^T S_TT^-1 r_T = |y|^2.
    let explained = y.iter().take(count).fold(zero, |acc, v| acc + *v * *v);
    let mut b = y;
    for a in (0..count).rev() {
        let mut v = b.get(a).copied()?;
        for c in a + 1..count {
            v -= l.get(c)?.get(a).copied()? * b.get(c).copied()?;
        }
        *b.get_mut(a)? = v / l.get(a)?.get(a).copied()?;
    }
    let rss = model.d2() - explained;
    Some(SubsetFit {
        set,
        count,
        rss: if rss > zero { rss } else { zero },
        bias: b,
    })
}

#[cfg(test)]
#[path = "reconstruct_cov_tests.rs"]
mod cov_tests;
