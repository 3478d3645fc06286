//! The state and measurement model shared by the three filters (seed 004
//! eqs. 7-8, SPEC §1 and §10).
//!
//! State (offsets from an `f64` [`Reference`] held by the monitor):
//! `[dx, dy, dz, b_G, b_R, b_E, b_C, b_J, d]`: ECEF position offset (m),
//! one clock bias per constellation (m) and one clock drift (m/s, the
//! receiver has one oscillator). Keeping the state small offsets lets it be
//! `T = f32` (SPEC §1, `real.rs`).
//!
//! Measurement: the range to satellite k from `r0 + dx` is expanded to
//! second order about the reference, `|s - r0 - dx| = R0 - u.dx +
//! (|dx|^2 - (u.dx)^2) / (2 R0) + O(|dx|^3 / R0^2)`: the big terms (`R0`,
//! the clock reference) are subtracted in `f64` once per epoch
//! ([`SatTerm::z0`]) and only metre-sized numbers reach `T`. The neglected
//! term is below 1e-5 m for |dx| < 10 km (R0 > 2e7 m); the monitor
//! recentres the reference on the estimate every epoch.

use crate::measurement::{SatId, MAX_SYSTEMS};
use crate::real::Real;

use super::config::{Likelihood, PfConfig};
use super::rng::PfRng;

/// State dimension: 3 position + one clock per constellation + drift.
pub const DIM: usize = 3 + MAX_SYSTEMS + 1;
/// Index of the first clock state.
pub const CLOCK0: usize = 3;
/// Index of the clock-drift state.
pub const DRIFT: usize = 3 + MAX_SYSTEMS;

/// The `f64` point the filter states are offsets from.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Reference {
    /// Receiver ECEF position, m.
    pub position_m: [f64; 3],
    /// Clock bias per constellation (System::index), m.
    pub clock_m: [f64; MAX_SYSTEMS],
    /// Receiver clock drift (one oscillator), m/s; the clock references
    /// advance by it each epoch so that the state holds only the offset.
    pub drift_m_s: f64,
}

impl Reference {
    /// The origin with zero clocks (the derived `Default`, as a constant).
    pub const ZERO: Self = Reference {
        position_m: [0.0; 3],
        clock_m: [0.0; MAX_SYSTEMS],
        drift_m_s: 0.0,
    };
}

/// One satellite's measurement, reduced against the reference.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SatTerm<T> {
    /// The satellite.
    pub id: SatId,
    /// Constellation index (the clock state used).
    pub sys: usize,
    /// Unit line of sight receiver -> satellite at the reference, ECEF.
    pub los: [T; 3],
    /// 1 / R0, 1/m.
    pub inv_range: T,
    /// rho - R0 - clock reference, m (computed in f64).
    pub z0: T,
    /// Ranging sigma, m.
    pub sigma: T,
    /// ln sigma.
    pub ln_sigma: T,
}

impl<T: Real> SatTerm<T> {
    /// Reduces one observation against the reference (all in f64, then
    /// rounded to `T`).
    pub fn new(
        id: SatId,
        pseudorange_m: f64,
        sat_m: &[f64; 3],
        sigma_m: f64,
        r: &Reference,
    ) -> Self {
        let d = [
            sat_m[0] - r.position_m[0],
            sat_m[1] - r.position_m[1],
            sat_m[2] - r.position_m[2],
        ];
        let range = libm::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        let sys = id.system.index();
        // System::index() < MAX_SYSTEMS (its match over System::ALL).
        #[allow(clippy::indexing_slicing)]
        let clock = r.clock_m[sys];
        SatTerm {
            id,
            sys,
            los: [
                T::of(d[0] / range),
                T::of(d[1] / range),
                T::of(d[2] / range),
            ],
            inv_range: T::of(1.0 / range),
            z0: T::of(pseudorange_m - range - clock),
            sigma: T::of(sigma_m),
            ln_sigma: T::of(libm::log(sigma_m)),
        }
    }

    /// The predicted measurement offset h(x) for a state offset x.
    #[inline]
    pub fn predict(&self, x: &[T; DIM]) -> T {
        let [ux, uy, uz] = self.los;
        let [dx, dy, dz] = [x[0], x[1], x[2]];
        let ud = ux * dx + uy * dy + uz * dz;
        let dd = dx * dx + dy * dy + dz * dz;
        let half = T::of(0.5);
        let clock = x.get(CLOCK0 + self.sys).copied().unwrap_or_else(T::zero);
        -ud + half * (dd - ud * ud) * self.inv_range + clock
    }

    /// The residual z - h(x), m.
    #[inline]
    pub fn residual(&self, x: &[T; DIM]) -> T {
        self.z0 - self.predict(x)
    }

    /// The Jacobian row dh/dx at x (for the EKF).
    pub fn jacobian(&self, x: &[T; DIM]) -> [T; DIM] {
        let [ux, uy, uz] = self.los;
        let ud = ux * x[0] + uy * x[1] + uz * x[2];
        let mut h = [T::zero(); DIM];
        h[0] = -ux + (x[0] - ud * ux) * self.inv_range;
        h[1] = -uy + (x[1] - ud * uy) * self.inv_range;
        h[2] = -uz + (x[2] - ud * uz) * self.inv_range;
        if let Some(c) = h.get_mut(CLOCK0 + self.sys) {
            *c = T::one();
        }
        h
    }
}

/// The measurement log-density in `T`, with its constants precomputed in
/// `f64` once per configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lik<T> {
    kind: LikKind,
    /// -0.5 ln(2 pi).
    c_gauss: T,
    /// Student-t: ln G((nu+1)/2) - ln G(nu/2) - 0.5 ln(nu pi).
    c_t: T,
    nu: T,
    half_nu1: T,
    /// Mixture: ln(1 - eps), ln eps - ln k, 1/k^2.
    ln_core: T,
    ln_tail: T,
    inv_k2: T,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum LikKind {
    Gaussian,
    StudentT,
    Mixture,
}

impl<T: Real> Lik<T> {
    /// The law of `cfg.likelihood`.
    pub fn new(cfg: &PfConfig) -> Self {
        Self::of(&cfg.likelihood)
    }

    /// The Gaussian law with the variance of `cfg.likelihood` (the EKF's).
    pub fn gaussian() -> Self {
        Self::of(&Likelihood::Gaussian)
    }

    fn of(l: &Likelihood) -> Self {
        let c_gauss = -0.5 * libm::log(2.0 * core::f64::consts::PI);
        let mut s = Lik {
            kind: LikKind::Gaussian,
            c_gauss: T::of(c_gauss),
            c_t: T::zero(),
            nu: T::one(),
            half_nu1: T::one(),
            ln_core: T::zero(),
            ln_tail: T::zero(),
            inv_k2: T::one(),
        };
        match *l {
            Likelihood::Gaussian => {}
            Likelihood::StudentT { nu } => {
                s.kind = LikKind::StudentT;
                s.c_t = T::of(
                    libm::lgamma(0.5 * (nu + 1.0))
                        - libm::lgamma(0.5 * nu)
                        - 0.5 * libm::log(nu * core::f64::consts::PI),
                );
                s.nu = T::of(nu);
                s.half_nu1 = T::of(0.5 * (nu + 1.0));
            }
            Likelihood::Mixture {
                outlier_prob,
                outlier_scale,
            } => {
                s.kind = LikKind::Mixture;
                s.ln_core = T::of(libm::log(1.0 - outlier_prob));
                s.ln_tail = T::of(libm::log(outlier_prob) - libm::log(outlier_scale));
                s.inv_k2 = T::of(1.0 / (outlier_scale * outlier_scale));
            }
        }
        s
    }

    /// ln p(r) for a residual r with the satellite's sigma.
    #[inline]
    pub fn ln_density(&self, r: T, t: &SatTerm<T>) -> T {
        let u = r / t.sigma;
        let u2 = u * u;
        let half = T::of(0.5);
        match self.kind {
            LikKind::Gaussian => self.c_gauss - half * u2 - t.ln_sigma,
            LikKind::StudentT => {
                self.c_t - t.ln_sigma - self.half_nu1 * (T::one() + u2 / self.nu).ln_m()
            }
            LikKind::Mixture => {
                let a = self.ln_core - half * u2;
                let b = self.ln_tail - half * u2 * self.inv_k2;
                let (hi, lo) = if a > b { (a, b) } else { (b, a) };
                self.c_gauss - t.ln_sigma + hi + (lo - hi).exp_m().ln_1p_m()
            }
        }
    }
}

/// What one filter update reports.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Step {
    /// ln p(y_k | Y_{k-1}) over the satellites the filter uses (seed 004
    /// eqs. 11-12, before the weights are normalised).
    pub ln_predictive: f64,
    /// Effective sample size of the weights used for resampling (seed 004
    /// eq. 16): after the genetic step for the GA-PF; the EKF reports 0.
    pub n_eff: f64,
    /// Effective sample size of the likelihood weights before the genetic
    /// step (equal to `n_eff` for the SIR filter; 0 for the EKF). The GA
    /// step replaces accepted particles' weights by their (higher)
    /// likelihoods, so `n_eff` rises partly by construction; this one does
    /// not.
    pub n_eff_before_ga: f64,
    /// The update failed (non-finite or hopeless likelihood): the filter
    /// must be reinitialised and its output discarded.
    pub collapsed: bool,
}

/// A recursive estimator the FDI structure runs as main and auxiliary
/// filters: the EKF, the SIR particle filter and the GA-PF.
pub trait Estimator<T: Real>: Sized {
    /// The method's name for reports ("ekf", "pf", "gapf").
    const KIND: &'static str;
    /// Particles per filter (0 for the EKF): with `KIND`, the row of the
    /// calibrated threshold table.
    const PARTICLES: usize;
    /// An empty filter, all zero (call [`Estimator::init`] before use). A
    /// constant, so that an engine can be built at compile time in a
    /// static ([`super::PfRaim::EMPTY`]).
    const BLANK: Self;
    /// Draws the prior about the zero offset (seed 004 step 1).
    fn init(&mut self, cfg: &PfConfig, rng: &mut PfRng);
    /// Becomes a copy of `other`.
    fn copy_from(&mut self, other: &Self);
    /// Propagates over `dt_s` seconds with the process model (eq. 7).
    fn predict(&mut self, cfg: &PfConfig, dt_s: f64, rng: &mut PfRng);
    /// Updates with the satellites in `terms`, leaving out index `skip`.
    fn update(
        &mut self,
        cfg: &PfConfig,
        terms: &[SatTerm<T>],
        skip: Option<usize>,
        rng: &mut PfRng,
    ) -> Step;
    /// The state estimate (mean).
    fn mean(&self) -> [T; DIM];
    /// Adds `delta` to every state (recentring; the law is unchanged).
    fn shift(&mut self, delta: &[T; DIM]);
}

/// Process noise per state for an interval dt: the standard deviations.
pub fn process_sigmas(cfg: &PfConfig, dt_s: f64) -> [f64; DIM] {
    let s = libm::sqrt(dt_s.max(0.0));
    let mut q = [0.0; DIM];
    for (i, v) in q.iter_mut().enumerate() {
        *v = if i < CLOCK0 {
            cfg.process.position_m_per_sqrt_s * s
        } else if i < DRIFT {
            cfg.process.clock_m_per_sqrt_s * s
        } else {
            cfg.process.drift_m_s_per_sqrt_s * s
        };
    }
    q
}

/// Initial standard deviations per state.
pub fn init_sigmas(cfg: &PfConfig) -> [f64; DIM] {
    let mut q = [0.0; DIM];
    for (i, v) in q.iter_mut().enumerate() {
        *v = if i < CLOCK0 {
            cfg.init_position_m
        } else if i < DRIFT {
            cfg.init_clock_m
        } else {
            cfg.init_drift_m_s
        };
    }
    q
}

/// Online log-sum-exp: keeps (max, sum of exp(v - max)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogSumExp<T> {
    max: T,
    sum: T,
    any: bool,
}

impl<T: Real> Default for LogSumExp<T> {
    fn default() -> Self {
        LogSumExp {
            max: T::zero(),
            sum: T::zero(),
            any: false,
        }
    }
}

impl<T: Real> LogSumExp<T> {
    /// Adds exp(v). A NaN poisons the result.
    #[inline]
    pub fn push(&mut self, v: T) {
        if !self.any {
            self.max = v;
            self.sum = T::one();
            self.any = true;
        } else if v > self.max {
            self.sum = self.sum * (self.max - v).exp_m() + T::one();
            self.max = v;
        } else if v.is_finite() || v < self.max {
            self.sum += (v - self.max).exp_m();
        } else {
            // NaN: propagate.
            self.max = v;
        }
    }

    /// ln(sum exp(v)) in f64; -inf when empty.
    pub fn value(&self) -> f64 {
        if !self.any {
            return f64::NEG_INFINITY;
        }
        self.max.to_f64() + libm::log(self.sum.to_f64())
    }
}
