//! The identification rules under study (SPEC §4.1-4.2), evaluated with the
//! core's own score, `raim_core::snapshot::lraim::score`, so the tool measures the
//! product's code rather than a re-implementation.
//!
//! Every rule's score has the form alpha_i w_i^2 + beta_i (w_i the
//! normalised residual): MLE alpha = 1, beta = 0; flat L-RAIM alpha = 1,
//! beta = -ln S_ii; Gaussian L-RAIM alpha = kS/(1+kS), beta = -ln(1+kS).
//! [`affine`] reads alpha and beta off the core's score (at w = 0 and w = 1)
//! for the exact integration; a test checks the form holds.

use raim_core::snapshot::lraim::score;
use raim_core::FiRule;

/// Relative tolerance under which two scores are a tie. Ties have
/// probability zero except where the geometry forces them (d = 1, where
/// every |w_j| is the same, so MLE cannot choose); a tie shares the credit
/// equally (a fair random tie-break).
pub const TIE_REL_TOL: f64 = 1e-9;

/// The rules compared: name for reports, and the core's rule.
#[derive(Debug, Clone, Copy)]
pub struct Rule {
    pub name: &'static str,
    pub rule: FiRule,
}

/// MLE, flat L-RAIM and Gaussian L-RAIM with the given kappa.
pub fn rules(kappa: f64) -> [Rule; 3] {
    [
        Rule {
            name: "mle",
            rule: FiRule::Mle,
        },
        Rule {
            name: "lraim_flat",
            rule: FiRule::LraimFlat,
        },
        Rule {
            name: "lraim_gauss",
            rule: FiRule::LraimGaussian { kappa },
        },
    ]
}

/// Scores of every satellite under `rule` from residuals r_j and S_jj
/// (`None`: unidentifiable, S_jj below `min_s_ii`).
pub fn scores_into(
    rule: FiRule,
    residual: &[f64],
    s_ii: &[f64],
    min_s_ii: f64,
    out: &mut [Option<f64>],
) {
    for ((o, &r), &s) in out.iter_mut().zip(residual.iter()).zip(s_ii.iter()) {
        *o = score(rule, r, s, min_s_ii).map(|c| c.score);
    }
}

/// The credit the rule gives satellite `i`: 1 if it alone has the largest
/// score, 1/k if it ties with k - 1 others, 0 otherwise (also when it is
/// unidentifiable).
pub fn credit(scores: &[Option<f64>], i: usize) -> f64 {
    let Some(Some(si)) = scores.get(i).copied() else {
        return 0.0;
    };
    let tol = TIE_REL_TOL * (1.0 + si.abs());
    let mut ties = 0usize;
    for s in scores.iter().flatten() {
        if *s > si + tol {
            return 0.0;
        }
        if (*s - si).abs() <= tol {
            ties += 1;
        }
    }
    1.0 / ties.max(1) as f64
}

/// (alpha, beta) of the rule's score alpha w^2 + beta for a satellite with
/// this S_ii, read off the core's score; `None` if unidentifiable.
pub fn affine(rule: FiRule, s_ii: f64, min_s_ii: f64) -> Option<(f64, f64)> {
    let beta = score(rule, 0.0, s_ii, min_s_ii)?.score;
    // Residual sqrt(S_ii) is w = 1.
    let one = score(rule, s_ii.sqrt(), s_ii, min_s_ii)?.score;
    Some((one - beta, beta))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The core's scores are affine in w^2 with the SPEC §4.2 coefficients.
    #[test]
    fn scores_are_affine_in_w_squared() {
        const AFFINE_TOL: f64 = 1e-12; // score units
        for rule in rules(100.0) {
            for s in [1e-3, 0.05, 0.3, 0.9] {
                let (alpha, beta) = affine(rule.rule, s, 1e-4).unwrap();
                let (a_spec, b_spec) = match rule.rule {
                    FiRule::Mle => (1.0, 0.0),
                    FiRule::LraimFlat => (1.0, -f64::ln(s)),
                    FiRule::LraimGaussian { kappa } => {
                        (kappa * s / (1.0 + kappa * s), -(1.0 + kappa * s).ln())
                    }
                };
                assert!((alpha - a_spec).abs() < AFFINE_TOL && (beta - b_spec).abs() < AFFINE_TOL);
                for w in [-3.0, 0.7, 5.0] {
                    let c = score(rule.rule, w * s.sqrt(), s, 1e-4).unwrap().score;
                    assert!((c - (alpha * w * w + beta)).abs() < 1e-10 * (1.0 + c.abs()));
                }
            }
            assert!(affine(rule.rule, 1e-6, 1e-4).is_none());
        }
    }

    #[test]
    fn credit_shares_ties_and_skips_unidentifiable() {
        assert_eq!(credit(&[Some(1.0), Some(3.0), None], 1), 1.0);
        assert_eq!(credit(&[Some(1.0), Some(3.0), None], 0), 0.0);
        assert_eq!(credit(&[Some(1.0), Some(3.0), None], 2), 0.0);
        assert_eq!(credit(&[Some(3.0), Some(3.0), Some(3.0)], 2), 1.0 / 3.0);
    }
}
