//! Effective sample quantity: seed 003's claims 1-5 (SPEC §9.2).
//!
//! From one ARAIM epoch ([`AraimOutput`]) and one axis:
//!
//! - P_k, the probability of hazardously misleading information with no
//!   detection for fault mode k, read the way the ADD's PL equation bounds
//!   it (SPEC §9.1 step 5): P_k = p_k Q((PL - T_k - b_k) / sigma_k) for the
//!   faulted modes, and P_0 = 2 Q((PL - b_0) / sigma_0) for the fault-free
//!   hypothesis (the seed's sum starts at k = 0, claim 2). PL is the
//!   epoch's protection level on that axis, so that
//!   sum_k P_k = the allocated integrity risk at the exact root (a check
//!   the tests make);
//! - P_Sigma = sum_k P_k (claim 2), P_max = max_k P_k (claim 3);
//! - N* = P_Sigma / P_max (claim 4), always >= 1;
//! - dT_e = T / N* for a window T (claim 5).
//!
//! [`Resampler`] then takes the epoch stream and says which epochs form the
//! effective measurement set {x_e}: N* is taken at the epoch that opens
//! each window, and the epochs emitted are the first at or after each
//! t_0 + j dT_e inside the window. [`statistic`] is the seed's test
//! x_e - x^(0) against its threshold on an emitted epoch: the ARAIM
//! solution separations |x_q^(k) - x_q^(0)| against T_k,q, as the largest
//! ratio. Probabilities are `f64` (precision policy, `real.rs`).

mod resample;
#[cfg(test)]
mod tests;

pub use resample::{Resampler, Sample, TIME_TOL_S};

use super::{AraimOutput, ModeStatus, PlOutput};
use crate::real::Real;
use crate::stats::dist::normal_q;

/// Why N* (or the resampling) could not be formed.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EsqError {
    /// The epoch has no protection level on the axis (ARAIM returned
    /// before step 5: unmonitored, mode capacity, PL not bracketed).
    NoProtectionLevel {
        /// The axis asked for (0 E, 1 N, 2 U).
        axis: usize,
    },
    /// An axis index outside 0..3 (0 E, 1 N, 2 U).
    BadAxis {
        /// The axis received.
        axis: usize,
    },
    /// Every P_k underflowed to zero: N* is 0/0.
    ZeroRisk,
    /// A non-finite or out-of-range quantity (field name and value).
    NotFinite {
        /// Name of the offending quantity.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// A window length or N* that is not positive and finite, or N* < 1;
    /// an epoch time outside `measurement::EPOCH_TIME_S`.
    OutOfRange {
        /// Name of the offending field.
        field: &'static str,
        /// Its value (s, or samples for N*).
        value: f64,
    },
    /// The epoch time went backwards (or repeated) in the stream.
    NonMonotonicTime {
        /// The previous epoch's time, s.
        previous_s: f64,
        /// This epoch's time, s.
        now_s: f64,
    },
}

impl core::fmt::Display for EsqError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            EsqError::NoProtectionLevel { axis } => {
                write!(f, "the epoch has no protection level on axis {axis}")
            }
            EsqError::BadAxis { axis } => write!(f, "axis {axis} outside 0..3 (E, N, U)"),
            EsqError::ZeroRisk => write!(f, "every mode's P_k underflowed to zero"),
            EsqError::NotFinite { field, value } => write!(f, "non-finite {field}: {value}"),
            EsqError::OutOfRange { field, value } => write!(f, "{field} = {value} is out of range"),
            EsqError::NonMonotonicTime { previous_s, now_s } => {
                write!(f, "time {now_s} s does not follow {previous_s} s")
            }
        }
    }
}

impl core::error::Error for EsqError {}

/// Which mode holds P_max.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum WorstMode {
    /// The fault-free hypothesis (k = 0).
    FaultFree,
    /// `out.modes[index]`.
    Mode {
        /// Index into `out.modes`.
        index: usize,
    },
}

/// Claims 2-4 on one axis of one epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EffectiveSamples {
    /// The axis (0 E, 1 N, 2 U).
    pub axis: usize,
    /// The protection level the P_k were evaluated at (m).
    pub pl_m: f64,
    /// P_0, the fault-free term 2 Q((PL - b_0) / sigma_0).
    pub p_fault_free: f64,
    /// P_Sigma = sum over k = 0.. of P_k.
    pub p_sigma: f64,
    /// P_max = max over k = 0.. of P_k.
    pub p_max: f64,
    /// The hypothesis whose P_k is P_max.
    pub worst: WorstMode,
    /// N* = P_Sigma / P_max (>= 1).
    pub n_star: f64,
    /// The monitored modes that entered the sum (k >= 1).
    pub n_modes: usize,
}

impl EffectiveSamples {
    /// dT_e = T / N* (claim 5), in seconds.
    ///
    /// # Errors
    /// `OutOfRange` when `window_s` is not positive and finite.
    pub fn interval_s(&self, window_s: f64) -> Result<f64, EsqError> {
        if !(window_s > 0.0 && window_s.is_finite()) {
            return Err(EsqError::OutOfRange {
                field: "window_s",
                value: window_s,
            });
        }
        Ok(window_s / self.n_star)
    }
}

/// P_k = p Q((pl - offset) / sigma): one mode's risk of HMI with no
/// detection at the protection level `pl_m`, where offset = T_k + b_k for a
/// faulted mode (p = p_k) and offset = b_0 for the fault-free one (p = 2).
pub fn mode_risk(p: f64, pl_m: f64, offset_m: f64, sigma_m: f64) -> f64 {
    p * normal_q((pl_m - offset_m) / sigma_m)
}

fn finite(field: &'static str, value: f64) -> Result<f64, EsqError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(EsqError::NotFinite { field, value })
    }
}

/// The protection level of `axis` in the output the configuration selects
/// (the ADD bracket output or the exact root).
fn axis_pl<T, const K: usize>(
    out: &AraimOutput<T, K>,
    which: PlOutput,
    axis: usize,
) -> Result<f64, EsqError> {
    let pl = match which {
        PlOutput::AddBracket => out.pl_add,
        PlOutput::Exact => out.pl_exact,
    };
    let v = match axis {
        0 => pl.hpl_axes_m[0],
        1 => pl.hpl_axes_m[1],
        2 => pl.vpl_m,
        _ => return Err(EsqError::BadAxis { axis }),
    };
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(EsqError::NoProtectionLevel { axis })
    }
}

/// Claims 2-4: P_k for every monitored mode and the fault-free term at the
/// epoch's protection level on `axis` (taken from `pl`: the ADD bracket
/// output or the exact root), then P_Sigma, P_max and N*.
///
/// # Errors
/// `BadAxis`, `NoProtectionLevel` (no PL on this epoch), `NotFinite`,
/// `ZeroRisk`.
pub fn effective_samples<T: Real, const K: usize>(
    out: &AraimOutput<T, K>,
    axis: usize,
    pl: PlOutput,
) -> Result<EffectiveSamples, EsqError> {
    let pl_m = axis_pl(out, pl, axis)?;
    let b0 = finite(
        "bias0_m",
        out.bias0_m.get(axis).map_or(f64::NAN, |v| v.to_f64()),
    )?;
    let s0 = finite(
        "sigma0_m",
        out.sigma0_m.get(axis).map_or(f64::NAN, |v| v.to_f64()),
    )?;
    let p0 = finite("p_fault_free", mode_risk(2.0, pl_m, b0, s0))?;
    let mut p_sigma = p0;
    let mut p_max = p0;
    let mut worst = WorstMode::FaultFree;
    let mut n_modes = 0;
    for (index, m) in out.modes.iter().enumerate() {
        if m.status != ModeStatus::Monitored {
            continue;
        }
        let t = m.threshold_m.get(axis).map_or(f64::NAN, |v| v.to_f64());
        let b = m.stats.bias_m.get(axis).map_or(f64::NAN, |v| v.to_f64());
        let s = m.stats.sigma_m.get(axis).map_or(f64::NAN, |v| v.to_f64());
        let pk = finite("p_k", mode_risk(m.events.prior, pl_m, t + b, s))?;
        p_sigma += pk;
        n_modes += 1;
        if pk > p_max {
            p_max = pk;
            worst = WorstMode::Mode { index };
        }
    }
    if !(p_max > 0.0) {
        return Err(EsqError::ZeroRisk);
    }
    Ok(EffectiveSamples {
        axis,
        pl_m,
        p_fault_free: p0,
        p_sigma,
        p_max,
        worst,
        n_star: p_sigma / p_max,
        n_modes,
    })
}

/// The seed's test statistic on an emitted epoch (step S104): the
/// solution separations x_q^(k) - x_q^(0) against T_k,q, reduced to the
/// largest ratio |x_q^(k) - x_q^(0)| / T_k,q over the monitored modes and
/// the three axes. Fault when the ratio exceeds 1.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SeparationTest {
    /// Largest |separation| / threshold (NaN propagates as a fault).
    pub ratio: f64,
    /// The separation and threshold of that mode and axis (m).
    pub separation_m: f64,
    /// The threshold T_k,q of that mode and axis, m.
    pub threshold_m: f64,
    /// The mode index in `out.modes` and the axis, if any mode was tested.
    pub mode: Option<usize>,
    /// The axis of the largest ratio (0 E, 1 N, 2 U).
    pub axis: usize,
    /// Every monitored mode passed (the ARAIM verdict).
    pub passed: bool,
}

/// The largest normalised separation of the epoch (see [`SeparationTest`]).
pub fn statistic<T: Real, const K: usize>(out: &AraimOutput<T, K>) -> SeparationTest {
    let mut best = SeparationTest {
        ratio: 0.0,
        separation_m: 0.0,
        threshold_m: 0.0,
        mode: None,
        axis: 0,
        passed: out.detection_passed,
    };
    for (index, m) in out.modes.iter().enumerate() {
        if m.status != ModeStatus::Monitored {
            continue;
        }
        for (axis, (sep, thr)) in m
            .stats
            .separation_m
            .iter()
            .zip(m.threshold_m.iter())
            .enumerate()
        {
            let (s, t) = (sep.to_f64(), thr.to_f64());
            let r = s.abs() / t;
            // A NaN ratio is kept (it is a failed test, never an all clear).
            if r.is_nan() || r > best.ratio || best.mode.is_none() {
                if best.ratio.is_nan() {
                    continue;
                }
                best = SeparationTest {
                    ratio: r,
                    separation_m: s,
                    threshold_m: t,
                    mode: Some(index),
                    axis,
                    passed: out.detection_passed,
                };
            }
        }
    }
    best
}
#[cfg(test)]
mod esq_cov_tests;
