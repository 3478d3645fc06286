//! Protection levels by the slope method (SPEC §6), and the accuracy
//! (1-sigma ENU) of the least-squares position, both from the whitened gain
//! A = (H^T H)^-1 H^T in local ENU.

use crate::linalg::parity::Parity;

/// Horizontal and vertical protection levels and the satellites that set them.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ProtectionLevels {
    /// HPL = max_i slope_H,i sqrt(lambda_md), m. Infinite when some
    /// satellite's fault would be undetectable (S_ii below the bound).
    pub hpl_m: f64,
    pub vpl_m: f64,
    /// Row of the satellite with the largest horizontal slope.
    pub worst_h_row: Option<usize>,
    pub worst_v_row: Option<usize>,
}

/// slope_H,i = sqrt(A_E,i^2 + A_N,i^2) / sqrt(S_ii), slope_V,i = |A_U,i| /
/// sqrt(S_ii); PL = max slope * sqrt(lambda_md). A satellite with S_ii below
/// `min_s_ii` has an unbounded slope, so its PLs are infinite.
pub fn slope_levels<const N: usize>(
    parity: &Parity<N>,
    lambda_md: f64,
    min_s_ii: f64,
) -> ProtectionLevels {
    let pbias = libm::sqrt(lambda_md);
    let mut out = ProtectionLevels::default();
    let (mut max_h, mut max_v) = (0.0f64, 0.0f64);
    let rows = parity
        .gain(0)
        .iter()
        .zip(parity.gain(1))
        .zip(parity.gain(2))
        .zip(parity.s_ii())
        .enumerate();
    for (row, (((e, n), u), &s)) in rows {
        let (slope_h, slope_v) = if s >= min_s_ii {
            let k = 1.0 / libm::sqrt(s);
            (libm::sqrt(e * e + n * n) * k, libm::fabs(*u) * k)
        } else {
            (f64::INFINITY, f64::INFINITY)
        };
        if slope_h > max_h || out.worst_h_row.is_none() {
            max_h = slope_h;
            out.worst_h_row = Some(row);
        }
        if slope_v > max_v || out.worst_v_row.is_none() {
            max_v = slope_v;
            out.worst_v_row = Some(row);
        }
    }
    out.hpl_m = max_h * pbias;
    out.vpl_m = max_v * pbias;
    out
}

/// 1-sigma position error along E, N, U in metres: sqrt of the diagonal of
/// (H^T H)^-1 (whitened), i.e. sqrt(sum_i A_k,i^2).
pub fn sigma_enu_m<const N: usize>(parity: &Parity<N>) -> [f64; 3] {
    let s = |axis: usize| libm::sqrt(parity.gain(axis).iter().map(|a| a * a).sum::<f64>());
    [s(0), s(1), s(2)]
}
