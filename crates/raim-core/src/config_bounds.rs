//! Operational bounds of the configuration (docs/PROTOCOL.md
//! "Configuration bounds").
//!
//! `Config::validate` checks every field against these ranges, so that every
//! entry point (the firmware's `Configure`, the CLI, a library caller) has
//! the same rules. The bounds are chosen so that no accepted configuration
//! switches detection off or makes the protection levels optimistic: with
//! Pfa = 1e-300 the chi-square threshold is ~37 sigma at 4 dof and a 160 m
//! step on one of 8 satellites passes as `Ok` (test
//! `config_bounds::tests::pfa_1e_300_is_refused_and_160_m_is_excluded`).
//!
//! Each bound is inclusive and refuses NaN (every comparison is written so
//! that NaN falls outside). A rejection is `RaimError::OutOfRange` carrying
//! the field name, the offending value and the bound.

use crate::config::{Config, FdeMethod, FiRule};
use crate::error::RaimError;
use crate::snapshot::fde::MAX_EXCLUSIONS;

/// An inclusive range `[min, max]` for one configuration field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound {
    /// Name of the `Config` field.
    pub field: &'static str,
    /// Smallest value accepted.
    pub min: f64,
    /// Largest value accepted.
    pub max: f64,
}

impl Bound {
    /// True when `min <= value <= max` (false for NaN).
    pub const fn contains(&self, value: f64) -> bool {
        value >= self.min && value <= self.max
    }

    /// `Ok` when `min <= value <= max`; NaN is refused.
    pub fn check(&self, value: f64) -> Result<(), RaimError> {
        if self.contains(value) {
            Ok(())
        } else {
            Err(RaimError::OutOfRange {
                field: self.field,
                value,
                min: self.min,
                max: self.max,
            })
        }
    }
}

/// False alarm per sample. Below 1e-9 the threshold grows without an
/// operational reason (DO-229 and ARAIM allocations are 1e-7..1e-5 per
/// sample) until detection is in effect off; above 1e-2 one epoch in a
/// hundred alarms, and the unit is not usable (the seeds' largest value).
pub const PFA: Bound = Bound {
    field: "pfa",
    min: 1e-9,
    max: 1e-2,
};
/// Missed detection for the protection levels. Above 1e-2 the PLs no longer
/// bound the error at any integrity level in use (DO-229: 1e-3); below 1e-9
/// lambda_md is meaningless next to the other risks.
pub const PMD: Bound = Bound {
    field: "pmd",
    min: 1e-9,
    max: 1e-2,
};
/// Probability of wrong exclusion the uniqueness check allows (docs/CORE.md
/// §FDE 3). A larger value accepts exclusions the data cannot tell apart.
pub const PWE: Bound = Bound {
    field: "pwe",
    min: 1e-9,
    max: 1e-2,
};
/// kappa = tau^2 / sigma^2 of the L-RAIM Gaussian prior (SPEC §4.2): from a
/// prior bias of 0.03 sigma (the rule is then in effect MLE on S_ii) to 10^6
/// sigma (the flat rule).
pub const KAPPA: Bound = Bound {
    field: "kappa",
    min: 1e-3,
    max: 1e12,
};
/// Horizontal alert limit, m: from the smallest HAL of any phase (APV-I and
/// LPV-200, 40 m) to the largest (oceanic en route, 4 nm = 7408 m).
pub const HAL_M: Bound = Bound {
    field: "hal_m",
    min: 40.0,
    max: 7408.0,
};
/// Vertical alert limit, m: from 10 m (the tightest VAL in use, CAT I) to
/// 50 m (LPV and APV-I). `None` means the vertical is not monitored.
pub const VAL_M: Bound = Bound {
    field: "val_m",
    min: 10.0,
    max: 50.0,
};
/// Smallest S_ii at which a satellite is identifiable (SPEC §4.2). A larger
/// value only makes more satellites unidentifiable (an alarm, never a pass).
pub const MIN_S_II: Bound = Bound {
    field: "min_s_ii",
    min: 1e-9,
    max: 0.5,
};
/// Gauss-Newton step tolerance, m: it must stay far below the smallest
/// sigma (0.36 m at zenith with the floors below) so that the statistic is
/// not computed at a position the solver had not reached.
pub const CONVERGENCE_M: Bound = Bound {
    field: "convergence_m",
    min: 1e-9,
    max: 0.1,
};
/// Gauss-Newton iteration cap (from the Earth's centre it takes ~6).
pub const MAX_ITERATIONS: Bound = Bound {
    field: "max_iterations",
    min: 1.0,
    max: 100.0,
};
/// Exclusions per epoch: 0 (detection only, every failure is an alarm) up
/// to what FDE implements.
pub const MAX_EXCLUSIONS_BOUND: Bound = Bound {
    field: "max_exclusions",
    min: 0.0,
    max: MAX_EXCLUSIONS as f64,
};
/// Signal-in-space sigma, m. Floor 0.3 m: about half of today's GPS
/// broadcast SIS URE RMS, and the smallest value the monitor was validated
/// with (the geodetic fit of docs/REPLAY.md); a smaller URA makes every
/// protection level optimistic. Above 100 m a satellite is unusable.
pub const URA_M: Bound = Bound {
    field: "ura_m",
    min: 0.3,
    max: 100.0,
};
/// Vertical ionosphere residual, m. 0 is allowed: dual-frequency iono-free
/// ranges have no iono residual (their amplified noise goes in `noise_m`);
/// the URA and noise floors and the fixed tropo (0.12 m) and multipath
/// (>= 0.13 m) terms keep every modelled sigma >= 0.36 m. Up to 30 m (a
/// severe storm's vertical delay).
pub const IONO_VERTICAL_M: Bound = Bound {
    field: "iono_vertical_m",
    min: 0.0,
    max: 30.0,
};
/// Receiver noise sigma, m. Floor 0.1 m: below DO-229D's best airborne
/// class (AAD-B, 0.15 m). Up to 10 m.
pub const NOISE_M: Bound = Bound {
    field: "noise_m",
    min: 0.1,
    max: 10.0,
};
/// Lowest elevation at which the sigma model is evaluated, rad (0..10 deg).
/// A higher value would give low satellites the smaller sigma of a higher
/// one (at 10 deg the tropo term is already 3x smaller than at 2 deg).
pub const MIN_ELEVATION_RAD: Bound = Bound {
    field: "min_elevation_rad",
    min: 0.0,
    max: 10.0 * core::f64::consts::PI / 180.0,
};
/// A per-satellite ranging sigma given with an observation, m (the
/// `sigma_m` of `RangeObservation` and `LinearObservation`, and the PF's
/// and ARAIM's host sigmas). Floor 0.3 m: the elevation model's floor
/// (0.36 m with every term at its bound, test
/// `sigma_floors_keep_the_modelled_sigma_above_0_36_m`) rounded down; a
/// smaller host sigma claims an accuracy no model here supports and
/// shrinks every protection level with it. Ceiling 150 m: above the
/// model's largest sigma (every term at its ceiling, at the horizon:
/// 138 m, test `sigma_bound_brackets_the_elevation_model`); a larger
/// sigma gives the satellite no weight, silently removing it from the
/// solution while it still counts in the degrees of freedom.
pub const SIGMA_M: Bound = Bound {
    field: "sigma_m",
    min: 0.3,
    max: 150.0,
};

/// How long an MCUSUM exclusion is held, s (up to ~3 h).
pub const HOLD_S: Bound = Bound {
    field: "hold_s",
    min: 0.0,
    max: 1e4,
};

/// Correlation time of the MCUSUM's Gauss-Markov error model, s (0 = white
/// noise, up to one hour). Longer than an hour, the error is a bias over
/// any flight phase and the weight 1 / sqrt(I) (I ~ 2 tau / dt) leaves the
/// MCUSUM nothing to accumulate: a sigma model that overbounds the bias is
/// then the remedy, not a longer tau.
pub const CORRELATION_TIME_S: Bound = Bound {
    field: "correlation_time_s",
    min: 0.0,
    max: 3600.0,
};

/// Simultaneous faults the reconstruction FDE searches for (SPEC §8; the
/// covering designs exist for t = 1..3).
pub const T_MAX: Bound = Bound {
    field: "t_max",
    min: 1.0,
    max: crate::multifault::covering::MAX_FAULTS as f64,
};
/// `t_max` in a build without the reconstruction FDE (raim-core's feature
/// `multifault` off): no simultaneous faults may be searched for, so any
/// `FdeMethod::Reconstruction` is refused with this bound instead of
/// falling back to the sequential FDE.
pub const T_MAX_NOT_BUILT: Bound = Bound {
    field: "t_max",
    min: 0.0,
    max: 0.0,
};
/// Constraint groups the reconstruction FDE may solve per epoch: at least
/// one (0 would switch the multi-fault search off).
pub const GROUP_BUDGET: Bound = Bound {
    field: "group_budget",
    min: 1.0,
    max: u16::MAX as f64,
};

/// Check every field of `cfg`; the first offending one is returned.
pub fn check(cfg: &Config) -> Result<(), RaimError> {
    PFA.check(cfg.pfa)?;
    PMD.check(cfg.pmd)?;
    PWE.check(cfg.pwe)?;
    if let FiRule::LraimGaussian { kappa } = cfg.rule {
        KAPPA.check(kappa)?;
    }
    HAL_M.check(cfg.alert.hal_m)?;
    if let Some(v) = cfg.alert.val_m {
        VAL_M.check(v)?;
    }
    MIN_S_II.check(cfg.min_s_ii)?;
    CONVERGENCE_M.check(cfg.convergence_m)?;
    MAX_ITERATIONS.check(f64::from(cfg.max_iterations))?;
    MAX_EXCLUSIONS_BOUND.check(f64::from(cfg.max_exclusions))?;
    let s = &cfg.sigma_model;
    URA_M.check(s.ura_m)?;
    IONO_VERTICAL_M.check(s.iono_vertical_m)?;
    NOISE_M.check(s.noise_m)?;
    MIN_ELEVATION_RAD.check(s.min_elevation_rad)?;
    // Checked whether the MCUSUM runs or not: a disabled part is still
    // part of the configuration the fingerprint covers, and enabling it
    // later must not bring unchecked values into force.
    crate::sequential::mcusum::check_settings(cfg.mcusum.k, cfg.mcusum.arl0)?;
    HOLD_S.check(cfg.mcusum.hold_s)?;
    CORRELATION_TIME_S.check(cfg.mcusum.correlation_time_s)?;
    if let FdeMethod::Reconstruction {
        t_max,
        group_budget,
    } = cfg.fde_method
    {
        if !cfg!(feature = "multifault") {
            T_MAX_NOT_BUILT.check(f64::from(t_max))?;
        }
        T_MAX.check(f64::from(t_max))?;
        GROUP_BUDGET.check(f64::from(group_budget))?;
    }
    Ok(())
}

pub mod araim;
pub mod pf;

#[cfg(test)]
mod tests;
