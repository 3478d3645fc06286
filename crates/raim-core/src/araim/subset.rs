//! Subset solutions from one factorisation (SPEC §9.1 steps 2-3, issue 12).
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
//! squares. A singular M (removing R leaves the geometry rank-deficient)
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
    pub c_acc: [T; N],
    pub b_nom: [T; N],
    pub y: [T; N],
    /// Each satellite's clock column.
    pub col: [usize; N],
}

impl<T: Real, const N: usize> Default for Geometry<T, N> {
    fn default() -> Self {
        Self {
            n: 0,
            m: 0,
            g: [[T::of(0.0); MAX_STATES]; N],
            w: [T::of(0.0); N],
            c_acc: [T::of(0.0); N],
            b_nom: [T::of(0.0); N],
            y: [T::of(0.0); N],
            col: [0; N],
        }
    }
}

/// A factored subset: P_B with the dropped columns zero, and the position
/// rows of S^(B) - S^(0).
#[derive(Debug, Clone, Copy)]
pub struct Base<T, const N: usize> {
    pub p: [[T; MAX_STATES]; MAX_STATES],
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
    pub s: [T; 3],
    pub d0: [T; 3],
    pub c_acc: T,
    pub b_nom: T,
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
        Self {
            p: [[T::of(0.0); MAX_STATES]; MAX_STATES],
            d: [[T::of(0.0); N]; 3],
            removed: 0,
            pack: [SatPack::default(); N],
        }
    }
}

/// A singular subset: `column` had the relative pivot `pivot`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Deficient {
    pub column: usize,
    pub pivot: f64,
}

/// sigma, b, sigma_ss and the separation of one subset, per axis E, N, U.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SubsetStats<T> {
    pub sigma_m: [T; 3],
    pub bias_m: [T; 3],
    pub sigma_ss_m: [T; 3],
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
        let diag = a.get(j).and_then(|r| r.get(j)).copied().unwrap_or(zero);
        let mut s = diag;
        for k in 0..j {
            let v = l.get(j).and_then(|r| r.get(k)).copied().unwrap_or(zero);
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
        if let Some(x) = l.get_mut(j).and_then(|r| r.get_mut(j)) {
            *x = ljj;
        }
        for i in (j + 1)..m {
            if !active(i) {
                continue;
            }
            let mut s = a.get(i).and_then(|r| r.get(j)).copied().unwrap_or(zero);
            for k in 0..j {
                let lik = l.get(i).and_then(|r| r.get(k)).copied().unwrap_or(zero);
                let ljk = l.get(j).and_then(|r| r.get(k)).copied().unwrap_or(zero);
                s -= lik * ljk;
            }
            if let Some(x) = l.get_mut(i).and_then(|r| r.get_mut(j)) {
                *x = s / ljj;
            }
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
                s -= l.get(i).and_then(|r| r.get(k)).copied().unwrap_or(zero)
                    * z.get(k).copied().unwrap_or(zero);
            }
            let lii = l.get(i).and_then(|r| r.get(i)).copied().unwrap_or(zero);
            if let Some(x) = z.get_mut(i) {
                *x = s / lii;
            }
        }
        for i in (0..m).rev() {
            if !active(i) {
                continue;
            }
            let mut s = z.get(i).copied().unwrap_or(zero);
            for k in (i + 1)..m {
                s -= l.get(k).and_then(|r| r.get(i)).copied().unwrap_or(zero)
                    * base
                        .p
                        .get(k)
                        .and_then(|r| r.get(c))
                        .copied()
                        .unwrap_or(zero);
            }
            let lii = l.get(i).and_then(|r| r.get(i)).copied().unwrap_or(zero);
            if let Some(x) = base.p.get_mut(i).and_then(|r| r.get_mut(c)) {
                *x = s / lii;
            }
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
    let gc = g.get(clk).copied().unwrap_or(T::of(0.0));
    let [a0, a1, a2, ..] = a;
    a0[0] += (g0 * w) * g0;
    a1[0] += (g1 * w) * g0;
    a1[1] += (g1 * w) * g1;
    a2[0] += (g2 * w) * g0;
    a2[1] += (g2 * w) * g1;
    a2[2] += (g2 * w) * g2;
    if clk >= 3 {
        if let Some(ac) = a.get_mut(clk) {
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

/// The coupling matrix of a base, Q[j][i] = g_j^T P_B g_i w_i for the
/// satellites j, i of the epoch: the h_i of the module doc are its rows
/// at the removed satellites, so a downdate with it reads h instead of
/// forming r dot products of length m per satellite (n^2 m once per epoch
/// against r m n per mode; with 465 modes on base 0 at 30 satellites, the
/// per-mode pass is about a third of its former cost).
pub fn coupling<T: Real, const N: usize>(
    geo: &Geometry<T, N>,
    base: &Base<T, N>,
    q: &mut [[T; N]; N],
) {
    let zero = T::of(0.0);
    let m = geo.m.min(MAX_STATES);
    for ((qrow, gj), &cj) in q
        .iter_mut()
        .zip(geo.g.iter())
        .zip(geo.col.iter())
        .take(geo.n.min(N))
    {
        // v = P_B g_j.
        let mut v = [zero; MAX_STATES];
        for (vc, prow) in v.iter_mut().zip(base.p.iter()).take(m) {
            *vc = gdot(prow, gj, cj);
        }
        for (x, ((gi, &w), &ci)) in qrow
            .iter_mut()
            .zip(geo.g.iter().zip(geo.w.iter()).zip(geo.col.iter()))
            .take(geo.n.min(N))
        {
            *x = gdot(&v, gi, ci) * w;
        }
    }
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

/// [`downdate`], with the base's [`coupling`] matrix when it is at hand
/// (the same numbers, summed in another order). Reads the base's
/// [`pack`] (so `s0` must be the one the pack was made with).
pub fn downdate_coupled<T: Real, const N: usize>(
    geo: &Geometry<T, N>,
    base: &Base<T, N>,
    extra: u64,
    coupling: Option<&[[T; N]; N]>,
) -> Result<SubsetStats<T>, Deficient> {
    let zero = T::of(0.0);
    let m = geo.m.min(MAX_STATES);
    let n = geo.n.min(N);
    // The removed rows.
    let mut rows = [0usize; MAX_EVENTS];
    let mut r = 0usize;
    for i in 0..n {
        if extra & bit(i) != 0 {
            if let Some(x) = rows.get_mut(r) {
                *x = i;
            }
            r += 1;
        }
    }
    if r > MAX_EVENTS {
        return Err(Deficient {
            column: 0,
            pivot: 0.0,
        });
    }
    // V = P_B G_R^T (stored by removed row), M = W_R^-1 - G_R V. With
    // the coupling matrix both are read, not formed: the position rows of
    // V are s0_q[i] / w_i (S0 = P0 G^T W) and g_a^T P0 g_b = Q[a][b] / w_b
    // (only the position rows of V are used on that path).
    let mut v = [[zero; MAX_STATES]; MAX_EVENTS];
    let mut mm = [[zero; MAX_EVENTS]; MAX_EVENTS];
    if let Some(cm) = coupling {
        for (a, (vr, &ia)) in v.iter_mut().zip(rows.iter()).take(r).enumerate() {
            let wa = geo.w.get(ia).copied().unwrap_or(T::of(1.0));
            if let Some(pk) = base.pack.get(ia) {
                for (x, &sq) in vr.iter_mut().zip(pk.s.iter()) {
                    *x = sq / wa;
                }
            }
            let qa = cm.get(ia);
            if let Some(mrow) = mm.get_mut(a) {
                for (b, (y, &ib)) in mrow.iter_mut().zip(rows.iter()).take(r).enumerate() {
                    let wb = geo.w.get(ib).copied().unwrap_or(T::of(1.0));
                    let mut x = -qa.and_then(|row| row.get(ib)).copied().unwrap_or(zero) / wb;
                    if a == b {
                        x += T::of(1.0) / wa;
                    }
                    *y = x;
                }
            }
        }
    } else {
        for (vr, &i) in v.iter_mut().zip(rows.iter()).take(r) {
            let g = geo.g.get(i).copied().unwrap_or([zero; MAX_STATES]);
            for (c, x) in vr.iter_mut().enumerate().take(m) {
                let prow = base.p.get(c).copied().unwrap_or([zero; MAX_STATES]);
                *x = dot(&prow, &g, m);
            }
        }
        for a in 0..r {
            let ia = rows.get(a).copied().unwrap_or(0);
            let ga = geo.g.get(ia).copied().unwrap_or([zero; MAX_STATES]);
            for b in 0..r {
                let vb = v.get(b).copied().unwrap_or([zero; MAX_STATES]);
                let mut x = -dot(&ga, &vb, m);
                if a == b {
                    x += T::of(1.0) / geo.w.get(ia).copied().unwrap_or(T::of(1.0));
                }
                if let Some(y) = mm.get_mut(a).and_then(|row| row.get_mut(b)) {
                    *y = x;
                }
            }
        }
    }
    // Cholesky of M (r x r), pivots relative to C_int of the removed row.
    let tol = rank_tolerance::<T>();
    let mut l = [[zero; MAX_EVENTS]; MAX_EVENTS];
    for j in 0..r {
        let ij = rows.get(j).copied().unwrap_or(0);
        let scale = T::of(1.0) / geo.w.get(ij).copied().unwrap_or(T::of(1.0));
        let mut s = mm.get(j).and_then(|x| x.get(j)).copied().unwrap_or(zero);
        for k in 0..j {
            let x = l.get(j).and_then(|x| x.get(k)).copied().unwrap_or(zero);
            s -= x * x;
        }
        if !(s > tol * scale) {
            return Err(Deficient {
                column: ij,
                pivot: (s / scale).to_f64(),
            });
        }
        let ljj = s.sqrt();
        if let Some(x) = l.get_mut(j).and_then(|x| x.get_mut(j)) {
            *x = ljj;
        }
        for i in (j + 1)..r {
            let mut s = mm.get(i).and_then(|x| x.get(j)).copied().unwrap_or(zero);
            for k in 0..j {
                s -= l.get(i).and_then(|x| x.get(k)).copied().unwrap_or(zero)
                    * l.get(j).and_then(|x| x.get(k)).copied().unwrap_or(zero);
            }
            if let Some(x) = l.get_mut(i).and_then(|x| x.get_mut(j)) {
                *x = s / ljj;
            }
        }
    }
    // c_q = M^-1 V_q (V_q: the q-th components of the r columns of V).
    let mut coef = [[zero; MAX_EVENTS]; 3];
    let mut out = SubsetStats::default();
    for (q, cq) in coef.iter_mut().enumerate() {
        let mut z = [zero; MAX_EVENTS];
        for i in 0..r {
            let mut s = v.get(i).and_then(|x| x.get(q)).copied().unwrap_or(zero);
            for k in 0..i {
                s -= l.get(i).and_then(|x| x.get(k)).copied().unwrap_or(zero)
                    * z.get(k).copied().unwrap_or(zero);
            }
            let lii = l
                .get(i)
                .and_then(|x| x.get(i))
                .copied()
                .unwrap_or(T::of(1.0));
            if let Some(x) = z.get_mut(i) {
                *x = s / lii;
            }
        }
        for i in (0..r).rev() {
            let mut s = z.get(i).copied().unwrap_or(zero);
            for k in (i + 1)..r {
                s -= l.get(k).and_then(|x| x.get(i)).copied().unwrap_or(zero)
                    * cq.get(k).copied().unwrap_or(zero);
            }
            let lii = l
                .get(i)
                .and_then(|x| x.get(i))
                .copied()
                .unwrap_or(T::of(1.0));
            if let Some(x) = cq.get_mut(i) {
                *x = s / lii;
            }
        }
        let mut var = base
            .p
            .get(q)
            .and_then(|x| x.get(q))
            .copied()
            .unwrap_or(zero);
        for k in 0..r {
            var += cq.get(k).copied().unwrap_or(zero)
                * v.get(k).and_then(|x| x.get(q)).copied().unwrap_or(zero);
        }
        if let Some(x) = out.sigma_m.get_mut(q) {
            *x = var.sqrt();
        }
    }
    // The coupling rows h_k[i] of the removed satellites: the base's
    // coupling matrix when at hand, else v_k . g_i w_i here (r n m), zero
    // at the satellites the base removes (so that there d = d0 = -s and
    // the pass takes their removed-satellite terms s^2 C_acc and -s y,
    // and |s + d| = 0, without a branch).
    let zero_row = [zero; N];
    let mut formed = [[zero; N]; MAX_EVENTS];
    let mut qrows: [&[T; N]; MAX_EVENTS] = [&zero_row; MAX_EVENTS];
    match coupling {
        Some(cm) => {
            for (qr, &i) in qrows.iter_mut().zip(rows.iter()).take(r) {
                if let Some(row) = cm.get(i) {
                    *qr = row;
                }
            }
        }
        None => {
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
        }
    }
    // The kept satellites in the contiguous runs between the removed ones
    // (sorted ascending), then the removed ones' own terms.
    let mut acc = [[zero; 3]; 3];
    let mut start = 0usize;
    for &stop in rows.iter().take(r).chain(core::iter::once(&n)) {
        if stop > start {
            let seg = start..stop;
            match r {
                1 => run::<T, N, 1>(&base.pack, &qrows, &coef, seg, &mut acc),
                2 => run::<T, N, 2>(&base.pack, &qrows, &coef, seg, &mut acc),
                3 => run::<T, N, 3>(&base.pack, &qrows, &coef, seg, &mut acc),
                _ => run::<T, N, MAX_EVENTS>(&base.pack, &qrows, &coef, seg, &mut acc),
            }
        }
        start = stop + 1;
    }
    let [mut ss, bias, mut sep] = acc;
    for &i in rows.iter().take(r) {
        if let Some(pk) = base.pack.get(i) {
            for ((a, c), &sq) in ss.iter_mut().zip(sep.iter_mut()).zip(pk.s.iter()) {
                *a += sq * sq * pk.c_acc;
                *c -= sq * pk.y;
            }
        }
    }
    for q in 0..3 {
        if let (Some(o), Some(a)) = (out.sigma_ss_m.get_mut(q), ss.get(q)) {
            *o = a.sqrt();
        }
    }
    out.bias_m = bias;
    out.separation_m = sep;
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
            *hk = row.get(j).copied().unwrap_or(zero);
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
