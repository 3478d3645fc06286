//! The PL bracket's memo replaced for another mode count, and brackets
//! that do not exist (an infinite offset at either end).

use super::*;

const FF: Term = Term {
    p: 2.0,
    offset_m: 0.3,
    sigma_m: 1.5,
};

/// A memo made for 5 modes, used by a 3-mode equation of the same
/// right-hand side, is replaced (its upper target rhs / 6 is not the
/// equation's rhs / 4): the bracket equals the one from fresh memos.
#[test]
fn a_memo_for_another_mode_count_is_replaced() {
    let terms = [
        Term {
            p: 1e-5,
            offset_m: 4.0,
            sigma_m: 2.0,
        },
        Term {
            p: 3e-5,
            offset_m: 2.0,
            sigma_m: 1.0,
        },
        Term {
            p: 2e-6,
            offset_m: 6.0,
            sigma_m: 3.0,
        },
    ];
    let eq = Equation {
        fault_free: FF,
        modes: || terms.iter().copied(),
        n_modes: 3,
        rhs: 1e-7,
    };
    let fresh = eq.bracket().unwrap();
    let mut other = BracketCache::new(eq.rhs, 5);
    assert_eq!(eq.bracket_cached(&mut other), Some(fresh));
    // The bracket's ends written out: the largest term quantile at rhs
    // (lower) and at rhs / (n_modes + 1) (upper), statrs' normal.
    use statrs::distribution::{ContinuousCDF, Normal};
    let q_inv = |x: f64| Normal::new(0.0, 1.0).unwrap().inverse_cdf(1.0 - x);
    let end = |target: f64| {
        terms
            .iter()
            .map(|t| t.offset_m + t.sigma_m * q_inv(target / t.p))
            .fold(FF.offset_m + FF.sigma_m * q_inv(target / FF.p), f64::max)
    };
    assert!((fresh.0 - end(1e-7)).abs() < 1e-9, "{fresh:?}");
    assert!((fresh.1 - end(1e-7 / 4.0)).abs() < 1e-9, "{fresh:?}");
}

/// A mode with an infinite offset leaves no finite bracket: through both
/// ends, or through the upper end alone when its prior equals the
/// right-hand side (no quantile at rhs / p = 1 for the lower end).
#[test]
fn an_infinite_offset_leaves_no_bracket() {
    let both = [Term {
        p: 1e-5,
        offset_m: f64::INFINITY,
        sigma_m: 1.0,
    }];
    let eq = Equation {
        fault_free: FF,
        modes: || both.iter().copied(),
        n_modes: 1,
        rhs: 1e-7,
    };
    assert_eq!(eq.bracket(), None);
    let upper_only = [Term {
        p: 1e-7,
        offset_m: f64::INFINITY,
        sigma_m: 1.0,
    }];
    let eq = Equation {
        fault_free: FF,
        modes: || upper_only.iter().copied(),
        n_modes: 1,
        rhs: 1e-7,
    };
    assert_eq!(eq.bracket(), None);
}
