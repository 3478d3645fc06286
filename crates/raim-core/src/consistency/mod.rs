//! Model checking at run time (issue 35, docs/MODEL_CHECK.md): does the
//! error model the unit was given (the snapshot monitor's sigma model, or
//! ARAIM's accuracy model C_acc from the ISM's sigma_URE) describe the
//! errors it actually sees?
//!
//! No integrity monitor can bound an error its error model denies: with
//! 1 m of noise against an ISM at its floors (sigma_URA 0.3 m, sigma_URE
//! 0.2 m) ARAIM's FDE can exclude the wrong satellites and report a
//! protection level below the error. What the unit can do is notice that
//! its model is wrong. Under the model, the normalised residuals of each
//! answered epoch give
//!
//! ```text
//! q = r^T W r ~ chi2(n - m),    r = (I - G (G^T W G)^-1 G^T W) y,
//! ```
//!
//! W the model's weights (SPEC §2-3: the snapshot test's D^2 with the
//! sigma model; for ARAIM W = C_acc^-1, [`fit::accuracy_fit`]). A model
//! that understates the errors by a factor k inflates q by k^2 on every
//! epoch, whatever the satellite; one epoch of it may pass, a window of
//! them does not.
//!
//! [`ModelCheck`] keeps a sliding window of samples (q, dof):
//!
//! - **Spacing.** An epoch becomes a sample only when at least
//!   [`ModelCheckConfig::spacing_s`] has passed since the last sample, so
//!   that samples are nearer to independent (the measured correlation
//!   time of the real parity vectors, docs/ESQ.md "mcusum-rho"; the
//!   default's derivation is at [`DEFAULT_SPACING_S`]). The epochs between
//!   are skipped, not stored.
//! - **Window.** The last [`ModelCheckConfig::window`] samples (at most
//!   the capacity `W`).
//! - **Test.** At every sample, the chi-square goodness of fit of the
//!   window: p = P(chi2(sum dof) > sum q), computed as the regularised
//!   upper incomplete gamma Q(sum dof / 2, sum q / 2)
//!   ([`crate::stats::dist::gamma_q`]). Under the model and independence
//!   p is uniform; the model is declared broken when p < p_eval (or p is
//!   NaN: fail safe). The window is tested from its first sample, so a
//!   gross model error is found at the first sample and a slight one
//!   accumulates over up to W samples.
//! - **Allocation** ([`ModelCheckConfig::p_fa_per_evaluation`]): the user
//!   allocates a false-alarm probability per hour of operation, P_h. An
//!   hour holds at most n_h = floor(3600 / spacing_s) + 1 samples, each
//!   one evaluation, so each evaluation gets p_eval = P_h / n_h and by the
//!   union bound the probability of a false declaration in any hour is at
//!   most P_h, whatever the overlap of consecutive windows. Nothing is
//!   fitted to the data that judge it.
//! - **Latch.** A broken model stays declared until [`ModelCheck::reset`]
//!   (the caller puts a new model in force): a window sliding past the
//!   evidence does not make the model right again. The caller maps
//!   [`ModelCheck::broken`] to the alarm output asserted.
//!
//! What feeds it: one sample per *answered* epoch, the solution actually
//! delivered (all in view, or the subset after an exclusion; an epoch
//! answered `Unavailable` still has its solution), never an `Alarm` epoch
//! (the alarm is asserted already, and a fault is not a model error):
//! [`crate::result::EpochResult::model_sample`] for the snapshot monitor,
//! [`crate::araim::Monitor::accuracy_sample`] for ARAIM.
//!
//! Time comes in as an argument (sans-IO) and must increase strictly from
//! offer to offer; a refused offer leaves the state as it was. Nothing is
//! allocated; the capacity `W` is a const generic.

use crate::stats::dist::{gamma_q, MAX_DOF};

pub mod fit;
#[cfg(test)]
mod tests;

/// Default spacing between samples, s: 1,800 s. The parity vector's
/// measured correlation time (docs/ESQ.md, table "mcusum-rho", the
/// first lag with rho < 1/e, per-satellite mean removed) is 1,530 s on
/// ESBC and 510 s on 0759 (30 s data), 1 s on GEOP; the raw vector, its
/// per-satellite bias included, stays correlated beyond the 1,800 s
/// examined. The default is the longest measured value rounded up to
/// the longest lag examined: samples at least as far apart as every
/// measured correlation time (the bias part is not decorrelated by any
/// spacing; docs/MODEL_CHECK.md says what that means for the allocation).
pub const DEFAULT_SPACING_S: f64 = 1800.0;
/// Default window, samples: 8 (3.5 hours from first to last sample at the
/// default spacing). The smallest window whose full test detects, with
/// probability at least [`DESIGN_POWER`], a model that understates every
/// sigma by half (errors twice the model: q scaled by 4) with 4 dof per
/// sample (an 8-satellite single-constellation sky) at the default
/// spacing and allocation: P(4 chi2(4 W) > T^2(p_eval, 4 W)) is 0.845 at
/// W = 7 and 0.904 at W = 8 (test `default_window_has_the_design_power`).
/// A gross understatement (5x, the red-team case) is found at the first
/// sample.
pub const DEFAULT_WINDOW: usize = 8;
/// The power the default window is designed for (above).
pub const DESIGN_POWER: f64 = 0.9;
/// Default allocation: 1e-6 false declarations per hour, a tenth of the
/// 1e-5 per hour continuity budget the snapshot test's default Pfa comes
/// from (SPEC §3; `budget::DEFAULT_P_FA_TOTAL` = 1e-5 / h over 30 samples).
pub const DEFAULT_P_FA_PER_HOUR: f64 = 1e-6;
/// Seconds in an hour, the unit of the allocation.
pub const HOUR_S: f64 = 3600.0;
/// Bounds of the spacing, s: from 1 ms (faster than any receiver) to a
/// day.
pub const SPACING_S: (f64, f64) = (1e-3, 86_400.0);
/// Bounds of the hourly allocation: [1e-12, 0.5].
pub const P_FA_PER_HOUR: (f64, f64) = (1e-12, 0.5);

/// Why an input or configuration was refused. Every variant carries the
/// offending value.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModelCheckError {
    /// A NaN (or, where noted, infinite) value.
    NotFinite {
        /// The field.
        field: &'static str,
        /// The value received.
        value: f64,
    },
    /// A value outside its bounds.
    OutOfRange {
        /// The field.
        field: &'static str,
        /// The value received.
        value: f64,
        /// Smallest accepted value.
        min: f64,
        /// Largest accepted value.
        max: f64,
    },
    /// A window of 0 samples or larger than the capacity `W`.
    WindowOutOfRange {
        /// The window asked for.
        window: usize,
        /// The capacity `W`.
        capacity: usize,
    },
    /// A sample with 0 degrees of freedom (no redundancy: nothing to test).
    ZeroDof,
    /// A sample with more degrees of freedom than a statistic can have.
    DofOutOfRange {
        /// The dof received.
        dof: u32,
        /// The largest accepted ([`MAX_DOF`]).
        max: u32,
    },
    /// The time does not follow the last offer's (strictly); the state is
    /// left as it was.
    TimeNotIncreasing {
        /// The time received, s.
        time_s: f64,
        /// The last offer's time, s.
        last_s: f64,
    },
    /// The geometry of a fit has no redundancy or is singular.
    Geometry {
        /// Satellites.
        n: usize,
        /// Unknowns.
        m: usize,
    },
}

/// The configuration: spacing, window and allocation.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModelCheckConfig {
    /// Least time between two samples, s ([`DEFAULT_SPACING_S`]).
    pub spacing_s: f64,
    /// Samples in the window, 1..=W ([`DEFAULT_WINDOW`]).
    pub window: usize,
    /// Allocated probability of a false declaration per hour of operation
    /// ([`DEFAULT_P_FA_PER_HOUR`]).
    pub p_fa_per_hour: f64,
}

impl Default for ModelCheckConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl ModelCheckConfig {
    /// The defaults above.
    pub const DEFAULT: Self = ModelCheckConfig {
        spacing_s: DEFAULT_SPACING_S,
        window: DEFAULT_WINDOW,
        p_fa_per_hour: DEFAULT_P_FA_PER_HOUR,
    };

    /// Checks every field against its bounds, for a capacity `capacity`.
    ///
    /// # Errors
    /// `NotFinite`, `OutOfRange` or `WindowOutOfRange` naming the field.
    pub fn validate(&self, capacity: usize) -> Result<(), ModelCheckError> {
        bounded("spacing_s", self.spacing_s, SPACING_S)?;
        bounded("p_fa_per_hour", self.p_fa_per_hour, P_FA_PER_HOUR)?;
        if self.window == 0 || self.window > capacity {
            return Err(ModelCheckError::WindowOutOfRange {
                window: self.window,
                capacity,
            });
        }
        Ok(())
    }

    /// The most evaluations any hour can hold: floor(3600 / spacing) + 1
    /// (samples at least `spacing_s` apart in a closed hour).
    pub fn evaluations_per_hour(&self) -> f64 {
        libm::floor(HOUR_S / self.spacing_s) + 1.0
    }

    /// The false-alarm probability of one evaluation: the hourly
    /// allocation divided over the evaluations an hour can hold.
    pub fn p_fa_per_evaluation(&self) -> f64 {
        self.p_fa_per_hour / self.evaluations_per_hour()
    }
}

fn bounded(field: &'static str, value: f64, (min, max): (f64, f64)) -> Result<(), ModelCheckError> {
    if value.is_nan() {
        return Err(ModelCheckError::NotFinite { field, value });
    }
    if !(min..=max).contains(&value) {
        return Err(ModelCheckError::OutOfRange {
            field,
            value,
            min,
            max,
        });
    }
    Ok(())
}

/// One sample of the window: q and its dof at a time.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sample {
    /// The epoch's time, s.
    pub time_s: f64,
    /// q = r^T W r of the solution delivered (dimensionless).
    pub q: f64,
    /// Its degrees of freedom, n - m.
    pub dof: u32,
}

/// The test of one window.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Evaluation {
    /// Samples in the window (1..=window).
    pub samples: usize,
    /// Sum of q over the window.
    pub q_sum: f64,
    /// Sum of the dof over the window.
    pub dof_sum: u32,
    /// P(chi2(dof_sum) > q_sum).
    pub p_value: f64,
    /// The per-evaluation false-alarm probability it is held against.
    pub p_fa: f64,
    /// This window rejects the model (p < p_fa, or p NaN).
    pub rejects: bool,
}

/// What an offer did.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Offer {
    /// Closer than `spacing_s` to the last sample: not taken.
    Skipped,
    /// Taken into the window, and the window tested.
    Evaluated(Evaluation),
}

/// The model-consistency monitor with a window capacity of `W` samples
/// (module doc).
#[derive(Debug, Clone)]
pub struct ModelCheck<const W: usize> {
    /// Ring buffer of the window's samples.
    ring: [Sample; W],
    /// Index of the oldest sample.
    head: usize,
    /// Samples held.
    len: usize,
    /// Time of the last offer (taken or skipped), s.
    last_offer_s: Option<f64>,
    /// Time of the last sample taken, s.
    last_sample_s: Option<f64>,
    /// Evaluations made since the last reset.
    evaluations: u64,
    /// Evaluations that rejected since the last reset.
    rejections: u64,
    /// The latch: the first rejecting evaluation's time, s.
    broken_at_s: Option<f64>,
}

impl<const W: usize> Default for ModelCheck<W> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const W: usize> ModelCheck<W> {
    /// An empty monitor (`const`: a device builds it in a static).
    pub const fn new() -> Self {
        ModelCheck {
            ring: [Sample {
                time_s: 0.0,
                q: 0.0,
                dof: 0,
            }; W],
            head: 0,
            len: 0,
            last_offer_s: None,
            last_sample_s: None,
            evaluations: 0,
            rejections: 0,
            broken_at_s: None,
        }
    }

    /// Forget everything, the latch included: a new model is in force.
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// The model was declared broken (latched until [`Self::reset`]); the
    /// caller asserts the alarm output.
    pub fn broken(&self) -> bool {
        self.broken_at_s.is_some()
    }

    /// The time of the first rejection since the last reset, s.
    pub fn broken_at_s(&self) -> Option<f64> {
        self.broken_at_s
    }

    /// Evaluations made since the last reset.
    pub fn evaluations(&self) -> u64 {
        self.evaluations
    }

    /// Evaluations that rejected the model since the last reset.
    pub fn rejections(&self) -> u64 {
        self.rejections
    }

    /// The window's samples, oldest first.
    pub fn samples(&self) -> impl Iterator<Item = &Sample> + '_ {
        (0..self.len).filter_map(move |k| self.ring.get((self.head + k) % W.max(1)))
    }

    /// Offer one answered epoch's (q, dof) at `time_s`.
    ///
    /// # Errors
    /// A bad configuration ([`ModelCheckConfig::validate`]); `time_s` NaN
    /// or infinite, or not after the last offer (`TimeNotIncreasing`);
    /// `q` NaN (`NotFinite`) or negative (`OutOfRange`; +infinity is taken:
    /// it rejects); `dof` 0 or above [`MAX_DOF`]. Nothing changes on an
    /// error.
    pub fn offer(
        &mut self,
        cfg: &ModelCheckConfig,
        time_s: f64,
        q: f64,
        dof: u32,
    ) -> Result<Offer, ModelCheckError> {
        cfg.validate(W)?;
        if !time_s.is_finite() {
            return Err(ModelCheckError::NotFinite {
                field: "time_s",
                value: time_s,
            });
        }
        if let Some(last_s) = self.last_offer_s {
            if !(time_s > last_s) {
                return Err(ModelCheckError::TimeNotIncreasing { time_s, last_s });
            }
        }
        if q.is_nan() {
            return Err(ModelCheckError::NotFinite {
                field: "q",
                value: q,
            });
        }
        if q < 0.0 {
            return Err(ModelCheckError::OutOfRange {
                field: "q",
                value: q,
                min: 0.0,
                max: f64::INFINITY,
            });
        }
        if dof == 0 {
            return Err(ModelCheckError::ZeroDof);
        }
        if dof > MAX_DOF {
            return Err(ModelCheckError::DofOutOfRange { dof, max: MAX_DOF });
        }
        self.last_offer_s = Some(time_s);
        if let Some(t) = self.last_sample_s {
            if time_s - t < cfg.spacing_s {
                return Ok(Offer::Skipped);
            }
        }
        self.push(cfg.window, Sample { time_s, q, dof });
        self.last_sample_s = Some(time_s);
        let e = self.evaluate(cfg);
        self.evaluations = self.evaluations.saturating_add(1);
        if e.rejects {
            self.rejections = self.rejections.saturating_add(1);
            if self.broken_at_s.is_none() {
                self.broken_at_s = Some(time_s);
            }
        }
        Ok(Offer::Evaluated(e))
    }

    /// Appends a sample, dropping the oldest ones beyond `window`.
    fn push(&mut self, window: usize, s: Sample) {
        let cap = W.max(1);
        while self.len >= window.min(W) && self.len > 0 {
            self.head = (self.head + 1) % cap;
            self.len -= 1;
        }
        if let Some(slot) = self.ring.get_mut((self.head + self.len) % cap) {
            *slot = s;
            self.len += 1;
        }
    }

    /// The goodness-of-fit test of the window as it stands.
    fn evaluate(&self, cfg: &ModelCheckConfig) -> Evaluation {
        let (mut q_sum, mut dof_sum, mut samples) = (0.0f64, 0u32, 0usize);
        for s in self.samples() {
            q_sum += s.q;
            dof_sum = dof_sum.saturating_add(s.dof);
            samples += 1;
        }
        let p_value = gamma_q(0.5 * f64::from(dof_sum), 0.5 * q_sum);
        let p_fa = cfg.p_fa_per_evaluation();
        Evaluation {
            samples,
            q_sum,
            dof_sum,
            p_value,
            p_fa,
            // NaN rejects (fail safe).
            rejects: !(p_value >= p_fa),
        }
    }
}
