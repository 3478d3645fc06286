//! Protection levels by the slope method (SPEC §6), and the accuracy
//! (1-sigma ENU) of the least-squares position, both from the whitened gain
//! A = (H^T H)^-1 H^T in local ENU.

use crate::linalg::parity::Parity;
use crate::real::Real;

/// Horizontal and vertical protection levels and the satellites that set them.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ProtectionLevels {
    /// HPL = max_i slope_H,i sqrt(lambda_md), m. Infinite when some
    /// satellite's fault would be undetectable (S_ii below the bound).
    pub hpl_m: f64,
    /// VPL = max_i slope_V,i sqrt(lambda_md), m; infinite as HPL.
    pub vpl_m: f64,
    /// Row of the satellite with the largest horizontal slope.
    pub worst_h_row: Option<usize>,
    /// Row of the satellite with the largest vertical slope.
    pub worst_v_row: Option<usize>,
}

/// slope_H,i = sqrt(A_E,i^2 + A_N,i^2) / sqrt(S_ii), slope_V,i = |A_U,i| /
/// sqrt(S_ii); PL = max slope * sqrt(lambda_md). A satellite with S_ii below
/// `min_s_ii` has an unbounded slope, so its PLs are infinite.
pub fn slope_levels<const N: usize, T: Real>(
    parity: &Parity<N, T>,
    lambda_md: f64,
    min_s_ii: f64,
) -> ProtectionLevels {
    slope_levels_rows(parity.gains(), parity.s_ii(), lambda_md, min_s_ii)
}

/// `slope_levels` on the gain rows E, N, U and S_ii. A slope that is NaN
/// (a NaN gain or S_ii) counts as infinite: the largest-slope search must
/// never skip a satellite whose slope it cannot evaluate (a NaN
/// compares false and used to be passed over, leaving a finite PL).
/// The slopes are computed and compared in `T`; the PLs, slope times
/// sqrt(lambda_md), in f64.
pub fn slope_levels_rows<T: Real>(
    gain_enu: [&[T]; 3],
    s_ii: &[T],
    lambda_md: f64,
    min_s_ii: f64,
) -> ProtectionLevels {
    let pbias = libm::sqrt(lambda_md);
    let min_s_ii = T::of(min_s_ii);
    let mut out = ProtectionLevels::default();
    let (mut max_h, mut max_v) = (T::zero(), T::zero());
    let [ge, gn, gu] = gain_enu;
    let rows = ge.iter().zip(gn).zip(gu).zip(s_ii).enumerate();
    let inf = T::of(f64::INFINITY);
    let nan_is_infinite = |x: T| if x.is_nan_m() { inf } else { x };
    for (row, (((&e, &n), &u), &s)) in rows {
        let (slope_h, slope_v) = if s >= min_s_ii {
            let k = T::one() / s.sqrt();
            ((e * e + n * n).sqrt() * k, u.abs() * k)
        } else {
            (inf, inf)
        };
        let (slope_h, slope_v) = (nan_is_infinite(slope_h), nan_is_infinite(slope_v));
        if slope_h > max_h || out.worst_h_row.is_none() {
            max_h = slope_h;
            out.worst_h_row = Some(row);
        }
        if slope_v > max_v || out.worst_v_row.is_none() {
            max_v = slope_v;
            out.worst_v_row = Some(row);
        }
    }
    out.hpl_m = max_h.to_f64() * pbias;
    out.vpl_m = max_v.to_f64() * pbias;
    out
}

/// 1-sigma position error along E, N, U in metres: sqrt of the diagonal of
/// (H^T H)^-1 (whitened), i.e. sqrt(sum_i A_k,i^2).
pub fn sigma_enu_m<const N: usize, T: Real>(parity: &Parity<N, T>) -> [f64; 3] {
    // In four lanes where the precision sums so (`linalg::Kernels::LANE_SUMS`, f64:
    // the same sum up to its last bits, vectorised), else left to right.
    let s = |g: &[T]| {
        let ssq = if T::LANE_SUMS {
            crate::linalg::qr::dot_lanes(g, g)
        } else {
            g.iter().fold(T::zero(), |acc, a| acc + *a * *a)
        };
        ssq.sqrt().to_f64()
    };
    parity.gains().map(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A NaN gain on one row gives an infinite PL with that row as the
    /// worst, wherever the row is (first, middle, last); the finite rows
    /// alone give the brute-force maximum slope times sqrt(lambda).
    ///
    /// Verifies: SAFE-NAN
    #[test]
    fn a_nan_slope_is_never_skipped() {
        const PL_TOL_M: f64 = 1e-12;
        let e = [0.3f64, -0.2, 0.5, 0.1];
        let n = [0.1f64, 0.4, -0.2, 0.2];
        let u = [0.6f64, -0.9, 0.3, 0.2];
        let s = [0.5f64, 0.6, 0.4, 0.7];
        let lambda = 30.0;
        let clean = slope_levels_rows([&e, &n, &u], &s, lambda, 1e-4);
        let brute_h = (0..4)
            .map(|i| (e[i] * e[i] + n[i] * n[i]).sqrt() / s[i].sqrt())
            .fold(0.0f64, f64::max);
        let brute_v = (0..4)
            .map(|i| u[i].abs() / s[i].sqrt())
            .fold(0.0f64, f64::max);
        assert!((clean.hpl_m - brute_h * lambda.sqrt()).abs() < PL_TOL_M);
        assert!((clean.vpl_m - brute_v * lambda.sqrt()).abs() < PL_TOL_M);
        for bad in 0..4 {
            let (mut e2, mut u2, mut s2) = (e, u, s);
            e2[bad] = f64::NAN;
            let pl = slope_levels_rows([&e2, &n, &u], &s, lambda, 1e-4);
            assert_eq!(pl.hpl_m, f64::INFINITY, "row {bad}");
            assert_eq!(pl.worst_h_row, Some(bad));
            u2[bad] = f64::NAN;
            let pl = slope_levels_rows([&e, &n, &u2], &s, lambda, 1e-4);
            assert_eq!(pl.vpl_m, f64::INFINITY, "row {bad}");
            assert_eq!(pl.worst_v_row, Some(bad));
            s2[bad] = f64::NAN;
            let pl = slope_levels_rows([&e, &n, &u], &s2, lambda, 1e-4);
            assert_eq!((pl.hpl_m, pl.vpl_m), (f64::INFINITY, f64::INFINITY));
        }
    }
}
