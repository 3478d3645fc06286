//! Subset solutions from one factorisation (SPEC §9.1 steps 2-3).
//!
//! The all-in-view weighted least squares is factored once (Cholesky of
//! the normal matrix, inverted: P0 = (G^T W G)^-1, at most 8 x 8), and
//! once more per constellation with its clock column dropped ("bases").
//! Every other mode is a low-rank downdate of its base by the Woodbury
//! identity. With R the r removed rows of the base B, V = P_B G_R^T and
//! M = W_R^-1 - G_R P_B G_R^T (the covariance of the removed residuals):
//!
//!   P_k = P_B + V M^-1 V^T,   S^(k)_i = S^(B)_i + V M^-1 h_i,
//!   h_i = G_R S^(B)_i = V^T g_i w_i  (i kept),   S^(k)_i = 0  (i in R).
//!
//! So sigma_q^(k)^2 = (P_k)_qq (since S W^-1 S^T = P), and the three
//! position rows of S^(k) - S^(0), which give sigma_ss, b^(k) and the
//! separation x^(k) - x^(0), are formed in O(r m n) without any new least
//! squares; on the all-in-view base, sigma_ss and the separation need no
//! pass over the satellites at all (`all_in_view`). A singular M (removing R leaves the geometry rank-deficient)
//! makes the mode unmonitorable. A mode that empties a constellation
//! (by its constellation event or by removing all its satellites) uses
//! that constellation's base, whose clock column is dropped.

use crate::measurement::MAX_STATES;
use crate::real::Real;

use super::modes::MAX_EVENTS;

/// Relative pivot below which a Cholesky factor is declared singular.
pub fn rank_tolerance<T: Real>() -> T {
    let t = 1e3 * T::EPS.to_f64();
    T::of(if t > 1e-9 { t } else { 1e-9 })
}

/// The whitened all-in-view problem of one epoch.
#[derive(Debug, Clone, Copy)]
pub struct Geometry<T, const N: usize> {
    /// Number of satellites.
    pub n: usize,
    /// Number of columns: 3 + one clock per constellation in use.
    pub m: usize,
    /// Full geometry rows (ENU then the one-hot clock column).
    pub g: [[T; MAX_STATES]; N],
    /// W = C_int^-1 (diagonal).
    pub w: [T; N],
    /// C_int itself (W^-1: M's diagonal and V = S0 W^-1 in `all_in_view`
    /// multiply by it instead of dividing by w).
    pub c_int: [T; N],
    /// C_acc, the accuracy variance per satellite, m^2.
    pub c_acc: [T; N],
    /// Nominal bias b_nom per satellite, m.
    pub b_nom: [T; N],
    /// Linearised residual y per satellite, m.
    pub y: [T; N],
    /// Each satellite's clock column.
    pub col: [usize; N],
}

impl<T: Real, const N: usize> Default for Geometry<T, N> {
    fn default() -> Self {
        Self::empty()
    }
}

impl<T: Real, const N: usize> Geometry<T, N> {
    /// No satellite loaded.
    pub const fn empty() -> Self {
        Self {
            n: 0,
            m: 0,
            g: [[T::ZERO; MAX_STATES]; N],
            w: [T::ZERO; N],
            c_int: [T::ZERO; N],
            c_acc: [T::ZERO; N],
            b_nom: [T::ZERO; N],
            y: [T::ZERO; N],
            col: [0; N],
        }
    }
}

/// A factored subset: P_B with the dropped columns zero, and the position
/// rows of S^(B) - S^(0).
#[derive(Debug, Clone, Copy)]
pub struct Base<T, const N: usize> {
    /// P_B = (G^T W G)^-1 of the subset, dropped columns zero.
    pub p: [[T; MAX_STATES]; MAX_STATES],
    /// Position rows (E, N, U) of S^(B) - S^(0), per satellite.
    pub d: [[T; N]; 3],
    /// Satellites removed by this base.
    pub removed: u64,
    /// Per satellite, what the downdate pass reads ([`pack`]).
    pub pack: [SatPack<T>; N],
}

/// One satellite's inputs to the per-mode pass, side by side: the
/// all-in-view gain rows s0, the base's d0 = S^(B) - S^(0), C_acc, b_nom
/// and the residual.
#[derive(Debug, Clone, Copy, Default)]
pub struct SatPack<T> {
    /// All-in-view gain rows s0 (E, N, U).
    pub s: [T; 3],
    /// The base's d0 = S^(B) - S^(0) rows (E, N, U).
    pub d0: [T; 3],
    /// C_acc, m^2.
    pub c_acc: T,
    /// b_nom, m.
    pub b_nom: T,
    /// Residual y, m.
    pub y: T,
}

/// Fills `base.pack` from the geometry, `s0` and `base.d` (after
/// [`factor`], and for the all-in-view base after its `d` is zeroed).
pub fn pack<T: Real, const N: usize>(
    geo: &Geometry<T, N>,
    s0: &[[T; N]; 3],
    base: &mut Base<T, N>,
) {
    let [se, sn, su] = s0;
    let [de, dn, du] = &base.d;
    let cols = se
        .iter()
        .zip(sn.iter())
        .zip(su.iter())
        .zip(de.iter().zip(dn.iter()).zip(du.iter()))
        .zip(geo.c_acc.iter().zip(geo.b_nom.iter()).zip(geo.y.iter()));
    for (pk, ((((&a, &b), &c), ((&d, &e), &f)), ((&ca, &bn), &y))) in base.pack.iter_mut().zip(cols)
    {
        *pk = SatPack {
            s: [a, b, c],
            d0: [d, e, f],
            c_acc: ca,
            b_nom: bn,
            y,
        };
    }
}

impl<T: Real, const N: usize> Default for Base<T, N> {
    fn default() -> Self {
        Self::empty()
    }
}

impl<T: Real, const N: usize> Base<T, N> {
    /// An empty base.
    pub const fn empty() -> Self {
        Self {
            p: [[T::ZERO; MAX_STATES]; MAX_STATES],
            d: [[T::ZERO; N]; 3],
            removed: 0,
            pack: [SatPack::ZERO; N],
        }
    }
}

impl<T: Real> SatPack<T> {
    /// All zero (the derived `Default`), for `const fn` constructors.
    pub const ZERO: Self = SatPack {
        s: [T::ZERO; 3],
        d0: [T::ZERO; 3],
        c_acc: T::ZERO,
        b_nom: T::ZERO,
        y: T::ZERO,
    };
}

/// A singular subset: `column` had the relative pivot `pivot`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Deficient {
    /// The column (or satellite) whose pivot collapsed.
    pub column: usize,
    /// Its pivot relative to the column norm or diagonal.
    pub pivot: f64,
}

/// sigma, b, sigma_ss and the separation of one subset, per axis E, N, U.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SubsetStats<T> {
    /// sigma_q^(k) from C_int per axis E, N, U, m.
    pub sigma_m: [T; 3],
    /// Nominal bias b_q^(k) per axis, m.
    pub bias_m: [T; 3],
    /// sigma_ss,q^(k) of the separation from all-in-view, per axis, m.
    pub sigma_ss_m: [T; 3],
    /// Solution separation x_q^(k) - x_q^(0) per axis, m.
    pub separation_m: [T; 3],
}

fn bit(i: usize) -> u64 {
    if i < 64 {
        1u64 << i
    } else {
        0
    }
}

/// Factors the subset that keeps the satellites not in `removed` and the
/// columns not in `dropped` (bit c = column c), into `base.p`; then fills
/// `base.d` with S^(B) - `s0` (pass zeros for the all-in-view base).
// In range: every row and column index below is < m = min(geo.m,
// MAX_STATES), the matrices' order. The loops index as the Cholesky and
// the triangular solves are written (and so compile to fewer
// instructions than the iterator forms).
#[allow(clippy::indexing_slicing, clippy::needless_range_loop)]
pub fn factor<T: Real, const N: usize>(
    geo: &Geometry<T, N>,
    removed: u64,
    dropped: u16,
    s0: &[[T; N]; 3],
    base: &mut Base<T, N>,
) -> Result<(), Deficient> {
    let zero = T::of(0.0);
    let m = geo.m.min(MAX_STATES);
    let active = |c: usize| c < m && dropped & (1u16 << c) == 0;
    // Normal matrix, lower triangle (the only one the Cholesky reads),
    // from the rows' structure: ENU then a one-hot clock column (`gdot`).
    let mut a = [[zero; MAX_STATES]; MAX_STATES];
    for (i, ((g, &w), &clk)) in geo
        .g
        .iter()
        .zip(geo.w.iter())
        .zip(geo.col.iter())
        .enumerate()
        .take(geo.n.min(N))
    {
        if removed & bit(i) != 0 {
            continue;
        }
        normal_add(&mut a, g, w, clk);
    }
    // Cholesky A = L L^T in place (lower triangle), active columns only.
    let tol = rank_tolerance::<T>();
    let mut l = [[zero; MAX_STATES]; MAX_STATES];
    for j in 0..m {
        if !active(j) {
            continue;
        }
        let diag = a[j][j];
        let mut s = diag;
        for k in 0..j {
            let v = l[j][k];
            s -= v * v;
        }
        if !(s > tol * diag) {
            return Err(Deficient {
                column: j,
                pivot: if diag > zero {
                    (s / diag).to_f64()
                } else {
                    0.0
                },
            });
        }
        let ljj = s.sqrt();
        l[j][j] = ljj;
        for i in (j + 1)..m {
            if !active(i) {
                continue;
            }
            let mut s = a[i][j];
            for k in 0..j {
                let lik = l[i][k];
                let ljk = l[j][k];
                s -= lik * ljk;
            }
            l[i][j] = s / ljj;
        }
    }
    // P = A^-1, column by column: L z = e_c, L^T p = z.
    base.p = [[zero; MAX_STATES]; MAX_STATES];
    for c in 0..m {
        if !active(c) {
            continue;
        }
        let mut z = [zero; MAX_STATES];
        for i in 0..m {
            if !active(i) {
                continue;
            }
            let mut s = if i == c { T::of(1.0) } else { zero };
            for k in 0..i {
                s -= l[i][k] * z[k];
            }
            let lii = l[i][i];
            z[i] = s / lii;
        }
        for i in (0..m).rev() {
            if !active(i) {
                continue;
            }
            let mut s = z[i];
            for k in (i + 1)..m {
                s -= l[k][i] * base.p[k][c];
            }
            let lii = l[i][i];
            base.p[i][c] = s / lii;
        }
    }
    base.removed = removed;
    for ((drow, s0row), prow) in base.d.iter_mut().zip(s0.iter()).zip(base.p.iter()) {
        for (i, ((x, &s), ((g, &w), &clk))) in drow
            .iter_mut()
            .zip(s0row.iter())
            .zip(geo.g.iter().zip(geo.w.iter()).zip(geo.col.iter()))
            .enumerate()
            .take(geo.n.min(N))
        {
            let s_b = if removed & bit(i) != 0 {
                zero
            } else {
                gdot(prow, g, clk) * w
            };
            *x = s_b - s;
        }
    }
    Ok(())
}

/// Adds w g g^T to the lower triangle of `a` for a geometry row g = (e, n,
/// u, one-hot clock at `clk`): the entries the dense sum touches with a
/// non-zero term, in the same order per entry (the zero terms add exact
/// zeros), so the same values as the dense form.
fn normal_add<T: Real>(
    a: &mut [[T; MAX_STATES]; MAX_STATES],
    g: &[T; MAX_STATES],
    w: T,
    clk: usize,
) {
    let [g0, g1, g2, ..] = *g;
    let [a0, a1, a2, ..] = a;
    a0[0] += (g0 * w) * g0;
    a1[0] += (g1 * w) * g0;
    a1[1] += (g1 * w) * g1;
    a2[0] += (g2 * w) * g0;
    a2[1] += (g2 * w) * g1;
    a2[2] += (g2 * w) * g2;
    if clk >= 3 {
        if let (Some(ac), Some(&gc)) = (a.get_mut(clk), g.get(clk)) {
            let gcw = gc * w;
            let [c0, c1, c2, ..] = ac;
            *c0 += gcw * g0;
            *c1 += gcw * g1;
            *c2 += gcw * g2;
            if let Some(x) = ac.get_mut(clk) {
                *x += gcw * gc;
            }
        }
    }
}

/// p . g for a geometry row g = (e, n, u, one-hot clock at `clk`): the
/// dense dot product's non-zero terms in its order (its other terms are
/// exact zeros), so the same value as [`dot`] over the first m columns
/// for clk < m.
fn gdot<T: Real>(p: &[T; MAX_STATES], g: &[T; MAX_STATES], clk: usize) -> T {
    let [p0, p1, p2, ..] = *p;
    let [g0, g1, g2, ..] = *g;
    let s = T::of(0.0) + p0 * g0 + p1 * g1 + p2 * g2;
    match (p.get(clk), g.get(clk)) {
        (Some(&pc), Some(&gc)) if clk >= 3 => s + pc * gc,
        _ => s,
    }
}

/// a . b over all `MAX_STATES` entries (for vectors that are zero beyond
/// the epoch's m columns).
fn full_dot<T: Real>(a: &[T; MAX_STATES], b: &[T; MAX_STATES]) -> T {
    a.iter()
        .zip(b.iter())
        .fold(T::of(0.0), |acc, (x, y)| acc + *x * *y)
}

fn dot<T: Real>(a: &[T; MAX_STATES], b: &[T; MAX_STATES], m: usize) -> T {
    a.iter()
        .zip(b.iter())
        .take(m)
        .fold(T::of(0.0), |acc, (x, y)| acc + *x * *y)
}

/// The position rows of S^(0) from the all-in-view P0.
pub fn gain_rows<T: Real, const N: usize>(
    geo: &Geometry<T, N>,
    p0: &[[T; MAX_STATES]; MAX_STATES],
    s0: &mut [[T; N]; 3],
) {
    for (row, prow) in s0.iter_mut().zip(p0.iter()) {
        for (x, ((g, &w), &clk)) in row
            .iter_mut()
            .zip(geo.g.iter().zip(geo.w.iter()).zip(geo.col.iter()))
            .take(geo.n)
        {
            *x = gdot(prow, g, clk) * w;
        }
    }
}

/// What the all-in-view base's downdates read instead of passing over
/// the satellites. [`coupling`] starts it once per epoch (the
/// C_acc-weighted information A, the residuals); the rows of a removed
/// satellite j are formed the first time a mode removes it
/// ([`Coupling::row`]), so an epoch that stops at its first failing mode
/// (FDE candidates, tests only) forms one or two rows, not n:
///
/// - `q[j]`: the coupling row `Q[j][i] = g_j^T P0 g_i w_i` (the h_i of the
///   module doc; V's position rows and M are read from it), n m.
/// - `bg[j]`: B g_j with B = P0 A P0, A = sum_i w_i^2 C_acc,i g_i g_i^T
///   (m x m): `g_a^T B g_b = sum_i C_acc,i Q[a][i] Q[b][i]`, the C_acc Gram
///   matrix of the removed rows' coupling rows, which gives sigma_ss
///   without a pass (see `all_in_view`), 2 m^2.
/// - `res`: the all-in-view residuals y - G x^(0), which give the
///   separation without a pass.
/// - `s`, `b_nom`, `biased`: the gain rows s0 and b_nom side by side for
///   the one pass left, b^(k); `biased` is false when every b_nom is
///   exactly 0 (then every b^(k) is exactly 0 and the pass is skipped).
#[derive(Debug, Clone, Copy)]
pub struct Coupling<T, const N: usize> {
    /// Coupling rows `Q[j][i] = g_j^T P0 g_i w_i`.
    pub q: [[T; N]; N],
    /// B g_j per satellite j, B = P0 A P0.
    pub bg: [[T; MAX_STATES]; N],
    /// Bit j: `q[j]` and `bg[j]` are formed for this epoch.
    pub ready: u64,
    /// A = sum_i w_i^2 C_acc,i g_i g_i^T (m x m).
    pub a: [[T; MAX_STATES]; MAX_STATES],
    /// All-in-view residuals y - G x^(0), m.
    pub res: [T; N],
    /// All-in-view gain rows s0 (E, N, U).
    pub s: [[T; N]; 3],
    /// b_nom per satellite, m.
    pub b_nom: [T; N],
    /// False when every b_nom is exactly 0 (the b^(k) pass is skipped).
    pub biased: bool,
}

impl<T: Real, const N: usize> Default for Coupling<T, N> {
    fn default() -> Self {
        Self::empty()
    }
}

impl<T: Real, const N: usize> Coupling<T, N> {
    /// Nothing formed yet.
    pub const fn empty() -> Self {
        let zero = T::ZERO;
        Self {
            q: [[zero; N]; N],
            bg: [[zero; MAX_STATES]; N],
            ready: 0,
            a: [[zero; MAX_STATES]; MAX_STATES],
            res: [zero; N],
            s: [[zero; N]; 3],
            b_nom: [zero; N],
            biased: false,
        }
    }
}

impl<T: Real, const N: usize> Coupling<T, N> {
    /// Forms `q[j]` and `bg[j]` from the all-in-view P0 unless this epoch
    /// already did.
    pub fn row(&mut self, geo: &Geometry<T, N>, p0: &[[T; MAX_STATES]; MAX_STATES], j: usize) {
        if self.ready & bit(j) == 0 {
            self.form_row(geo, p0, j);
        }
    }

    /// [`Self::row`]'s work, out of line (once per satellite and epoch).
    #[inline(never)]
    fn form_row(&mut self, geo: &Geometry<T, N>, p0: &[[T; MAX_STATES]; MAX_STATES], j: usize) {
        let zero = T::of(0.0);
        let m = geo.m.min(MAX_STATES);
        let n = geo.n.min(N);
        let (Some(gj), Some(&cj), Some(qrow), Some(bgj)) = (
            geo.g.get(j),
            geo.col.get(j),
            self.q.get_mut(j),
            self.bg.get_mut(j),
        ) else {
            return;
        };
        // v = P0 g_j.
        let mut v = [zero; MAX_STATES];
        for (vc, prow) in v.iter_mut().zip(p0.iter()).take(m) {
            *vc = gdot(prow, gj, cj);
        }
        for (x, ((gi, &w), &ci)) in qrow
            .iter_mut()
            .zip(geo.g.iter().zip(geo.w.iter()).zip(geo.col.iter()))
            .take(n)
        {
            *x = gdot(&v, gi, ci) * w;
        }
        // B g_j = P0 (A v), over the full width (P0, A and v are zero
        // beyond m: exact zero terms, and the loops unroll).
        let mut t = [zero; MAX_STATES];
        for (tc, arow) in t.iter_mut().zip(self.a.iter()) {
            *tc = full_dot(arow, &v);
        }
        for (x, prow) in bgj.iter_mut().zip(p0.iter()) {
            *x = full_dot(prow, &t);
        }
        self.ready |= bit(j);
    }
}

/// Starts `cp` ([`Coupling`]) for the epoch: no row formed, A, the
/// residuals y - G x^(0) with x^(0) = P0 G^T W y (2 n m + m^2), and the
/// gain rows `s0` with b_nom for the b^(k) pass.
pub fn coupling<T: Real, const N: usize>(
    geo: &Geometry<T, N>,
    base: &Base<T, N>,
    s0: &[[T; N]; 3],
    cp: &mut Coupling<T, N>,
) {
    let zero = T::of(0.0);
    let m = geo.m.min(MAX_STATES);
    let n = geo.n.min(N);
    cp.ready = 0;
    // A = sum_i (w_i^2 C_acc,i) g_i g_i^T (lower triangle, then mirrored).
    let mut a = [[zero; MAX_STATES]; MAX_STATES];
    for (((g, &w), &c), &clk) in geo
        .g
        .iter()
        .zip(geo.w.iter())
        .zip(geo.c_acc.iter())
        .zip(geo.col.iter())
        .take(n)
    {
        normal_add(&mut a, g, w * w * c, clk);
    }
    // i < j < m = min(geo.m, MAX_STATES), the order of A; the transpose
    // reads a[j][i] and writes a[i][j].
    #[allow(clippy::indexing_slicing, clippy::needless_range_loop)]
    for i in 0..m {
        for j in (i + 1)..m {
            a[i][j] = a[j][i];
        }
    }
    cp.a = a;
    // x^(0) = P0 (G^T W y), then the residuals.
    let mut gty = [zero; MAX_STATES];
    for (((g, &w), &y), &clk) in geo
        .g
        .iter()
        .zip(geo.w.iter())
        .zip(geo.y.iter())
        .zip(geo.col.iter())
        .take(n)
    {
        let wy = w * y;
        let [g0, g1, g2, ..] = *g;
        let [t0, t1, t2, ..] = &mut gty;
        *t0 += g0 * wy;
        *t1 += g1 * wy;
        *t2 += g2 * wy;
        if clk >= 3 {
            if let (Some(t), Some(&gc)) = (gty.get_mut(clk), g.get(clk)) {
                *t += gc * wy;
            }
        }
    }
    let mut x0 = [zero; MAX_STATES];
    for (x, prow) in x0.iter_mut().zip(base.p.iter()).take(m) {
        *x = dot(prow, &gty, m);
    }
    for (r, ((g, &y), &clk)) in cp
        .res
        .iter_mut()
        .zip(geo.g.iter().zip(geo.y.iter()).zip(geo.col.iter()))
        .take(n)
    {
        *r = y - gdot(&x0, g, clk);
    }
    cp.s = *s0;
    cp.b_nom = geo.b_nom;
    cp.biased = geo.b_nom.iter().take(n).any(|&b| b != zero);
}

/// The statistics of the subset that removes the satellites `extra` (a
/// bit mask, all kept by `base`) from `base`, by the rank-r downdate of
/// the module doc (the all-in-view gain rows s0 from the base's [`pack`]).
pub fn downdate<T: Real, const N: usize>(
    geo: &Geometry<T, N>,
    base: &Base<T, N>,
    extra: u64,
) -> Result<SubsetStats<T>, Deficient> {
    downdate_coupled(geo, base, extra, None)
}

/// [`downdate`], with the epoch's [`Coupling`] when the base is the
/// all-in-view one: then `all_in_view` (sigma_ss and the separation in
/// closed form, one pass for b^(k); the same quantities to rounding,
/// checked against the dense reference). Otherwise the pass over the
/// satellites, which reads the base's [`pack`] (so `s0` must be the one
/// the pack was made with).
pub fn downdate_coupled<T: Real, const N: usize>(
    geo: &Geometry<T, N>,
    base: &Base<T, N>,
    extra: u64,
    coupling: Option<&mut Coupling<T, N>>,
) -> Result<SubsetStats<T>, Deficient> {
    let none = Deficient {
        column: 0,
        pivot: 0.0,
    };
    // Sizes checked once: every row below is < n <= N, every column < m
    // <= MAX_STATES.
    if geo.n == 0 || geo.n > N || geo.m > MAX_STATES {
        return Err(none);
    }
    let Some((rows, r)) = removed_rows(extra, geo.n) else {
        return Err(none);
    };
    // The coupling describes the all-in-view base only.
    if let Some(cp) = coupling.filter(|_| base.removed == 0) {
        for &j in rows.iter().take(r) {
            cp.row(geo, &base.p, j);
        }
        let cp = &*cp;
        let [a, b, c, d] = rows;
        return match r {
            1 => all_in_view(geo, base, cp, [a]),
            2 => all_in_view(geo, base, cp, [a, b]),
            3 => all_in_view(geo, base, cp, [a, b, c]),
            4 => all_in_view(geo, base, cp, [a, b, c, d]),
            _ => Err(none),
        };
    }
    downdate_pass(geo, base, &rows, r)
}

/// The satellites of `mask` below `n`, ascending, and their count; None
/// when there are more than `MAX_EVENTS`.
fn removed_rows(mask: u64, n: usize) -> Option<([usize; MAX_EVENTS], usize)> {
    let below_n = if n >= 64 { u64::MAX } else { (1u64 << n) - 1 };
    let mut rest = mask & below_n;
    let mut rows = [0usize; MAX_EVENTS];
    let mut r = 0usize;
    while rest != 0 {
        *rows.get_mut(r)? = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        r += 1;
    }
    Some((rows, r))
}

/// The rank-r downdate of any base with a pass over the satellites (SPEC
/// §9.1, the ADD's step 3 for the mode that removes `rows[..r]` from
/// `base`): the Woodbury blocks V and M ([`woodbury_blocks`]), M's
/// Cholesky factor ([`cholesky_removed`]), c_q = M^-1 V_q and sigma_q
/// ([`axis_coefficients`]), then sigma_ss, b^(k) and the separation by
/// the pass ([`kept_pass`]).
fn downdate_pass<T: Real, const N: usize>(
    geo: &Geometry<T, N>,
    base: &Base<T, N>,
    rows: &[usize; MAX_EVENTS],
    r: usize,
) -> Result<SubsetStats<T>, Deficient> {
    let (v, mm) = woodbury_blocks(geo, base, rows, r);
    let l = cholesky_removed(geo, &mm, rows, r)?;
    let mut out = SubsetStats::default();
    let coef = axis_coefficients(base, &v, &l, r, &mut out.sigma_m);
    let [ss, bias, sep] = kept_pass(geo, base, rows, r, &v, &coef);
    for (o, a) in out.sigma_ss_m.iter_mut().zip(ss.iter()) {
        *o = a.sqrt();
    }
    out.bias_m = bias;
    out.separation_m = sep;
    Ok(out)
}

/// V = P_B G_R^T (stored by removed row) and M = W_R^-1 - G_R V, the
/// covariance of the removed residuals (module doc).
// In range: rows[..r] < n <= N (`downdate_coupled`), and r <= MAX_EVENTS.
#[allow(clippy::indexing_slicing)]
fn woodbury_blocks<T: Real, const N: usize>(
    geo: &Geometry<T, N>,
    base: &Base<T, N>,
    rows: &[usize; MAX_EVENTS],
    r: usize,
) -> ([[T; MAX_STATES]; MAX_EVENTS], [[T; MAX_EVENTS]; MAX_EVENTS]) {
    let zero = T::of(0.0);
    let m = geo.m;
    let mut v = [[zero; MAX_STATES]; MAX_EVENTS];
    let mut mm = [[zero; MAX_EVENTS]; MAX_EVENTS];
    for (vr, &i) in v.iter_mut().zip(rows.iter()).take(r) {
        let g = &geo.g[row::<N>(i)];
        for (x, prow) in vr.iter_mut().zip(base.p.iter()).take(m) {
            *x = dot(prow, g, m);
        }
    }
    for (a, (mrow, &ia)) in mm.iter_mut().zip(rows.iter()).enumerate().take(r) {
        let ga = &geo.g[row::<N>(ia)];
        for (b, (y, vb)) in mrow.iter_mut().zip(v.iter()).enumerate().take(r) {
            let mut x = -dot(ga, vb, m);
            if a == b {
                x += T::of(1.0) / geo.w[row::<N>(ia)];
            }
            *y = x;
        }
    }
    (v, mm)
}

/// `i.min(N - 1)`: the identity on a satellite row, which is below n <= N
/// wherever a removed row is read; written so that the build proves the
/// index in bounds and links no panic path (docs/EVIDENCE.md "Panic
/// sites").
#[inline(always)]
fn row<const N: usize>(i: usize) -> usize {
    i.min(N.saturating_sub(1))
}

/// M = L L^T (r x r), each pivot relative to C_int of its removed row: a
/// pivot at or below [`rank_tolerance`] leaves the mode's geometry
/// rank-deficient.
// In range: j, k, i < r <= MAX_EVENTS, and rows[..r] < n <= N.
#[allow(clippy::indexing_slicing)]
fn cholesky_removed<T: Real, const N: usize>(
    geo: &Geometry<T, N>,
    mm: &[[T; MAX_EVENTS]; MAX_EVENTS],
    rows: &[usize; MAX_EVENTS],
    r: usize,
) -> Result<[[T; MAX_EVENTS]; MAX_EVENTS], Deficient> {
    let zero = T::of(0.0);
    let tol = rank_tolerance::<T>();
    let mut l = [[zero; MAX_EVENTS]; MAX_EVENTS];
    let r = r.min(MAX_EVENTS);
    for j in 0..r {
        let ij = rows[j];
        let scale = T::of(1.0) / geo.w[row::<N>(ij)];
        let mut s = mm[j][j];
        for &x in l[j].iter().take(j) {
            s -= x * x;
        }
        if !(s > tol * scale) {
            return Err(Deficient {
                column: ij,
                pivot: (s / scale).to_f64(),
            });
        }
        let ljj = s.sqrt();
        l[j][j] = ljj;
        for i in (j + 1)..r {
            let mut s = mm[i][j];
            for (&lik, &ljk) in l[i].iter().zip(l[j].iter()).take(j) {
                s -= lik * ljk;
            }
            l[i][j] = s / ljj;
        }
    }
    Ok(l)
}

/// c_q = M^-1 V_q per axis q (V_q: the q-th components of the r columns
/// of V; L z = V_q, then L^T c_q = z), and sigma_q = sqrt((P_B)_qq + c_q .
/// V_q) into `sigma_m` (the module doc's (P_k)_qq).
// In range: i, k < r <= MAX_EVENTS, and q < 3 <= MAX_STATES.
#[allow(clippy::indexing_slicing)]
fn axis_coefficients<T: Real, const N: usize>(
    base: &Base<T, N>,
    v: &[[T; MAX_STATES]; MAX_EVENTS],
    l: &[[T; MAX_EVENTS]; MAX_EVENTS],
    r: usize,
    sigma_m: &mut [T; 3],
) -> [[T; MAX_EVENTS]; 3] {
    let zero = T::of(0.0);
    let mut coef = [[zero; MAX_EVENTS]; 3];
    let r = r.min(MAX_EVENTS);
    for (q, (cq, sq)) in coef.iter_mut().zip(sigma_m.iter_mut()).enumerate() {
        let mut z = [zero; MAX_EVENTS];
        for i in 0..r {
            let mut s = v[i][q];
            for k in 0..i {
                s -= l[i][k] * z[k];
            }
            let lii = l[i][i];
            z[i] = s / lii;
        }
        for i in (0..r).rev() {
            let mut s = z[i];
            for k in (i + 1)..r {
                s -= l[k][i] * cq[k];
            }
            let lii = l[i][i];
            cq[i] = s / lii;
        }
        let mut var = base.p[q][q];
        for k in 0..r {
            var += cq[k] * v[k][q];
        }
        *sq = var.sqrt();
    }
    coef
}

/// The pass over the satellites for sigma_ss^2, b^(k) and the separation
/// of the mode ([`run`] on the contiguous runs of kept satellites between
/// the removed ones, then the removed ones' own terms s^2 C_acc and
/// -s y), as [sigma_ss^2, b, separation] per axis. The coupling rows
/// h_k[i] of the removed satellites are formed here as v_k . g_i w_i (r n
/// m), zero at the satellites the base removes (so that there d = d0 =
/// -s and the pass takes their removed-satellite terms s^2 C_acc and -s
/// y, and |s + d| = 0, without a branch).
fn kept_pass<T: Real, const N: usize>(
    geo: &Geometry<T, N>,
    base: &Base<T, N>,
    rows: &[usize; MAX_EVENTS],
    r: usize,
    v: &[[T; MAX_STATES]; MAX_EVENTS],
    coef: &[[T; MAX_EVENTS]; 3],
) -> [[T; 3]; 3] {
    let zero = T::of(0.0);
    let m = geo.m;
    let n = geo.n;
    let zero_row = [zero; N];
    let mut formed = [[zero; N]; MAX_EVENTS];
    let mut qrows: [&[T; N]; MAX_EVENTS] = [&zero_row; MAX_EVENTS];
    for (f, vk) in formed.iter_mut().zip(v.iter()).take(r) {
        let sats = geo.g.iter().zip(geo.w.iter()).enumerate().take(n);
        for ((i, (g, &w)), x) in sats.zip(f.iter_mut()) {
            if base.removed & bit(i) == 0 {
                *x = vk
                    .iter()
                    .zip(g.iter())
                    .take(m)
                    .fold(zero, |acc, (a, b)| acc + *a * *b)
                    * w;
            }
        }
    }
    for (qr, f) in qrows.iter_mut().zip(formed.iter()).take(r) {
        *qr = f;
    }
    let mut acc = [[zero; 3]; 3];
    let mut start = 0usize;
    for &stop in rows.iter().take(r).chain(core::iter::once(&n)) {
        if stop > start {
            let seg = start..stop;
            match r {
                1 => run::<T, N, 1>(&base.pack, &qrows, coef, seg, &mut acc),
                2 => run::<T, N, 2>(&base.pack, &qrows, coef, seg, &mut acc),
                3 => run::<T, N, 3>(&base.pack, &qrows, coef, seg, &mut acc),
                _ => run::<T, N, MAX_EVENTS>(&base.pack, &qrows, coef, seg, &mut acc),
            }
        }
        start = stop + 1;
    }
    let [ss, _, sep] = &mut acc;
    for &i in rows.iter().take(r) {
        if let Some(pk) = base.pack.get(i) {
            for ((a, c), &sq) in ss.iter_mut().zip(sep.iter_mut()).zip(pk.s.iter()) {
                *a += sq * sq * pk.c_acc;
                *c -= sq * pk.y;
            }
        }
    }
    acc
}

/// Per removed row a of the all-in-view base: C_int (= 1/w), C_acc, the
/// all-in-view residual, its coupling row Q[R_a], and per axis q the gain
/// s0_q and V's position row s0_q C_int.
struct RemovedRows<'a, T, const N: usize, const R: usize> {
    c_int: [T; R],
    c_acc: [T; R],
    res: [T; R],
    qrows: [&'a [T; N]; R],
    s: [[T; R]; 3],
    v: [[T; R]; 3],
}

/// Gathers [`RemovedRows`] for `rows` from the geometry and the coupling.
// In range: rows < n <= N (`downdate_coupled`).
#[allow(clippy::indexing_slicing)]
fn removed_rows_of<'a, T: Real, const N: usize, const R: usize>(
    geo: &Geometry<T, N>,
    cp: &'a Coupling<T, N>,
    rows: &[usize; R],
) -> RemovedRows<'a, T, N, R> {
    let zero = T::of(0.0);
    let c_int = rows.map(|i| geo.c_int[row::<N>(i)]);
    let mut s = [[zero; R]; 3];
    let mut v = [[zero; R]; 3];
    for ((sq, vq), srow) in s.iter_mut().zip(v.iter_mut()).zip(cp.s.iter()) {
        for (((x, y), &ia), &ca) in sq
            .iter_mut()
            .zip(vq.iter_mut())
            .zip(rows.iter())
            .zip(c_int.iter())
        {
            *x = srow[row::<N>(ia)];
            *y = *x * ca;
        }
    }
    RemovedRows {
        c_int,
        c_acc: rows.map(|i| geo.c_acc[row::<N>(i)]),
        res: rows.map(|i| cp.res[row::<N>(i)]),
        qrows: rows.map(|i| &cp.q[row::<N>(i)]),
        s,
        v,
    }
}

/// Q[R_a][R_b], and M = W_R^-1 - G_R P0 G_R^T from it (g_a^T P0 g_b =
/// Q[a][b] C_int,b).
// In range: rows < n <= N, and a Q row has N entries.
#[allow(clippy::indexing_slicing)]
fn removed_block<T: Real, const N: usize, const R: usize>(
    rr: &RemovedRows<'_, T, N, R>,
    rows: &[usize; R],
) -> ([[T; R]; R], [[T; R]; R]) {
    let zero = T::of(0.0);
    let mut qrr = [[zero; R]; R];
    let mut mm = [[zero; R]; R];
    for (a, ((qrow, mrow), qa)) in qrr
        .iter_mut()
        .zip(mm.iter_mut())
        .zip(rr.qrows.iter())
        .enumerate()
    {
        for (b, ((x, y), (&ib, &cb))) in qrow
            .iter_mut()
            .zip(mrow.iter_mut())
            .zip(rows.iter().zip(rr.c_int.iter()))
            .enumerate()
        {
            *x = qa[row::<N>(ib)];
            let mut m = -(*x * cb);
            if a == b {
                m += cb;
            }
            *y = m;
        }
    }
    (qrr, mm)
}

/// M = L D L^T (L unit lower triangular), pivots d_j = the Cholesky
/// pivots' squares, relative to C_int of the removed row; no square root,
/// and the reciprocals 1/d_j returned (with L) so that the solves
/// multiply: one division per removed row and mode.
// In range: i, j, k < R, the arrays' length.
#[allow(clippy::indexing_slicing)]
fn ldl_removed<T: Real, const R: usize>(
    mm: &[[T; R]; R],
    rows: &[usize; R],
    c_int: &[T; R],
) -> Result<([[T; R]; R], [T; R]), Deficient> {
    let zero = T::of(0.0);
    let one = T::of(1.0);
    let tol = rank_tolerance::<T>();
    let mut l = [[zero; R]; R];
    let mut d = [zero; R];
    let mut inv = [one; R];
    for j in 0..R {
        let ij = rows[j];
        let scale = c_int[j];
        let lj = l[j];
        // u_k = l_jk d_k (k < j).
        let mut u = [zero; R];
        let mut dj = mm[j][j];
        for k in 0..j {
            let ljk = lj[k];
            let uk = ljk * d[k];
            u[k] = uk;
            dj -= ljk * uk;
        }
        if !(dj > tol * scale) {
            return Err(Deficient {
                column: ij,
                pivot: (dj / scale).to_f64(),
            });
        }
        let rj = one / dj;
        d[j] = dj;
        inv[j] = rj;
        for i in (j + 1)..R {
            let mut sum = mm[i][j];
            for (k, &uk) in u.iter().enumerate().take(j) {
                sum -= l[i][k] * uk;
            }
            l[i][j] = sum * rj;
        }
    }
    Ok((l, inv))
}

/// E_ab = g_Ra^T B g_Rb (symmetric; [`Coupling`]`::bg`), the C_acc Gram
/// matrix of the removed rows' coupling rows.
// In range: rows < n <= N.
#[allow(clippy::indexing_slicing)]
fn gram_removed<T: Real, const N: usize, const R: usize>(
    geo: &Geometry<T, N>,
    cp: &Coupling<T, N>,
    rows: &[usize; R],
) -> [[T; R]; R] {
    let mut e = [[T::of(0.0); R]; R];
    for (a, &ia) in rows.iter().enumerate() {
        let (ga, ca) = (&geo.g[row::<N>(ia)], geo.col[row::<N>(ia)]);
        for (b, &ib) in rows.iter().enumerate().take(a + 1) {
            let x = gdot(&cp.bg[row::<N>(ib)], ga, ca);
            e[a][b] = x;
            e[b][a] = x;
        }
    }
    e
}

/// c_q = M^-1 V_q from M = L D L^T: L z = V_q, then L^T c = D^-1 z (times
/// the reciprocal pivots `inv`).
// In range: i, k < R, the arrays' length.
#[allow(clippy::indexing_slicing)]
fn ldl_solve<T: Real, const R: usize>(l: &[[T; R]; R], inv: &[T; R], vq: &[T; R]) -> [T; R] {
    let zero = T::of(0.0);
    let mut z = [zero; R];
    for i in 0..R {
        let mut sum = vq[i];
        for k in 0..i {
            sum -= l[i][k] * z[k];
        }
        z[i] = sum;
    }
    let mut cq = [zero; R];
    for i in (0..R).rev() {
        let mut sum = z[i] * inv[i];
        for k in (i + 1)..R {
            sum -= l[k][i] * cq[k];
        }
        cq[i] = sum;
    }
    cq
}

/// sigma_ss,q^2 and the separation of one axis without a pass: c_q^T E
/// c_q minus the removed rows' own terms of that form, floored at 0, plus
/// their terms as removed rows (s^2 C_acc); the separation -c_q . r_R
/// (`all_in_view`'s doc).
// In range: j < R, the length of a Q_RR row.
#[allow(clippy::indexing_slicing)]
fn sigma_ss_sq_and_separation<T: Real, const N: usize, const R: usize>(
    cq: &[T; R],
    sq: &[T; R],
    e: &[[T; R]; R],
    qrr: &[[T; R]; R],
    rr: &RemovedRows<'_, T, N, R>,
) -> (T, T) {
    let zero = T::of(0.0);
    let mut quad = zero;
    for (&ca, erow) in cq.iter().zip(e.iter()) {
        let ec = erow
            .iter()
            .zip(cq.iter())
            .fold(zero, |acc, (&x, &c)| acc + x * c);
        quad += ca * ec;
    }
    let mut removed = zero;
    let mut sep = zero;
    for (j, (((&sj, &cj), &ca), &rj)) in sq
        .iter()
        .zip(cq.iter())
        .zip(rr.c_acc.iter())
        .zip(rr.res.iter())
        .enumerate()
    {
        let dj = cq
            .iter()
            .zip(qrr.iter())
            .fold(zero, |acc, (&c, qrow)| acc + c * qrow[j]);
        quad -= dj * dj * ca;
        removed += sj * sj * ca;
        sep -= cj * rj;
    }
    let kept = if quad > zero { quad } else { zero };
    (kept + removed, sep)
}

/// b^(k)_q = sum_kept |s_qi + d_qi| b_nom,i with d_qi = sum_k c_qk
/// Q[R_k][i]: one pass over the kept satellites, by the runs between the
/// removed ones (`rows` ascending).
// In range: j < stop <= N, and a Q row and `cp.s`'s rows have N entries.
#[allow(clippy::indexing_slicing)]
fn bias_kept<T: Real, const N: usize, const R: usize>(
    cp: &Coupling<T, N>,
    rows: &[usize; R],
    qrows: &[&[T; N]; R],
    coef: &[[T; R]; 3],
    n: usize,
) -> [T; 3] {
    let zero = T::of(0.0);
    let mut bias = [zero; 3];
    let mut start = 0usize;
    for stop in rows.iter().copied().chain(core::iter::once(n)) {
        let stop = stop.min(N);
        for j in start..stop {
            let bn = cp.b_nom[j];
            let mut h = [zero; R];
            for (hk, row) in h.iter_mut().zip(qrows.iter()) {
                *hk = row[j];
            }
            for ((bq, cq), srow) in bias.iter_mut().zip(coef.iter()).zip(cp.s.iter()) {
                let t = cq
                    .iter()
                    .zip(h.iter())
                    .fold(srow[j], |x, (&c, &hk)| x + c * hk);
                *bq += t.abs() * bn;
            }
        }
        start = stop + 1;
    }
    bias
}

/// The statistics of the subset that removes the satellites `rows`
/// (ascending, `R` of them, a constant so that every loop below unrolls)
/// from the all-in-view base, from the epoch's [`Coupling`] and without a
/// pass over the satellites for sigma_ss and the separation (SPEC §9.1,
/// the ADD's step 3 for one mode).
///
/// V's position rows are s0_q[i] C_int,i (S0 = P0 G^T W, C_int = 1/w) and
/// M = W_R^-1 - G_R P0 G_R^T has g_a^T P0 g_b = Q[a][b] C_int,b; M = L D
/// L^T (no square root, one reciprocal per removed row); c_q = M^-1 V_q and
/// sigma_q^2 = (P0)_qq + c_q . V_q (module doc). With d_i = (S_k - S_0)
/// e_i:
///
/// - kept i: d_qi = sum_k c_qk Q[R_k][i]; removed i: d_i = -s_i. So
///   sigma_ss,q^2 = sum_kept d_qi^2 C_acc,i + sum_R s_qi^2 C_acc,i, and
///   sum_all_i (sum_k c_qk Q[R_k][i])^2 C_acc,i = c_q^T E c_q with
///   E_ab = g_Ra^T B g_Rb ([`Coupling`]`::bg`): the kept sum is
///   c_q^T E c_q minus the removed rows' terms of the same form (r^2 m
///   per mode instead of r n per axis). The subtraction cancels about as
///   much as forming M does already (relative eps h / (1 - h), h the
///   removed rows' leverage); the kept sum, a sum of squares, is floored
///   at 0 against that rounding.
/// - separation: x^(k) - x^(0) = -V M^-1 r_R with r = y - G x^(0) the
///   all-in-view residuals (the Woodbury form of removing rows), so
///   sep_q = -c_q . r_R.
/// - b^(k)_q = sum_kept |s_qi + d_qi| b_nom,i needs the satellites (the
///   absolute value): one pass, r multiplies per satellite and axis, by
///   the contiguous runs between the removed satellites; skipped when
///   every b_nom is exactly 0 (then every term, so b^(k), is exactly 0).
fn all_in_view<T: Real, const N: usize, const R: usize>(
    geo: &Geometry<T, N>,
    base: &Base<T, N>,
    cp: &Coupling<T, N>,
    rows: [usize; R],
) -> Result<SubsetStats<T>, Deficient> {
    let zero = T::of(0.0);
    let rr = removed_rows_of(geo, cp, &rows);
    let (qrr, mm) = removed_block(&rr, &rows);
    let (l, inv) = ldl_removed(&mm, &rows, &rr.c_int)?;
    let e = gram_removed(geo, cp, &rows);
    let mut out = SubsetStats::default();
    let mut coef = [[zero; R]; 3];
    let axes = coef
        .iter_mut()
        .zip(rr.v.iter().zip(rr.s.iter()))
        .zip(base.p.iter())
        .zip(out.sigma_m.iter_mut())
        .zip(out.sigma_ss_m.iter_mut().zip(out.separation_m.iter_mut()));
    for (q, ((((cq, (vq, sq)), prow), sigma), (sigma_ss, separation))) in axes.enumerate() {
        *cq = ldl_solve(&l, &inv, vq);
        // sigma_q^2 = (P0)_qq + c_q . V_q; q < 3 <= MAX_STATES.
        #[allow(clippy::indexing_slicing)]
        let mut var = prow[q];
        for (&c, &vk) in cq.iter().zip(vq.iter()) {
            var += c * vk;
        }
        let (ss2, sep) = sigma_ss_sq_and_separation(cq, sq, &e, &qrr, &rr);
        *sigma = var.sqrt();
        *sigma_ss = ss2.sqrt();
        *separation = sep;
    }
    if cp.biased {
        out.bias_m = bias_kept(cp, &rows, &rr.qrows, &coef, geo.n);
    }
    Ok(out)
}

/// The kept satellites `seg` of one mode: per axis q,
/// d = d0_q + sum_k c_qk h_k (the change of the gain row), and
/// sigma_ss^2 += d^2 C_acc, b += |s_q + d| b_nom, separation += d y,
/// into `acc` = [sigma_ss^2, b, separation]. `R` removed rows, a
/// constant, so the inner sum unrolls.
#[inline]
fn run<T: Real, const N: usize, const R: usize>(
    pack: &[SatPack<T>; N],
    qrows: &[&[T; N]; MAX_EVENTS],
    coef: &[[T; MAX_EVENTS]; 3],
    seg: core::ops::Range<usize>,
    acc: &mut [[T; 3]; 3],
) {
    let zero = T::of(0.0);
    let mut c = [[zero; R]; 3];
    for (cq, src) in c.iter_mut().zip(coef.iter()) {
        for (a, b) in cq.iter_mut().zip(src.iter()) {
            *a = *b;
        }
    }
    let [ss, bias, sep] = acc;
    let Some(sats) = pack.get(seg.clone()) else {
        return;
    };
    for (j, pk) in seg.zip(sats.iter()) {
        let mut h = [zero; R];
        for (hk, row) in h.iter_mut().zip(qrows.iter()) {
            // j < seg.end <= N (`pack.get(seg)` succeeded), a Q row's length.
            #[allow(clippy::indexing_slicing)]
            {
                *hk = row[j];
            }
        }
        for (((((a, b), e), cq), &d0), &sq) in ss
            .iter_mut()
            .zip(bias.iter_mut())
            .zip(sep.iter_mut())
            .zip(c.iter())
            .zip(pk.d0.iter())
            .zip(pk.s.iter())
        {
            let d = cq
                .iter()
                .zip(h.iter())
                .fold(d0, |x, (ck, hk)| x + *ck * *hk);
            *a += d * d * pk.c_acc;
            *b += (sq + d).abs() * pk.b_nom;
            *e += d * pk.y;
        }
    }
}
