//! Fault identification (SPEC §4): the MLE baseline (seed 000 eqs. 8-9) and
//! the leveraged L-RAIM rule (SPEC §4.2), which integrates the likelihood of
//! each fault mode over the unknown bias instead of plugging in its maximum.

use crate::config::FiRule;
use crate::linalg::parity::Parity;
use crate::real::Real;

/// The per-satellite identification quantities, in sigma units, in the
/// precision `T` of the parity space they come from.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Candidate<T: Real = f64> {
    /// Row in the model.
    pub row: usize,
    /// Normalised residual w_i = r_i / sqrt(S_ii) (the w-test).
    pub w: T,
    /// Bias estimate b_i = r_i / S_ii, sigma units (seed 000 eq. 8).
    pub bias_sigma: T,
    /// The rule's score (larger = more likely faulty).
    pub score: T,
}

/// The score of one satellite under a rule, from its whitened residual and
/// S_ii. `None` when S_ii is below `min_s_ii` (unidentifiable).
#[inline]
pub fn score<T: Real>(rule: FiRule, residual: T, s_ii: T, min_s_ii: T) -> Option<Candidate<T>> {
    if !(s_ii >= min_s_ii) {
        return None;
    }
    Some(score_with(rule, residual, s_ii, log_term(rule, s_ii)))
}

/// The rule's logarithm of S_ii, the only transcendental part of its score
/// (zero for the MLE; ln S_ii flat; ln(1 + kappa S_ii) Gaussian), computed
/// apart so that a caller can take all of an epoch's logarithms in one
/// tight loop ([`crate::snapshot`]'s per-satellite
/// output). [`score_with`] of it is [`score`] bit for bit.
#[inline]
pub fn log_term<T: Real>(rule: FiRule, s_ii: T) -> T {
    match rule {
        FiRule::Mle => T::zero(),
        FiRule::LraimFlat => s_ii.ln_m(),
        FiRule::LraimGaussian { kappa } => (T::of(kappa) * s_ii).ln_1p_m(),
    }
}

/// [`score`] for an identifiable satellite (S_ii >= `min_s_ii`, checked
/// by the caller), with the rule's [`log_term`] of S_ii given.
#[inline(always)]
pub fn score_with<T: Real>(rule: FiRule, residual: T, s_ii: T, log_term: T) -> Candidate<T> {
    let w2 = residual * residual / s_ii;
    let score = match rule {
        FiRule::Mle => w2,
        // 2 ln of the flat-prior marginal likelihood, up to a constant:
        // w^2 - ln S_ii (SPEC §4.2).
        FiRule::LraimFlat => w2 - log_term,
        // Exact Gaussian prior b ~ N(0, kappa sigma^2):
        // w^2 kS/(1+kS) - ln(1+kS).
        FiRule::LraimGaussian { kappa } => {
            let ks = T::of(kappa) * s_ii;
            w2 * ks / (T::one() + ks) - log_term
        }
    };
    Candidate {
        row: 0,
        w: residual / s_ii.sqrt(),
        bias_sigma: residual / s_ii,
        score,
    }
}

/// The best and the runner-up candidate of a parity solution under `rule`.
/// `None` for the best means no satellite is identifiable.
pub fn rank<const N: usize, T: Real>(
    parity: &Parity<N, T>,
    rule: FiRule,
    min_s_ii: f64,
) -> (Option<Candidate<T>>, Option<Candidate<T>>) {
    rank_rows(rule, parity.residuals(), parity.s_ii(), T::of(min_s_ii))
}

/// The best and the runner-up of `rule` over rows given by a residual-like
/// vector (`residuals`, or the MCUSUM's accumulated vector) and S_ii.
pub fn rank_rows<T: Real>(
    rule: FiRule,
    residuals: &[T],
    s_ii: &[T],
    min_s_ii: T,
) -> (Option<Candidate<T>>, Option<Candidate<T>>) {
    let mut ranking = Ranking::new();
    for (row, (&r, &s)) in residuals.iter().zip(s_ii).enumerate() {
        let Some(mut c) = score(rule, r, s, min_s_ii) else {
            continue;
        };
        c.row = row;
        ranking.offer(c);
    }
    (ranking.best, ranking.second)
}

/// The running best and runner-up of a ranking, fed candidates in row
/// order: [`rank_rows`]'s update, shared with the per-satellite output,
/// which scores every row anyway (FDE's first ranking, on the
/// all-in-view solution, is taken from there instead of scoring again).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Ranking<T: Real> {
    pub(crate) best: Option<Candidate<T>>,
    pub(crate) second: Option<Candidate<T>>,
}

impl<T: Real> Ranking<T> {
    pub(crate) fn new() -> Self {
        Ranking {
            best: None,
            second: None,
        }
    }

    /// Offer the next row's candidate.
    pub(crate) fn offer(&mut self, c: Candidate<T>) {
        match self.best {
            Some(b) if !outranks(c.score, b.score) => {
                if self.second.is_none_or(|s2| outranks(c.score, s2.score)) {
                    self.second = Some(c);
                }
            }
            _ => {
                self.second = self.best;
                self.best = Some(c);
            }
        }
    }
}

/// Whether score `a` ranks strictly above `b`. A NaN score (a satellite
/// whose residual cannot be evaluated) ranks above every number, so it is
/// identified first whatever its position in the list (`<=` on a
/// NaN made the ranking depend on the order of the rows). Between two NaNs
/// the earlier row stays.
fn outranks<T: Real>(a: T, b: T) -> bool {
    match (a.is_nan_m(), b.is_nan_m()) {
        (true, false) => true,
        (false, false) => a > b,
        (_, true) => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A NaN residual ranks first and the finite rows keep their order,
    /// for every position of the NaN row and every rule.
    ///
    /// Verifies: SAFE-NAN
    #[test]
    fn nan_ranking_does_not_depend_on_row_order() {
        let s = [0.5, 0.6, 0.4, 0.7];
        let r = [1.0, -3.0, 0.5, 2.0];
        for rule in [FiRule::Mle, FiRule::LraimFlat, FiRule::default()] {
            let (b, s2) = rank_rows(rule, &r, &s, 1e-4);
            let (b, s2) = (b.unwrap().row, s2.unwrap().row);
            for bad in 0..4 {
                let mut r2 = r;
                r2[bad] = f64::NAN;
                let (nb, ns) = rank_rows(rule, &r2, &s, 1e-4);
                assert_eq!(nb.unwrap().row, bad, "{rule:?} row {bad}");
                // The runner-up is the best of the finite rows.
                let expect = if bad == b { s2 } else { b };
                assert_eq!(ns.unwrap().row, expect, "{rule:?} row {bad}");
            }
        }
        assert!(outranks(f64::NAN, f64::INFINITY));
        assert!(!outranks(f64::INFINITY, f64::NAN));
        assert!(!outranks(f64::NAN, f64::NAN));
    }

    /// The flat-prior score is 2 ln of the marginal likelihood
    /// integral exp(-J(b)/2) db of seed 000 eq. 7, up to a constant common
    /// to all satellites. Check by numerical quadrature.
    ///
    /// Verifies: SPEC-4.2
    #[test]
    fn flat_prior_score_is_twice_log_marginal_likelihood() {
        // Two satellites with different S_ii and residuals; zSz common.
        let cases = [(1.3, 0.4), (0.7, 0.05), (-2.1, 0.9)];
        let zsz = 9.0;
        let mut diffs = [0.0; 3];
        for (k, (r, s)) in cases.iter().enumerate() {
            // J(b) = S b^2 - 2 b r + zSz (r = S_i^T z).
            let mut integral = 0.0;
            let (lo, hi, steps) = (-400.0, 400.0, 400_000);
            let db = (hi - lo) / steps as f64;
            for j in 0..=steps {
                let b = lo + j as f64 * db;
                let wgt = if j == 0 || j == steps { 0.5 } else { 1.0 };
                integral += wgt * (-(s * b * b - 2.0 * b * r + zsz) / 2.0).exp() * db;
            }
            let c = score(FiRule::LraimFlat, *r, *s, 1e-9).unwrap();
            // 2 ln(integral) = score - zSz + ln(2 pi)
            diffs[k] = 2.0 * integral.ln() - (c.score - zsz + (2.0 * core::f64::consts::PI).ln());
        }
        const QUADRATURE_TOL: f64 = 1e-9; // dimensionless, log-likelihood units
        for d in diffs {
            assert!(d.abs() < QUADRATURE_TOL, "{diffs:?}");
        }
    }

    /// Verifies: SPEC-4.2
    #[test]
    fn gaussian_prior_tends_to_flat_and_matches_quadrature() {
        let (r, s) = (1.7, 0.3);
        let flat = score(FiRule::LraimFlat, r, s, 1e-9).unwrap().score;
        let big = score(FiRule::LraimGaussian { kappa: 1e12 }, r, s, 1e-9)
            .unwrap()
            .score;
        // kappa -> inf: w^2 kS/(1+kS) - ln(1+kS) -> w^2 - ln S - ln kappa.
        assert!((big + 1e12f64.ln() - flat).abs() < 1e-6, "{big} {flat}");
        // Quadrature of the Gaussian prior marginal: N(b; 0, kappa) prior.
        let kappa = 4.0;
        let mut integral = 0.0;
        let steps = 200_000;
        let db = 200.0 / steps as f64;
        for j in 0..=steps {
            let b = -100.0 + j as f64 * db;
            let prior =
                (-b * b / (2.0 * kappa)).exp() / (2.0 * core::f64::consts::PI * kappa).sqrt();
            integral += (-(s * b * b - 2.0 * b * r) / 2.0).exp() * prior * db;
        }
        let g = score(FiRule::LraimGaussian { kappa }, r, s, 1e-9)
            .unwrap()
            .score;
        assert!(
            (2.0 * integral.ln() - g).abs() < 1e-8,
            "{} vs {g}",
            2.0 * integral.ln()
        );
    }

    /// Verifies: SPEC-4.2
    #[test]
    fn unidentifiable_below_min_s_ii() {
        assert!(score(FiRule::Mle, 1.0, 1e-6, 1e-4).is_none());
        assert!(score(FiRule::Mle, 1.0, f64::NAN, 1e-4).is_none());
    }
}

#[cfg(test)]
#[path = "lraim_cov_tests.rs"]
mod cov_tests;
