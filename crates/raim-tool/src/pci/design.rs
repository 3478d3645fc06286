//! Bias designs, detection probability and minimal detectable bias
//! (SPEC §3, §4.3), from the core's distributions (`raim_core::stats::dist`).
//!
//! A bias b (sigma units) on satellite i moves the parity vector by b a_i,
//! so lambda_i = b^2 S_ii and P_D = P(ncx2(d, lambda_i) >= T^2).

use anyhow::{anyhow, bail, Result};
use raim_core::stats::dist;

use super::geometry::Geometry;

/// How the per-satellite biases are chosen.
#[derive(Debug, Clone, Copy, PartialEq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum DesignKind {
    // Each satellite gets the bias that gives the chi-square test P_D.
    PdMatched,
    // One bias for every satellite (given, or chosen so the mean P_D is the target).
    FixedB,
}

/// The detection threshold T^2 for Pfa and d degrees of freedom.
pub fn threshold(pfa: f64, d: usize) -> Result<f64> {
    dist::chi2_quantile_upper(pfa, d as u32).map_err(|e| anyhow!("threshold: {e}"))
}

/// P(ncx2(d, lambda) >= T^2). Above the core's `MAX_LAMBDA` (1e5) the
/// mean lambda + d is thousands of standard deviations above any threshold
/// T^2 < 1e4, so P_D is 1 to double precision.
pub fn p_detect(t2: f64, d: usize, lambda: f64) -> Result<f64> {
    if lambda > dist::MAX_LAMBDA && t2 < 1e4 {
        return Ok(1.0);
    }
    Ok(1.0 - dist::ncx2_cdf(t2, d as u32, lambda).map_err(|e| anyhow!("ncx2_cdf: {e}"))?)
}

/// Minimal detectable bias MDB_i = sqrt(lambda(Pfa, Pmd, d) / S_ii), sigma
/// units; infinite below `min_s_ii`.
pub fn mdb(geom: &Geometry, pfa: f64, pmd: f64, min_s_ii: f64) -> Result<Vec<f64>> {
    let lambda =
        dist::ncx2_lambda(pfa, pmd, geom.d as u32).map_err(|e| anyhow!("ncx2_lambda: {e}"))?;
    Ok(geom
        .s_ii
        .iter()
        .map(|&s| {
            if s >= min_s_ii {
                (lambda / s).sqrt()
            } else {
                f64::INFINITY
            }
        })
        .collect())
}

/// Mean P_D over satellites for one common bias b.
fn mean_pd(geom: &Geometry, t2: f64, b: f64) -> Result<f64> {
    let mut sum = 0.0;
    for &s in &geom.s_ii {
        sum += p_detect(t2, geom.d, b * b * s)?;
    }
    Ok(sum / geom.n() as f64)
}

/// Largest bias the fixed-b search tries, sigma units.
const FIXED_B_MAX_SIGMA: f64 = 1e3;
/// Bisection steps of the fixed-b search (interval 1e3 / 2^60).
const FIXED_B_STEPS: usize = 60;

/// Per-satellite biases (sigma units) for the design.
/// `bias`: one given bias (fixed-b); otherwise `pd` is the target.
pub fn biases(
    geom: &Geometry,
    t2: f64,
    pfa: f64,
    design: DesignKind,
    pd: Option<f64>,
    bias: Option<f64>,
    min_s_ii: f64,
) -> Result<Vec<f64>> {
    match (bias, pd) {
        (Some(b), None) => {
            if !(b.is_finite() && b >= 0.0) {
                bail!("--bias must be finite and >= 0, got {b}");
            }
            Ok(vec![b; geom.n()])
        }
        (None, Some(pd)) => {
            if !(pd > pfa && pd < 1.0) {
                bail!("--pd must be in (Pfa, 1) = ({pfa}, 1), got {pd}");
            }
            match design {
                DesignKind::PdMatched => {
                    let lambda = dist::ncx2_lambda(pfa, 1.0 - pd, geom.d as u32)
                        .map_err(|e| anyhow!("ncx2_lambda(pfa {pfa}, pmd {}): {e}", 1.0 - pd))?;
                    Ok(geom
                        .s_ii
                        .iter()
                        .map(|&s| {
                            if s >= min_s_ii {
                                (lambda / s).sqrt()
                            } else {
                                f64::INFINITY
                            }
                        })
                        .collect())
                }
                DesignKind::FixedB => {
                    let (mut lo, mut hi) = (0.0, FIXED_B_MAX_SIGMA);
                    let reach = mean_pd(geom, t2, hi)?;
                    if reach < pd {
                        bail!("mean P_D reaches only {reach} at b = {hi} sigma; target {pd}");
                    }
                    for _ in 0..FIXED_B_STEPS {
                        let mid = 0.5 * (lo + hi);
                        if mean_pd(geom, t2, mid)? < pd {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    Ok(vec![0.5 * (lo + hi); geom.n()])
                }
            }
        }
        _ => bail!("give exactly one of --pd or --bias"),
    }
}
