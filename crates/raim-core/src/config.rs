//! Configuration: false-alarm and missed-detection budgets, the fault
//! identification rule, alert limits, the sigma model. Passed by reference
//! to every call (sans-IO: no global state).

use crate::error::RaimError;
use crate::sigma::SigmaModel;

/// Default prior variance ratio kappa = tau^2 / sigma^2 of the Gaussian
/// bias prior of L-RAIM (SPEC §4.2). 100 means a fault bias of ~10 sigma is
/// typical: the size where identification starts to matter for a protection
/// level at Pfa 3.3e-7 / Pmd 1e-3 (pbias ~ 8-10 sigma, SPEC §6).
pub const DEFAULT_KAPPA: f64 = 100.0;

/// Default smallest S_ii at which a satellite is identifiable (SPEC §4.2).
/// Below it a bias changes the parity vector by less than 1 % of its size in
/// the measurement and the normalised residual is not meaningful.
pub const DEFAULT_MIN_S_II: f64 = 1e-4;

/// How the MCUSUM state crosses a change of the satellite set (SPEC §7.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Carry {
    /// Carry the state through measurement space, indexed by satellite:
    /// v = U2_old S_old, mapped to the new list (0 for newcomers), then
    /// S_new = U2_new^T v.
    #[default]
    Transport,
    /// Restart the state at 0 whenever the satellite set changes (kept for
    /// comparison; while the set is unchanged the state is transported,
    /// since the parity basis rotates as the satellites move).
    Reset,
}

/// Default MCUSUM reference value k, in sigma units: half the parity-space
/// shift the test is tuned to, here 2 sigma (seed 001 Table 2 uses k = 1).
pub const DEFAULT_MCUSUM_K: f64 = 1.0;

/// Default share of the per-epoch false-alarm budget given to the snapshot
/// test when the MCUSUM runs beside it (SPEC §7.4): an even split.
pub const DEFAULT_SNAPSHOT_SHARE: f64 = 0.5;

/// Default time an MCUSUM exclusion is held, s (10 minutes): long enough for
/// a persistent fault not to be re-admitted at once, short enough that a
/// satellite that recovered comes back. A satellite that leaves view is
/// released at once.
pub const DEFAULT_MCUSUM_HOLD_S: f64 = 600.0;

/// Sequential detection settings (SPEC §7, docs/CORE.md "MCUSUM").
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct McusumConfig {
    /// Run the MCUSUM beside the snapshot test. Off by default: with it
    /// off, every result is exactly the snapshot monitor's.
    pub enabled: bool,
    /// Reference value k (sigma units); one of `mcusum::K_VALUES`.
    pub k: f64,
    /// In-control average run length of the MCUSUM alone, epochs. The
    /// threshold h comes from the device table for the current dimension.
    pub arl0: f64,
    /// What the MCUSUM state does when the satellite set changes.
    pub carry: Carry,
    /// How long a satellite excluded after an MCUSUM alarm stays excluded, s.
    pub hold_s: f64,
    /// Correlation time tau of the first-order Gauss-Markov error model the
    /// MCUSUM whitens against, s; 0 (the default) is white noise, the
    /// assumption of the ARL0 table. With tau > 0 each epoch's parity
    /// vector is weighted by 1 / sqrt(I) before it enters the recursion,
    /// I = (1 + rho) / (1 - rho), rho = exp(-dt / tau), dt the interval
    /// since the previous epoch (`mcusum::variance_inflation`): the
    /// variance of a sum of n weighted samples is then at most n, that of
    /// the white unit-variance samples the threshold h was computed for.
    /// Bounds: `config_bounds::CORRELATION_TIME_S`.
    pub correlation_time_s: f64,
}

impl Default for McusumConfig {
    fn default() -> Self {
        // Disabled; the ARL0 is the MCUSUM half of the default budget
        // (Pfa 3.3333e-7 per epoch split evenly: 1 / 1.66667e-7 = 6e6).
        McusumConfig {
            enabled: false,
            k: DEFAULT_MCUSUM_K,
            arl0: 6.0e6,
            carry: Carry::Transport,
            hold_s: DEFAULT_MCUSUM_HOLD_S,
            correlation_time_s: 0.0,
        }
    }
}

/// The fault identification rule (SPEC §4).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum FiRule {
    /// argmax w_i^2 (normalised residual, seed 000 eqs. 8-9).
    Mle,
    /// argmax w_i^2 - ln S_ii: L-RAIM with a flat bias prior.
    LraimFlat,
    /// argmax w_i^2 kappa S_ii / (1 + kappa S_ii) - ln(1 + kappa S_ii).
    LraimGaussian {
        /// The prior bias-to-noise variance ratio kappa (dimensionless).
        kappa: f64,
    },
}

impl Default for FiRule {
    fn default() -> Self {
        FiRule::LraimGaussian {
            kappa: DEFAULT_KAPPA,
        }
    }
}

/// The fault detection and exclusion method of the snapshot monitor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum FdeMethod {
    /// Single exclusion by the identification rule, repeated, with the
    /// closed-form pair search and the uniqueness check (SPEC §5).
    #[default]
    Sequential,
    /// Error reconstruction over constraint groups (SPEC §8, seed 002): the
    /// fewest satellites (1..t_max, at most 3 and at most
    /// `max_exclusions`) whose exclusion explains the residuals, searching
    /// at most `group_budget` groups per epoch (docs/MULTIFAULT.md).
    Reconstruction {
        /// Largest fault count searched (1..=3).
        t_max: u8,
        /// Constraint groups searched per epoch at most.
        group_budget: u16,
    },
}

/// Horizontal and vertical alert limits; `None` means "not monitored".
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct AlertLimits {
    /// Horizontal alert limit HAL, m.
    pub hal_m: f64,
    /// Vertical alert limit VAL, m (`None`: no vertical requirement).
    pub val_m: Option<f64>,
}

/// Flight phase presets (SPEC §6, secondary sources).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Phase {
    /// HAL 2 nm = 3704 m, time to alert 30 s.
    EnRoute,
    /// HAL 1 nm = 1852 m, time to alert 15 s.
    Terminal,
    /// Non-precision approach: HAL 0.3 nm = 556 m, time to alert 10 s.
    Npa,
}

impl Phase {
    /// The alert limits of the flight phase (SPEC §6).
    pub const fn alert_limits(self) -> AlertLimits {
        match self {
            Phase::EnRoute => AlertLimits {
                hal_m: 3704.0,
                val_m: None,
            },
            Phase::Terminal => AlertLimits {
                hal_m: 1852.0,
                val_m: None,
            },
            Phase::Npa => AlertLimits {
                hal_m: 556.0,
                val_m: None,
            },
        }
    }

    /// The time to alert of the flight phase, s.
    pub const fn time_to_alert_s(self) -> f64 {
        match self {
            Phase::EnRoute => 30.0,
            Phase::Terminal => 15.0,
            Phase::Npa => 10.0,
        }
    }
}

/// Everything an epoch needs besides its measurements.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Config {
    /// Probability of false alarm per sample (SPEC §3). Default 3.3333e-7.
    pub pfa: f64,
    /// Probability of missed detection for protection levels (SPEC §6).
    pub pmd: f64,
    /// The identification rule (MLE or L-RAIM).
    pub rule: FiRule,
    /// The alert limits the protection levels are held to.
    pub alert: AlertLimits,
    /// How each satellite's sigma is formed.
    pub sigma_model: SigmaModel,
    /// Most satellites FDE may exclude in one epoch (SPEC §5).
    pub max_exclusions: u8,
    /// Satellites with S_ii below this are "unidentifiable" (SPEC §4.2).
    pub min_s_ii: f64,
    /// Refuse an exclusion when excluding the runner-up candidate would
    /// also give a consistent subset: the fault cannot be told apart, and an
    /// avionics monitor alarms rather than guess (docs/CORE.md).
    pub require_unique_exclusion: bool,
    /// Probability of wrong exclusion that the uniqueness check allows: an
    /// exclusion stands only if every other single-satellite explanation is
    /// rejected, i.e. its subset statistic D^2 - w_j^2 reaches the
    /// chi-square quantile at 1 - pwe with dof - 1 (docs/CORE.md); the
    /// multiple-fault search applies the same level to every other set
    /// (SPEC §8.4). Its share of the conditional integrity budget
    /// (`crate::budget::Budget::pwe`, docs/BUDGET.md). Default 1e-3.
    pub pwe: f64,
    /// Gauss-Newton stops when the position step is below this, m.
    pub convergence_m: f64,
    /// Gauss-Newton iteration cap.
    pub max_iterations: u32,
    /// Sequential detection (MCUSUM, SPEC §7); disabled by default.
    pub mcusum: McusumConfig,
    /// The FDE method; `Sequential` (today's) by default.
    pub fde_method: FdeMethod,
}

impl Default for Config {
    fn default() -> Self {
        Config::preset(Phase::Npa)
    }
}

impl Config {
    /// A configuration for a flight phase, from the default budget
    /// (`crate::budget`, docs/BUDGET.md): Pfa 3.3333e-7 per sample
    /// (1e-5 / h over ~30 independent samples), all of it to the snapshot
    /// test; the conditional integrity budget under a fault, 2e-3, split
    /// into Pmd 1e-3 (protection levels) and pwe 1e-3 (uniqueness checks).
    pub fn preset(phase: Phase) -> Self {
        use crate::budget::{
            DEFAULT_P_FA_TOTAL, DEFAULT_P_MD_TOTAL, DEFAULT_WRONG_EXCLUSION_SHARE,
        };
        Config {
            pfa: DEFAULT_P_FA_TOTAL,
            pmd: DEFAULT_P_MD_TOTAL * (1.0 - DEFAULT_WRONG_EXCLUSION_SHARE),
            rule: FiRule::default(),
            alert: phase.alert_limits(),
            sigma_model: SigmaModel::default(),
            max_exclusions: 2,
            min_s_ii: DEFAULT_MIN_S_II,
            require_unique_exclusion: true,
            pwe: DEFAULT_P_MD_TOTAL * DEFAULT_WRONG_EXCLUSION_SHARE,
            convergence_m: 1e-4,
            max_iterations: 20,
            mcusum: McusumConfig::default(),
            fde_method: FdeMethod::Sequential,
        }
    }

    /// Enable the MCUSUM and split the false-alarm budget (SPEC §7.4): the
    /// current `pfa` is taken as the total per-epoch budget 1 / ARL0; the
    /// snapshot test gets `snapshot_share` of it and the MCUSUM the rest,
    /// so 1 / ARL0_combined ~ pfa_snapshot + 1 / ARL0_mcusum = the total.
    pub fn split_false_alarm_budget(mut self, snapshot_share: f64) -> Self {
        let total = self.pfa;
        self.pfa = total * snapshot_share;
        self.mcusum.enabled = true;
        self.mcusum.arl0 = 1.0 / (total * (1.0 - snapshot_share));
        self
    }

    /// Check every field against its operational bound
    /// (`config_bounds`, docs/PROTOCOL.md "Configuration bounds"); returns
    /// the first offending field as `OutOfRange`.
    pub fn validate(&self) -> Result<(), RaimError> {
        crate::config_bounds::check(self)
    }
}

#[cfg(test)]
#[path = "config_cov_tests.rs"]
mod cov_tests;
