//! The particle filters: plain SIR (seed 004's "PF" baseline) and the
//! genetic-resampling GA-PF (seed 004 §2, SPEC §10), on a fixed array of
//! `P` particles with no heap.
//!
//! Per epoch (after [`Estimator::predict`] moved every particle through
//! the process model, seed 004 step 5):
//! 1. weights w_i = p(z | x_i) (eq. 1 with the prior as proposal; the
//!    weights are uniform after last epoch's resampling), kept as logs so
//!    nothing underflows; ln p(z | Z_{k-1}) = ln mean_i p(z | x_i)
//!    (eqs. 11-12) is reported for the LLR;
//! 2. GA-PF only: the weight of rank round(N/3) splits low from high
//!    (eqs. 3-4); on the low set, floor(N_L/2) crossovers of random pairs
//!    (eqs. 5-6) and one mutation per low particle, each candidate accepted
//!    by a Metropolis test on the likelihood; merge (in place);
//! 3. normalise (eq. 2), N_eff = 1 / sum w_i^2 (eq. 16), the estimate
//!    sum w_i x_i, then systematic resampling in place.

use crate::real::Real;

use super::config::PfConfig;
use super::model::{init_sigmas, process_sigmas, Estimator, Lik, LogSumExp, SatTerm, Step, DIM};
use super::resample::{apply_counts, crossover, metropolis, rank_threshold, systematic_counts};
use super::rng::{self, PfRng};

/// The most satellites one particle update handles.
pub const MAX_PF_SATS: usize = 32;

/// A particle filter with `P` particles of state `[T; DIM]`. `GA = true`
/// is the GA-PF, `false` the plain SIR filter.
#[derive(Debug, Clone)]
pub struct ParticleFilter<T, const P: usize, const GA: bool> {
    particles: [[T; DIM]; P],
    /// ln p(z | x_i) of the last update, then the normalised weights.
    work: [T; P],
    estimate: [T; DIM],
}

/// Seed 004's plain particle filter (sequential importance resampling).
pub type SirPf<T, const P: usize> = ParticleFilter<T, P, false>;
/// Seed 004's genetic-algorithm-aided particle filter.
pub type GaPf<T, const P: usize> = ParticleFilter<T, P, true>;

/// ln p(z | x) over `terms` except `skip`.
fn ln_lik<T: Real>(lik: &Lik<T>, terms: &[SatTerm<T>], skip: Option<usize>, x: &[T; DIM]) -> T {
    let mut l = T::zero();
    for (k, t) in terms.iter().enumerate() {
        if Some(k) != skip {
            l += lik.ln_density(t.residual(x), t);
        }
    }
    l
}

/// N_eff = (sum w)^2 / sum w^2 of the weights exp(l_i - max), computed in
/// f64 from log-weights whose maximum is `max` (seed 004 eq. 16).
fn n_eff_of_log_weights<T: Real>(log_w: &[T], max: T) -> f64 {
    let mut s1 = 0.0f64;
    let mut s2 = 0.0f64;
    let m = max.to_f64();
    for &l in log_w {
        let w = libm::exp(l.to_f64() - m);
        s1 += w;
        s2 += w * w;
    }
    if s2 > 0.0 {
        s1 * s1 / s2
    } else {
        0.0
    }
}

impl<T: Real, const P: usize, const GA: bool> ParticleFilter<T, P, GA> {
    /// The particles (for tests and memory accounting).
    pub fn particles(&self) -> &[[T; DIM]; P] {
        &self.particles
    }

    /// Bytes of state one filter holds.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    /// The genetic step on the low-weight set (`work` holds ln p(z|x)).
    fn genetic(
        &mut self,
        cfg: &PfConfig,
        lik: &Lik<T>,
        terms: &[SatTerm<T>],
        skip: Option<usize>,
        rng: &mut PfRng,
    ) {
        let thr = rank_threshold(&self.work);
        let mut low = [0u16; P];
        let mut n_low = 0usize;
        for (i, &l) in self.work.iter().enumerate() {
            if l < thr {
                if let Some(s) = low.get_mut(n_low) {
                    *s = i as u16;
                    n_low += 1;
                }
            }
        }
        // n_low <= P: it counts only the successful stores above.
        let low = low.get(..n_low).unwrap_or(&[]);
        // Crossover: floor(N_L / 2) random pairs (eqs. 5-6), each child
        // accepted against the better parent.
        for _ in 0..n_low / 2 {
            // rng::index(_, n) < n for n >= 1, and here n_low >= 2.
            let (Some(&m), Some(&n)) = (
                low.get(rng::index(rng, n_low)),
                low.get(rng::index(rng, n_low)),
            ) else {
                continue;
            };
            let (m, n) = (m as usize, n as usize);
            let a = T::of(rng::uniform(rng));
            let (Some(&xm), Some(&xn)) = (self.particles.get(m), self.particles.get(n)) else {
                continue;
            };
            let (Some(&lm), Some(&ln)) = (self.work.get(m), self.work.get(n)) else {
                continue;
            };
            let best = if lm > ln { lm } else { ln };
            let (cm, cn) = crossover(&xm, &xn, a);
            let lcm = ln_lik(lik, terms, skip, &cm);
            let lcn = ln_lik(lik, terms, skip, &cn);
            if metropolis(lcm, best, rng) {
                if let (Some(p), Some(w)) = (self.particles.get_mut(m), self.work.get_mut(m)) {
                    *p = cm;
                    *w = lcm;
                }
            }
            if metropolis(lcn, best, rng) {
                if let (Some(p), Some(w)) = (self.particles.get_mut(n), self.work.get_mut(n)) {
                    *p = cn;
                    *w = lcn;
                }
            }
        }
        // Mutation: one Gaussian step per low particle on position and
        // clocks (seed 004 step 4b), accepted against the particle itself.
        let s = cfg.mutation_m;
        for &j in low {
            let j = j as usize;
            let (Some(&xj), Some(&lj)) = (self.particles.get(j), self.work.get(j)) else {
                continue;
            };
            let mut c = xj;
            for (i, v) in c.iter_mut().enumerate() {
                let d = rng::normal(rng);
                if i < super::model::DRIFT {
                    *v += T::of(s * d);
                }
            }
            let lc = ln_lik(lik, terms, skip, &c);
            if metropolis(lc, lj, rng) {
                if let (Some(p), Some(w)) = (self.particles.get_mut(j), self.work.get_mut(j)) {
                    *p = c;
                    *w = lc;
                }
            }
        }
    }
}

impl<T: Real, const P: usize, const GA: bool> Estimator<T> for ParticleFilter<T, P, GA> {
    const KIND: &'static str = if GA { "gapf" } else { "pf" };
    const PARTICLES: usize = P;

    const BLANK: Self = ParticleFilter {
        particles: [[T::ZERO; DIM]; P],
        work: [T::ZERO; P],
        estimate: [T::ZERO; DIM],
    };

    fn init(&mut self, cfg: &PfConfig, rng: &mut PfRng) {
        let s = init_sigmas(cfg);
        for p in self.particles.iter_mut() {
            for (v, &si) in p.iter_mut().zip(s.iter()) {
                *v = T::of(si * rng::normal(rng));
            }
        }
        self.estimate = [T::zero(); DIM];
    }

    fn copy_from(&mut self, other: &Self) {
        self.particles = other.particles;
        self.estimate = other.estimate;
    }

    fn predict(&mut self, cfg: &PfConfig, dt_s: f64, rng: &mut PfRng) {
        let q = process_sigmas(cfg, dt_s);
        let dt = T::of(dt_s);
        for p in self.particles.iter_mut() {
            let drift = p[super::model::DRIFT];
            for (i, (v, &qi)) in p.iter_mut().zip(q.iter()).enumerate() {
                if (super::model::CLOCK0..super::model::DRIFT).contains(&i) {
                    *v += drift * dt;
                }
                *v += T::of(qi * rng::normal(rng));
            }
        }
    }

    fn update(
        &mut self,
        cfg: &PfConfig,
        terms: &[SatTerm<T>],
        skip: Option<usize>,
        rng: &mut PfRng,
    ) -> Step {
        let lik = Lik::<T>::new(cfg);
        let n_terms = terms.len().min(MAX_PF_SATS);
        #[allow(clippy::indexing_slicing)] // n_terms <= terms.len()
        let terms = &terms[..n_terms];
        let used = n_terms - usize::from(skip.is_some_and(|s| s < n_terms));
        let mut total = LogSumExp::<T>::default();
        // 1. likelihoods and the predictive density.
        for (p, w) in self.particles.iter().zip(self.work.iter_mut()) {
            let l = ln_lik(&lik, terms, skip, p);
            *w = l;
            total.push(l);
        }
        let ln_n = libm::log(P as f64);
        let ln_pred = total.value() - ln_n;
        let best = self
            .work
            .iter()
            .fold(T::min_value().unwrap_or_else(T::zero), |m, &v| {
                if v > m {
                    v
                } else {
                    m
                }
            });
        let floor = -0.5 * cfg.collapse_sigma * cfg.collapse_sigma * used.max(1) as f64;
        let any_nan = self.work.iter().any(|v| v.partial_cmp(v).is_none());
        if any_nan || !ln_pred.is_finite() || !(best.to_f64() > floor) {
            return Step {
                ln_predictive: ln_pred,
                n_eff: 0.0,
                n_eff_before_ga: 0.0,
                collapsed: true,
            };
        }
        // N_eff of the likelihood weights before the genetic step (eq. 16).
        let n_eff_before_ga = n_eff_of_log_weights(&self.work, best);
        // 2. genetic operators on the low-weight set.
        if GA {
            self.genetic(cfg, &lik, terms, skip, rng);
        }
        // 3. normalise, N_eff, estimate, resample.
        let mut m = T::min_value().unwrap_or_else(T::zero);
        for &v in self.work.iter() {
            if v > m {
                m = v;
            }
        }
        let mut sum = T::zero();
        for v in self.work.iter_mut() {
            *v = (*v - m).exp_m();
            sum += *v;
        }
        let mut sum2 = T::zero();
        let mut est = [T::zero(); DIM];
        for (v, p) in self.work.iter_mut().zip(self.particles.iter()) {
            *v /= sum;
            sum2 += *v * *v;
            for (e, &x) in est.iter_mut().zip(p.iter()) {
                *e += *v * x;
            }
        }
        self.estimate = est;
        let mut counts = [0u16; P];
        systematic_counts(&self.work, rng::uniform(rng), &mut counts);
        apply_counts(&mut self.particles, &counts);
        Step {
            ln_predictive: ln_pred,
            n_eff: 1.0 / sum2.to_f64(),
            n_eff_before_ga,
            collapsed: false,
        }
    }

    fn mean(&self) -> [T; DIM] {
        self.estimate
    }

    fn shift(&mut self, delta: &[T; DIM]) {
        for p in self.particles.iter_mut() {
            for (v, &d) in p.iter_mut().zip(delta.iter()) {
                *v += d;
            }
        }
        for (v, &d) in self.estimate.iter_mut().zip(delta.iter()) {
            *v += d;
        }
    }
}

#[cfg(test)]
#[path = "particle_cov_tests.rs"]
mod particle_cov_tests;
