//! Edge cases of the distributions (SPEC §3, §6): the boundaries of the
//! CDFs, invalid shapes, the smallest positive inputs, shapes below 1/2,
//! and quantiles far in either tail, against statrs or closed forms.
//!
//! Test code only (`#[cfg(test)] mod edge_tests;` in `stats/dist.rs`).
#![allow(clippy::unwrap_used, clippy::float_cmp)]

use super::*;
use statrs::distribution::{ChiSquared, ContinuousCDF};
use statrs::function::gamma::{gamma_lr, gamma_ur};

/// Relative tolerance of the incomplete gamma against statrs.
const TOL_GAMMA_REL: f64 = 1e-12;

/// The smallest positive f64 (subnormal): half of it rounds to 0.
const TINY: f64 = 5e-324;

/// x <= 0, x = inf and the smallest positive x at the CDFs' ends: exact
/// 0 and 1 (half of the smallest subnormal is 0, so chi-square and the
/// non-central chi-square see no mass below it).
#[test]
fn chi_square_ends_are_exact() {
    for dof in [1, 3, 10] {
        for x in [0.0, -1.0, -f64::INFINITY, TINY] {
            assert_eq!(chi2_cdf(x, dof), Ok(0.0), "{x} {dof}");
            assert_eq!(chi2_sf(x, dof), Ok(1.0), "{x} {dof}");
        }
        assert_eq!(chi2_cdf(f64::INFINITY, dof), Ok(1.0));
        assert_eq!(chi2_sf(f64::INFINITY, dof), Ok(0.0));
        assert_eq!(ncx2_cdf(TINY, dof, 4.0), Ok(0.0));
    }
}

/// P(a, x) and Q(a, x): NaN for a shape that is not finite and positive or
/// a NaN x; 0/1 at x <= 0 and 1/0 at x = inf; elsewhere statrs' values, for
/// shapes below 1/2 (the direct Poisson term), non-half-integer shapes
/// (Stirling's error from lgamma), on both sides of x = a + 1.
#[test]
fn incomplete_gamma_edges_and_small_shapes_match_statrs() {
    for a in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(gamma_p(a, 1.0).is_nan() && gamma_q(a, 1.0).is_nan(), "{a}");
    }
    assert!(gamma_p(2.0, f64::NAN).is_nan() && gamma_q(2.0, f64::NAN).is_nan());
    assert_eq!((gamma_p(2.0, 0.0), gamma_q(2.0, -3.0)), (0.0, 1.0));
    assert_eq!(
        (gamma_p(2.0, f64::INFINITY), gamma_q(2.0, f64::INFINITY)),
        (1.0, 0.0)
    );
    for a in [0.05, 0.3, 0.49, 3.3, 7.7, 14.2] {
        for x in [0.01, 0.4, 1.0, 2.5, 9.0, 30.0] {
            let (p, q) = (gamma_p(a, x), gamma_q(a, x));
            let (p_ref, q_ref) = (gamma_lr(a, x), gamma_ur(a, x));
            assert!(
                (p - p_ref).abs() <= TOL_GAMMA_REL * p_ref,
                "P({a}, {x}) = {p}, statrs {p_ref}"
            );
            assert!(
                (q - q_ref).abs() <= TOL_GAMMA_REL * q_ref,
                "Q({a}, {x}) = {q}, statrs {q_ref}"
            );
        }
    }
}

/// Quantiles with pfa near 1 (Wilson-Hilferty's start goes negative; the
/// small-x power law starts instead) and far in the upper tail, for 1 to
/// 200 dof: statrs' CDF or survival function at our quantile gives back
/// the probability asked for.
#[test]
fn extreme_quantiles_match_statrs() {
    for dof in [3, 4, 10, 50, 200] {
        for lower in [1e-3, 1e-6, 1e-10] {
            let x = chi2_quantile_upper(1.0 - lower, dof).unwrap();
            let cdf = ChiSquared::new(f64::from(dof)).unwrap().cdf(x);
            // 1 - lower is rounded to the nearest double: its error, 1.1e-16,
            // relative to `lower`.
            let tol = 1e-9 + 2.0 * f64::EPSILON / lower;
            assert!(
                (cdf - lower).abs() <= tol * lower,
                "{dof} {lower}: {x} {cdf}"
            );
        }
    }
    for dof in [1, 2, 7, 60, 200] {
        for pfa in [1e-30, 1e-100, 1e-250] {
            let x = chi2_quantile_upper(pfa, dof).unwrap();
            let sf = ChiSquared::new(f64::from(dof)).unwrap().sf(x);
            assert!((sf - pfa).abs() <= 1e-9 * pfa, "{dof} {pfa}: {x} {sf}");
        }
    }
}

/// The smallest positive pfa with one dof: the closed-form start
/// Q^-1(pfa / 2)^2 underflows (pfa / 2 = 0), and the iteration still
/// finds the root. At that pfa the survival function is a subnormal
/// quantised to multiples of pfa itself, so the root is any x whose true
/// tail lies within half a quantum of pfa: between the x of 1.5 pfa and
/// of 0.5 pfa. Reference: Mills' asymptotic 2 Q(z) ~ 2 phi(z) / z, solved
/// for z by fixed point (its relative error, 1 / z^2 ~ 7e-4 in the tail,
/// moves z^2 by ~1.4e-3).
#[test]
fn smallest_pfa_one_dof_lies_in_the_asymptotic_band() {
    // x = z^2 with 2 Q(z) = exp(ln_tail).
    let x_at = |ln_tail: f64| {
        let ln_q = ln_tail - core::f64::consts::LN_2;
        let mut z: f64 = 38.0;
        for _ in 0..50 {
            z = libm::sqrt(2.0 * (-ln_q - libm::log(z) - LN_SQRT_2PI));
        }
        z * z
    };
    let ln_tiny = libm::log(TINY);
    let lo = x_at(ln_tiny + libm::log(1.5));
    let hi = x_at(ln_tiny + libm::log(0.5));
    let x = chi2_quantile_upper(TINY, 1).unwrap();
    assert!(lo - 0.01 <= x && x <= hi + 0.01, "{x} outside [{lo}, {hi}]");
}
