//! The deviance and Stirling-error helpers at their ends: the limits of
//! a ln(a / x) + x - a as x -> 0 and x -> inf (+inf), Stirling's error at
//! a = 0 (+inf) and against ln Gamma(a + 1) - ln(sqrt(2 pi) a^(a + 1/2)
//! e^-a) from statrs away from the tabulated half-integers.

extern crate std;

use super::*;

#[test]
fn deviance_is_infinite_at_its_ends() {
    assert_eq!(bd0(1.0, 0.0), f64::INFINITY);
    assert_eq!(bd0(3.0, f64::INFINITY), f64::INFINITY);
    // Inside: the closed form (far from a = x, where it does not cancel).
    for (a, x) in [(1.0f64, 5.0f64), (2.5, 0.25), (10.0, 40.0)] {
        let exact = a * (a / x).ln() + x - a;
        assert!((bd0(a, x) - exact).abs() <= 1e-13 * exact, "{a} {x}");
    }
}

#[test]
fn stirling_error_at_zero_and_off_the_table() {
    assert_eq!(stirlerr(0.0), f64::INFINITY);
    for a in [0.3, 1.7, 7.25, 14.9] {
        let exact = statrs::function::gamma::ln_gamma(a + 1.0)
            - (0.5 * (2.0 * core::f64::consts::PI).ln() + (a + 0.5) * f64::ln(a) - a);
        assert!(
            (stirlerr(a) - exact).abs() < 1e-13,
            "{a}: {} {exact}",
            stirlerr(a)
        );
    }
}
