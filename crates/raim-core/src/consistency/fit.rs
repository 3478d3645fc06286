//! The sample of an ARAIM epoch: the goodness of fit of its accuracy
//! model C_acc (SPEC §9.1, error model: C_acc,ii = sigma_URE,i^2 +
//! sigma_tropo^2 + sigma_user^2).
//!
//! ARAIM's all-in-view solution is weighted by C_int^-1 (the integrity
//! model, with sigma_URA). Its residuals normalised by C_acc are not
//! chi-square unless C_int is proportional to C_acc, so the sample is the
//! C_acc-weighted least-squares fit of the same linearised epoch:
//!
//! ```text
//! x = (G^T W G)^-1 G^T W y,   r = y - G x,   q = r^T W r,   W = C_acc^-1,
//! ```
//!
//! which is chi2(n - m) when y = G x + e with e ~ N(0, C_acc). C_acc is
//! the model that says how large the errors are in normal operation (the
//! ISM's sigma_URE is the fault-free one-sigma error); the red-team case
//! of issue 35 is errors larger than it.
//!
//! Computed in f64 whatever the engine's precision (the normal equations
//! of at most `MAX_STATES` unknowns, a Cholesky factor with a relative
//! pivot check, then the residuals formed explicitly, so that q is not a
//! difference of large sums).

use super::ModelCheckError;
use crate::araim::subset::Geometry;
use crate::measurement::MAX_STATES;
use crate::real::Real;

/// One epoch's q and dof.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Fit {
    /// q = r^T C_acc^-1 r.
    pub q: f64,
    /// n - m.
    pub dof: u32,
}

/// Relative pivot below which the normal matrix is singular (the squared
/// counterpart of a QR pivot of 1e-6 relative to its column).
const PIVOT_REL: f64 = 1e-12;

/// The C_acc-weighted fit of the geometry's rows 0..n, columns 0..m (module
/// doc).
///
/// # Errors
/// `Geometry { n, m }` when n <= m, m > `MAX_STATES`, n > N, or the
/// normal matrix is singular; `NotFinite`/`OutOfRange { field: "c_acc_m2" }`
/// for a C_acc that is not a positive number.
pub fn accuracy_fit<T: Real, const N: usize>(geo: &Geometry<T, N>) -> Result<Fit, ModelCheckError> {
    let (n, m) = (geo.n, geo.m);
    let bad = ModelCheckError::Geometry { n, m };
    if n <= m || m > MAX_STATES || n > N || m == 0 {
        return Err(bad);
    }
    let rows = geo.g.iter().zip(geo.c_acc.iter()).zip(geo.y.iter()).take(n);
    // Normal equations A x = b, A = G^T W G, b = G^T W y.
    let mut a = [[0.0f64; MAX_STATES]; MAX_STATES];
    let mut b = [0.0f64; MAX_STATES];
    for ((g, c), y) in rows.clone() {
        let c = c.to_f64();
        if c.is_nan() {
            return Err(ModelCheckError::NotFinite {
                field: "c_acc_m2",
                value: c,
            });
        }
        if !(c > 0.0 && c.is_finite()) {
            return Err(ModelCheckError::OutOfRange {
                field: "c_acc_m2",
                value: c,
                min: f64::MIN_POSITIVE,
                max: f64::MAX,
            });
        }
        let w = 1.0 / c;
        let y = y.to_f64();
        for (j, (arow, bj)) in a.iter_mut().zip(b.iter_mut()).enumerate().take(m) {
            let gj = g.get(j).map_or(0.0, |v| v.to_f64());
            *bj += w * gj * y;
            for (k, ajk) in arow.iter_mut().enumerate().take(m) {
                *ajk += w * gj * g.get(k).map_or(0.0, |v| v.to_f64());
            }
        }
    }
    let x = solve_spd(&mut a, &b, m).ok_or(bad)?;
    let mut q = 0.0;
    for ((g, c), y) in rows {
        let fitted: f64 = g
            .iter()
            .zip(x.iter())
            .take(m)
            .map(|(gj, xj)| gj.to_f64() * xj)
            .sum();
        let r = y.to_f64() - fitted;
        q += r * r / c.to_f64();
    }
    Ok(Fit {
        q,
        dof: u32::try_from(n - m).map_err(|_| bad)?,
    })
}

/// Solves A x = b for the symmetric positive definite m x m `a` (lower
/// Cholesky in place); `None` when a pivot falls below `PIVOT_REL` times
/// its diagonal entry, or is not a positive number.
fn solve_spd(
    a: &mut [[f64; MAX_STATES]; MAX_STATES],
    b: &[f64; MAX_STATES],
    m: usize,
) -> Option<[f64; MAX_STATES]> {
    let m = m.min(MAX_STATES);
    for j in 0..m {
        let diag = *a.get(j)?.get(j)?;
        let mut d = diag;
        for k in 0..j {
            let l = *a.get(j)?.get(k)?;
            d -= l * l;
        }
        if !(d > PIVOT_REL * diag) {
            return None;
        }
        let d = libm::sqrt(d);
        *a.get_mut(j)?.get_mut(j)? = d;
        for i in (j + 1)..m {
            let mut s = *a.get(i)?.get(j)?;
            for k in 0..j {
                s -= a.get(i)?.get(k)? * a.get(j)?.get(k)?;
            }
            *a.get_mut(i)?.get_mut(j)? = s / d;
        }
    }
    // L z = b, then L^T x = z.
    let mut z = [0.0f64; MAX_STATES];
    for i in 0..m {
        let mut s = *b.get(i)?;
        for k in 0..i {
            s -= a.get(i)?.get(k)? * z.get(k)?;
        }
        *z.get_mut(i)? = s / a.get(i)?.get(i)?;
    }
    let mut x = [0.0f64; MAX_STATES];
    for i in (0..m).rev() {
        let mut s = *z.get(i)?;
        for k in (i + 1)..m {
            s -= a.get(k)?.get(i)? * x.get(k)?;
        }
        *x.get_mut(i)? = s / a.get(i)?.get(i)?;
    }
    Some(x)
}
