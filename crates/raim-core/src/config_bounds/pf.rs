//! Operational bounds of the particle-filter RAIM configuration (SPEC §10,
//! docs/PF.md; docs/PROTOCOL.md "Configuration bounds").
//!
//! `PfConfig::validate` checks every field (NaN and infinities refused,
//! bounds inclusive); a rejection is `PfError::OutOfRange` with the field,
//! the value and the bound.
//!
//! # The decision threshold
//!
//! The threshold lambda is compared with the windowed accumulated LLR
//! (seed 004 eq. 13). It is not configured: it is looked up in the
//! calibrated table at the allocated `pfa` (`pf::threshold`), whose bound
//! is the snapshot monitor's (`super::PFA`, 1e-9..1e-2). The looked-up
//! threshold is then checked against [`threshold_bound`]. Its scale: in
//! an ideal filter (the main filter predicts y_q exactly), a bias of
//! delta sigmas on satellite q adds to that satellite's LLR, per epoch
//! (docs/PF.md "the LLR"),
//!
//! ```text
//! s(delta) = -ln f(delta) - ln sqrt(2 pi e v),
//! ```
//!
//! with f the configured law at unit scale and v its variance factor:
//! (delta^2 - 1) / 2 for the Gaussian, only logarithmic in delta for the
//! Student-t. Over the window U the statistic reaches at most about
//! U s(delta). A threshold above U s(DETECT_SIGMA) cannot be reached by a
//! DETECT_SIGMA fault even in the ideal filter held for the whole window:
//! detection of the faults the snapshot monitor must detect is then
//! impossible, so it is refused. DETECT_SIGMA is the bias the snapshot
//! monitor's most lenient accepted allocation needs (Pfa = Pmd = 1e-9, the
//! floors of `PFA` and `PMD`, one degree of freedom: 12.107 sigma, SPEC
//! §6), rounded up. For the default (Gaussian, U = 10) the ceiling is
//! 728 nats; with the Student-t of 3 dof, 68.5.
//!
//! The floor: the ideal filter's per-epoch LLR is at least -1/2 (Gaussian,
//! delta = 0), so any threshold below -1/2 alarms at every epoch; real
//! filters' prediction terms move the statistic (docs/PF.md's calibrated
//! EKF threshold is -0.21), so the floor is -MAX_WINDOW = -64 nats: the low
//! side costs continuity, never integrity, and is bounded only to keep
//! the field finite.

use super::Bound;
use crate::pf::config::{Likelihood, PfConfig, MAX_WINDOW};
use crate::pf::error::PfError;

impl Bound {
    /// `check` for the PF configuration: `PfError::OutOfRange`.
    pub fn check_pf(&self, value: f64) -> Result<(), PfError> {
        if self.contains(value) {
            Ok(())
        } else {
            Err(PfError::OutOfRange {
                field: self.field,
                value,
                min: self.min,
                max: self.max,
            })
        }
    }
}

/// The fault size (sigmas) a PF threshold must leave detectable (module
/// doc): sqrt(lambda_md) at Pfa = Pmd = 1e-9, 1 dof, is 12.107.
pub const DETECT_SIGMA: f64 = 12.11;

/// Process noise densities: position and clock random walks, m / sqrt(s)
/// (0 is a static receiver or a perfect clock; 1000 m / sqrt(s) is far
/// beyond any aircraft, whose speed is 250 m/s), drift, (m/s) / sqrt(s).
pub const POSITION_M_PER_SQRT_S: Bound = Bound {
    field: "process.position_m_per_sqrt_s",
    min: 0.0,
    max: 1e3,
};
/// The clock process noise, m/sqrt(s).
pub const CLOCK_M_PER_SQRT_S: Bound = Bound {
    field: "process.clock_m_per_sqrt_s",
    min: 0.0,
    max: 1e3,
};
/// The clock drift process noise, (m/s)/sqrt(s).
pub const DRIFT_M_S_PER_SQRT_S: Bound = Bound {
    field: "process.drift_m_s_per_sqrt_s",
    min: 0.0,
    max: 100.0,
};
/// The ranging sigma used when an observation carries none: the
/// per-satellite sigma's bound (`super::SIGMA_M`).
pub const SIGMA_M: Bound = Bound {
    field: "sigma_m",
    ..super::SIGMA_M
};
/// Initial spreads about the first least-squares fix: position and clock,
/// m (1 mm to 100 km), drift, m/s.
pub const INIT_POSITION_M: Bound = Bound {
    field: "init_position_m",
    min: 1e-3,
    max: 1e5,
};
/// The initial clock spread, m.
pub const INIT_CLOCK_M: Bound = Bound {
    field: "init_clock_m",
    min: 1e-3,
    max: 1e5,
};
/// The initial drift spread, m/s.
pub const INIT_DRIFT_M_S: Bound = Bound {
    field: "init_drift_m_s",
    min: 1e-3,
    max: 1e4,
};
/// GA-PF mutation step, m (0: no mutation).
pub const MUTATION_M: Bound = Bound {
    field: "mutation_m",
    min: 0.0,
    max: 1e3,
};
/// False-alarm probability per epoch allocated to the PF monitor: the
/// snapshot monitor's bound (`super::PFA`).
pub const PFA: Bound = Bound {
    field: "pfa",
    ..super::PFA
};
/// Decision window U, epochs.
pub const WINDOW: Bound = Bound {
    field: "window",
    min: 1.0,
    max: MAX_WINDOW as f64,
};
/// Readmission delay, s (0 excludes for good; up to a day).
pub const READMIT_S: Bound = Bound {
    field: "readmit_s",
    min: 0.0,
    max: 86_400.0,
};
/// Clock-jump detector, m (0 disables; 3e5 m is a 1 ms steering step).
pub const CLOCK_JUMP_M: Bound = Bound {
    field: "clock_jump_m",
    min: 0.0,
    max: 3e5,
};
/// Collapse test, RMS normalised residual in sigmas: below 1 a filter
/// collapses on noise; above 1e4 it never does.
pub const COLLAPSE_SIGMA: Bound = Bound {
    field: "collapse_sigma",
    min: 1.0,
    max: 1e4,
};
/// Student-t degrees of freedom: nu > 2 for a variance (2.5 gives the EKF
/// baseline 5 sigma^2); 1000 is the Gaussian in all but name.
pub const NU: Bound = Bound {
    field: "likelihood.nu",
    min: 2.5,
    max: 1e3,
};
/// Mixture outlier probability: above one half the "outlier" is the core.
pub const OUTLIER_PROB: Bound = Bound {
    field: "likelihood.outlier_prob",
    min: 1e-6,
    max: 0.5,
};
/// Mixture outlier scale k (the outlier sigma in core sigmas).
pub const OUTLIER_SCALE: Bound = Bound {
    field: "likelihood.outlier_scale",
    min: 1.0,
    max: 100.0,
};

/// -ln of the configured law's density at `delta` (unit scale).
fn neg_ln_density(law: &Likelihood, delta: f64) -> f64 {
    const LN_SQRT_2PI: f64 = 0.918_938_533_204_672_8;
    match *law {
        Likelihood::Gaussian => 0.5 * delta * delta + LN_SQRT_2PI,
        Likelihood::StudentT { nu } => {
            let c = libm::lgamma(0.5 * (nu + 1.0))
                - libm::lgamma(0.5 * nu)
                - 0.5 * libm::log(nu * core::f64::consts::PI);
            0.5 * (nu + 1.0) * libm::log1p(delta * delta / nu) - c
        }
        Likelihood::Mixture {
            outlier_prob: e,
            outlier_scale: k,
        } => {
            let core_ = (1.0 - e) * libm::exp(-0.5 * delta * delta);
            let outlier = e / k * libm::exp(-0.5 * delta * delta / (k * k));
            LN_SQRT_2PI - libm::log(core_ + outlier)
        }
    }
}

/// s(delta): the ideal filter's per-epoch LLR for a delta-sigma bias
/// (module doc).
pub fn llr_per_epoch(law: &Likelihood, delta: f64) -> f64 {
    let v = law.variance_factor();
    neg_ln_density(law, delta)
        - 0.5 * libm::log(2.0 * core::f64::consts::PI * core::f64::consts::E * v)
}

/// The threshold's bound for a law and window (module doc):
/// [-MAX_WINDOW, U s(DETECT_SIGMA)].
pub fn threshold_bound(law: &Likelihood, window: usize) -> Bound {
    Bound {
        field: "threshold",
        min: -(MAX_WINDOW as f64),
        max: window as f64 * llr_per_epoch(law, DETECT_SIGMA),
    }
}

/// Every field of `cfg` against its bound; the first offender is returned.
/// The threshold is not a field: [`threshold_bound`] checks the calibrated
/// one (`PfRaim::process`).
pub fn check(cfg: &PfConfig) -> Result<(), PfError> {
    let p = &cfg.process;
    POSITION_M_PER_SQRT_S.check_pf(p.position_m_per_sqrt_s)?;
    CLOCK_M_PER_SQRT_S.check_pf(p.clock_m_per_sqrt_s)?;
    DRIFT_M_S_PER_SQRT_S.check_pf(p.drift_m_s_per_sqrt_s)?;
    SIGMA_M.check_pf(cfg.sigma_m)?;
    INIT_POSITION_M.check_pf(cfg.init_position_m)?;
    INIT_CLOCK_M.check_pf(cfg.init_clock_m)?;
    INIT_DRIFT_M_S.check_pf(cfg.init_drift_m_s)?;
    MUTATION_M.check_pf(cfg.mutation_m)?;
    WINDOW.check_pf(cfg.window as f64)?;
    PFA.check_pf(cfg.pfa)?;
    READMIT_S.check_pf(cfg.readmit_s)?;
    CLOCK_JUMP_M.check_pf(cfg.clock_jump_m)?;
    COLLAPSE_SIGMA.check_pf(cfg.collapse_sigma)?;
    match cfg.likelihood {
        Likelihood::Gaussian => {}
        Likelihood::StudentT { nu } => NU.check_pf(nu)?,
        Likelihood::Mixture {
            outlier_prob,
            outlier_scale,
        } => {
            OUTLIER_PROB.check_pf(outlier_prob)?;
            OUTLIER_SCALE.check_pf(outlier_scale)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
