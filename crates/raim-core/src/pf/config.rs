//! Configuration of the particle-filter RAIM: process model, measurement
//! likelihood, genetic operators and the LLR test (SPEC §10, seed 004).

use super::error::PfError;

/// The measurement noise law used to weight particles (seed 004 eq. 1's
/// p(z|x)), per satellite with scale `sigma_m`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Likelihood {
    /// N(0, sigma^2).
    Gaussian,
    /// Student-t with `nu` degrees of freedom and scale sigma (nu > 2 so
    /// the EKF baseline has a variance to use).
    StudentT {
        /// Degrees of freedom nu (> 2).
        nu: f64,
    },
    /// (1 - eps) N(0, sigma^2) + eps N(0, (k sigma)^2): a Gaussian core
    /// with an outlier component, `outlier_prob` = eps, `outlier_scale` = k.
    Mixture {
        /// eps, the outlier component's weight (a probability).
        outlier_prob: f64,
        /// k, the outlier sigma over the core sigma (dimensionless).
        outlier_scale: f64,
    },
}

impl Likelihood {
    /// The variance of the law in units of sigma^2: what the EKF baseline
    /// (Gaussian by construction) uses in place of the true law.
    pub fn variance_factor(&self) -> f64 {
        match *self {
            Likelihood::Gaussian => 1.0,
            Likelihood::StudentT { nu } => nu / (nu - 2.0),
            Likelihood::Mixture {
                outlier_prob,
                outlier_scale,
            } => (1.0 - outlier_prob) + outlier_prob * outlier_scale * outlier_scale,
        }
    }
}

/// Random-walk process model (seed 004 eq. 7 with F the identity on the
/// position and the clock integrating the drift): the noise densities,
/// scaled by sqrt(dt) each epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ProcessModel {
    /// Position random walk per axis, m / sqrt(s).
    pub position_m_per_sqrt_s: f64,
    /// Clock-bias random walk (each constellation), m / sqrt(s).
    pub clock_m_per_sqrt_s: f64,
    /// Clock-drift random walk, (m/s) / sqrt(s).
    pub drift_m_s_per_sqrt_s: f64,
}

/// Everything the `pf` monitor needs besides the measurements.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PfConfig {
    /// The state's process noise.
    pub process: ProcessModel,
    /// The measurement likelihood.
    pub likelihood: Likelihood,
    /// Ranging sigma when an observation carries none, m.
    pub sigma_m: f64,
    /// Initial spread of the position about the first fix, per axis, m.
    pub init_position_m: f64,
    /// Initial spread of each clock bias, m.
    pub init_clock_m: f64,
    /// Initial spread of the clock drift, m/s.
    pub init_drift_m_s: f64,
    /// GA-PF mutation step (seed 004 step 4b), position and clock, m.
    pub mutation_m: f64,
    /// Window U of the decision function (seed 004 eq. 13), epochs
    /// (1..=[`MAX_WINDOW`]).
    pub window: usize,
    /// False-alarm probability per epoch allocated to this monitor: the
    /// decision threshold lambda of eq. 13 is looked up in the calibrated
    /// table for the filter, particle count, window, likelihood and model
    /// profile (`pf::threshold`, docs/PF.md "Thresholds"), never set by hand.
    pub pfa: f64,
    /// Exclude the isolated satellite and restart the filters from its
    /// auxiliary filter (seed 004 step 7).
    pub exclude: bool,
    /// An excluded satellite is readmitted after this many seconds (its
    /// auxiliary filter restarts from the main one); 0 excludes for good.
    pub readmit_s: f64,
    /// A common-mode residual of one constellation larger than this (m) is
    /// taken as a receiver clock jump and moves that clock's reference
    /// (docs/PF.md, "clock jumps"); 0 disables.
    pub clock_jump_m: f64,
    /// A filter whose best particle explains the epoch worse than this
    /// RMS normalised residual (in sigmas) is collapsed and reinitialised.
    pub collapse_sigma: f64,
}

/// The longest decision window the monitor stores.
pub const MAX_WINDOW: usize = 64;

impl Default for PfConfig {
    fn default() -> Self {
        PfConfig {
            process: ProcessModel {
                position_m_per_sqrt_s: 1.0,
                clock_m_per_sqrt_s: 1.0,
                drift_m_s_per_sqrt_s: 0.1,
            },
            likelihood: Likelihood::Gaussian,
            sigma_m: 3.0,
            init_position_m: 10.0,
            init_clock_m: 10.0,
            init_drift_m_s: 1.0,
            mutation_m: 0.5,
            window: 8,
            pfa: 1e-3,
            exclude: true,
            readmit_s: 0.0,
            clock_jump_m: 1000.0,
            collapse_sigma: 100.0,
        }
    }
}

impl PfConfig {
    /// Checks every field against its operational bound
    /// (`config_bounds::pf`, docs/PROTOCOL.md "Configuration bounds"; the
    /// threshold's bound depends on the law and the window); the first
    /// offender is reported as `PfError::OutOfRange`.
    pub fn validate(&self) -> Result<(), PfError> {
        crate::config_bounds::pf::check(self)
    }
}
