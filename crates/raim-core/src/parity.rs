//! Parity space by Householder QR (SPEC §2, seed 000 eqs. 4-5, seed 001 eq. 2).
//!
//! Works on the whitened model (z~ = C^-1/2 z, H~ = C^-1/2 H), so the parity
//! vector is N(U2^T f, I). `U` is never formed: `p` is the tail of `U^T z`;
//! `S_ii = 1 - ||T1^-T h_i||^2`, and the least-squares gain
//! `A = (H^T H)^-1 H^T` has columns `T1^-1 T1^-T h_i`.

use crate::error::RaimError;
use crate::measurement::MAX_STATES;
use crate::qr::Householder;

/// Parity-space quantities of one (whitened) linear model.
#[derive(Debug, Clone)]
pub struct Parity<const N: usize> {
    n: usize,
    m: usize,
    qr: Householder<N>,
    /// U^T z; entries m..n are the parity vector p = U2^T z.
    utz: [f64; N],
    /// Diagonal of S = I - H (H^T H)^-1 H^T.
    s_ii: [f64; N],
    /// Residuals r = S z (whitened).
    residual: [f64; N],
    /// Rows 0..3 of the gain A = (H^T H)^-1 H^T (the position states).
    gain: [[f64; N]; 3],
    /// Least-squares state correction dx = A z.
    dx: [f64; MAX_STATES],
}

impl<const N: usize> Parity<N> {
    /// Factor the whitened column-major `h` (n x m) and project `z`.
    /// Needs n > m (at least one redundant measurement).
    pub fn new(h: &[[f64; N]; MAX_STATES], z: &[f64; N], n: usize, m: usize) -> Result<Self, RaimError> {
        if n <= m {
            return Err(RaimError::TooFewSatellites { have: n, need: m + 1 });
        }
        let qr = Householder::factor(h, n, m)?;
        let mut utz = *z;
        qr.apply_ut(&mut utz);
        let mut rhs = [0.0; MAX_STATES];
        for (r, u) in rhs.iter_mut().zip(utz.iter()).take(m) {
            *r = *u;
        }
        let dx = qr.solve_t(&rhs);
        let mut s_ii = [0.0; N];
        let mut residual = [0.0; N];
        let mut gain = [[0.0; N]; 3];
        for i in 0..n {
            let mut hi = [0.0; MAX_STATES];
            for (dst, col) in hi.iter_mut().zip(h.iter()).take(m) {
                *dst = col.get(i).copied().unwrap_or(0.0);
            }
            let g = qr.solve_tt(&hi);
            let leverage: f64 = g.iter().take(m).map(|v| v * v).sum();
            let a = qr.solve_t(&g);
            let fitted: f64 = hi.iter().zip(dx.iter()).take(m).map(|(a, b)| a * b).sum();
            if let Some(s) = s_ii.get_mut(i) {
                // Clamp rounding: S_ii is in [0, 1] mathematically.
                *s = (1.0 - leverage).clamp(0.0, 1.0);
            }
            if let (Some(r), Some(zi)) = (residual.get_mut(i), z.get(i)) {
                *r = zi - fitted;
            }
            for (row, ak) in gain.iter_mut().zip(a.iter()) {
                if let Some(v) = row.get_mut(i) {
                    *v = *ak;
                }
            }
        }
        Ok(Parity {
            n,
            m,
            qr,
            utz,
            s_ii,
            residual,
            gain,
            dx,
        })
    }

    pub fn rows(&self) -> usize {
        self.n
    }

    pub fn states(&self) -> usize {
        self.m
    }

    /// Degrees of freedom of the test, n - m (the parity dimension).
    pub fn dof(&self) -> usize {
        self.n - self.m
    }

    /// The parity vector p = U2^T z (length n - m).
    pub fn p(&self) -> &[f64] {
        self.utz.get(self.m..self.n).unwrap_or(&[])
    }

    /// Weighted sum of squared residuals, p^T p = ||S z||^2.
    pub fn sse(&self) -> f64 {
        self.p().iter().map(|v| v * v).sum()
    }

    /// S_ii for the active rows.
    pub fn s_ii(&self) -> &[f64] {
        self.s_ii.get(..self.n).unwrap_or(&[])
    }

    /// Whitened residuals r = S z.
    pub fn residuals(&self) -> &[f64] {
        self.residual.get(..self.n).unwrap_or(&[])
    }

    /// Row `axis` (0 = E, 1 = N, 2 = U) of the position gain A.
    pub fn gain(&self, axis: usize) -> &[f64] {
        self.gain.get(axis).and_then(|r| r.get(..self.n)).unwrap_or(&[])
    }

    /// Least-squares state correction dx (first m entries meaningful).
    pub fn dx(&self) -> &[f64; MAX_STATES] {
        &self.dx
    }

    /// The factorisation, for applying U or U^T (MCUSUM transport, SPEC §7.3).
    pub fn qr(&self) -> &Householder<N> {
        &self.qr
    }

    /// U2 y for a parity-space vector y (length n - m): lifts it into
    /// measurement space, indexed like the rows.
    pub fn lift(&self, y: &[f64]) -> [f64; N] {
        let mut x = [0.0; N];
        for (dst, v) in x.iter_mut().skip(self.m).zip(y.iter()).take(self.n - self.m) {
            *dst = *v;
        }
        self.qr.apply_u(&mut x);
        x
    }

    /// U2^T x for a measurement-space vector x: its parity coordinates,
    /// written into `out` (length n - m). Returns the number written.
    pub fn project(&self, x: &[f64; N], out: &mut [f64]) -> usize {
        let mut y = *x;
        for v in y.iter_mut().skip(self.n) {
            *v = 0.0;
        }
        self.qr.apply_ut(&mut y);
        let mut k = 0;
        for (dst, v) in out.iter_mut().zip(y.iter().skip(self.m).take(self.n - self.m)) {
            *dst = *v;
            k += 1;
        }
        k
    }
}
