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
    LraimGaussian { kappa: f64 },
}

impl Default for FiRule {
    fn default() -> Self {
        FiRule::LraimGaussian { kappa: DEFAULT_KAPPA }
    }
}

/// Horizontal and vertical alert limits; `None` means "not monitored".
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct AlertLimits {
    pub hal_m: f64,
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
    pub const fn alert_limits(self) -> AlertLimits {
        match self {
            Phase::EnRoute => AlertLimits { hal_m: 3704.0, val_m: None },
            Phase::Terminal => AlertLimits { hal_m: 1852.0, val_m: None },
            Phase::Npa => AlertLimits { hal_m: 556.0, val_m: None },
        }
    }

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
    pub rule: FiRule,
    pub alert: AlertLimits,
    pub sigma_model: SigmaModel,
    /// Most satellites FDE may exclude in one epoch (SPEC §5).
    pub max_exclusions: u8,
    /// Satellites with S_ii below this are "unidentifiable" (SPEC §4.2).
    pub min_s_ii: f64,
    /// Refuse an exclusion when excluding the runner-up candidate would
    /// also give a consistent subset: the fault cannot be told apart, and an
    /// avionics monitor alarms rather than guess (docs/CORE.md).
    pub require_unique_exclusion: bool,
    /// Gauss-Newton stops when the position step is below this, m.
    pub convergence_m: f64,
    /// Gauss-Newton iteration cap.
    pub max_iterations: u32,
}

impl Default for Config {
    fn default() -> Self {
        Config::preset(Phase::Npa)
    }
}

impl Config {
    /// A configuration for a flight phase: Pfa 3.3333e-7 per sample
    /// (1e-5 / h over ~30 independent samples), Pmd 1e-3.
    pub fn preset(phase: Phase) -> Self {
        Config {
            pfa: 3.3333e-7,
            pmd: 1e-3,
            rule: FiRule::default(),
            alert: phase.alert_limits(),
            sigma_model: SigmaModel::default(),
            max_exclusions: 2,
            min_s_ii: DEFAULT_MIN_S_II,
            require_unique_exclusion: true,
            convergence_m: 1e-4,
            max_iterations: 20,
        }
    }

    /// Check every field's range; returns the first offending one.
    pub fn validate(&self) -> Result<(), RaimError> {
        let prob = |field: &'static str, v: f64| {
            if v > 0.0 && v < 0.5 {
                Ok(())
            } else {
                Err(RaimError::OutOfRange { field, value: v, min: 0.0, max: 0.5 })
            }
        };
        prob("pfa", self.pfa)?;
        prob("pmd", self.pmd)?;
        let positive = |field: &'static str, v: f64, max: f64| {
            if v > 0.0 && v <= max {
                Ok(())
            } else {
                Err(RaimError::OutOfRange { field, value: v, min: 0.0, max })
            }
        };
        if let FiRule::LraimGaussian { kappa } = self.rule {
            positive("kappa", kappa, 1e12)?;
        }
        positive("hal_m", self.alert.hal_m, 1e7)?;
        if let Some(v) = self.alert.val_m {
            positive("val_m", v, 1e7)?;
        }
        positive("min_s_ii", self.min_s_ii, 0.5)?;
        positive("convergence_m", self.convergence_m, 1e3)?;
        let s = &self.sigma_model;
        let non_negative = |field: &'static str, v: f64| {
            if (0.0..=1e4).contains(&v) {
                Ok(())
            } else {
                Err(RaimError::OutOfRange { field, value: v, min: 0.0, max: 1e4 })
            }
        };
        non_negative("ura_m", s.ura_m)?;
        non_negative("iono_vertical_m", s.iono_vertical_m)?;
        non_negative("noise_m", s.noise_m)?;
        non_negative("min_elevation_rad", s.min_elevation_rad)?;
        if self.max_iterations == 0 || self.max_iterations > 100 {
            return Err(RaimError::OutOfRange {
                field: "max_iterations",
                value: self.max_iterations as f64,
                min: 1.0,
                max: 100.0,
            });
        }
        Ok(())
    }
}
