//! The particle filter's degenerate inputs: log-weights that are all
//! -inf (N_eff 0), equal log-weights (N_eff = the count), and an update
//! whose likelihoods are NaN or -inf (a collapse, never a fix).

extern crate std;

use super::*;
use crate::measurement::{SatId, System};
use crate::pf::model::Reference;

#[test]
fn n_eff_of_degenerate_and_equal_weights() {
    // exp(-inf - -inf) is NaN: no weight is positive, N_eff is 0.
    let none = [f64::NEG_INFINITY; 4];
    assert_eq!(n_eff_of_log_weights(&none, f64::NEG_INFINITY), 0.0);
    // Equal weights: (n w)^2 / (n w^2) = n.
    let equal = [-3.0f64; 7];
    assert!((n_eff_of_log_weights(&equal, -3.0) - 7.0).abs() < 1e-12);
    // One dominant weight: N_eff -> 1.
    let one = [0.0, -800.0, -800.0];
    assert!((n_eff_of_log_weights(&one, 0.0) - 1.0).abs() < 1e-12);
}

fn term(pseudorange_m: f64) -> SatTerm<f64> {
    SatTerm::new(
        SatId::new(System::Gps, 1),
        pseudorange_m,
        &[2.0e7, 0.0, 0.0],
        3.0,
        &Reference::ZERO,
    )
}

/// A NaN range makes every particle's likelihood NaN, an infinite one
/// every likelihood -inf (the predictive density -inf): both collapse
/// with N_eff 0 and leave the particles as they were.
#[test]
fn nan_or_infinite_likelihoods_collapse() {
    let cfg = PfConfig::default();
    for z in [f64::NAN, f64::INFINITY] {
        let mut rng = rng::seeded(9);
        let mut f = GaPf::<f64, 16>::BLANK;
        f.init(&cfg, &mut rng);
        let before = *f.particles();
        let s = f.update(&cfg, &[term(z)], None, &mut rng);
        assert!(s.collapsed, "{z}");
        assert_eq!((s.n_eff, s.n_eff_before_ga), (0.0, 0.0));
        assert!(!s.ln_predictive.is_finite(), "{z}");
        assert_eq!(f.particles(), &before);
        // The initial particles are drawn: not the blank zeros.
        assert!(before.iter().any(|p| p.iter().any(|&v| v != 0.0)));
    }
    // A sound range does not collapse.
    let mut rng = rng::seeded(9);
    let mut f = GaPf::<f64, 16>::BLANK;
    f.init(&cfg, &mut rng);
    let s = f.update(&cfg, &[term(2.0e7)], None, &mut rng);
    assert!(!s.collapsed && s.ln_predictive.is_finite() && s.n_eff >= 1.0);
}
