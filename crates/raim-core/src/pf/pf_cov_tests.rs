//! The PF monitor's rarer arms: an observation without its own sigma
//! (the configuration's is used), the EKF's refused innovations, the
//! online log-sum-exp's NaN and infinite terms, and the LLR window's
//! emptiness.

extern crate std;

use super::llr::LlrWindow;
use super::model::{Estimator, LogSumExp, SatTerm};
use super::*;
use crate::measurement::{RangeObservation, SatId, System};

/// A receiver on the equator at longitude 0 and six satellites 20 000 km
/// out, spread over the sky; pseudoranges are the true ranges plus a
/// 100 m clock, plus `noise_m(i)`.
fn epoch(k: usize, sigma_m: Option<f64>) -> [RangeObservation; 6] {
    let rx = [6_378_137.0, 0.0, 0.0];
    let dirs: [[f64; 3]; 6] = [
        [1.0, 0.0, 0.0],
        [0.8, 0.6, 0.0],
        [0.8, -0.6, 0.0],
        [0.8, 0.0, 0.6],
        [0.8, 0.0, -0.6],
        [0.6, 0.56, 0.57],
    ];
    let mut out = [RangeObservation {
        id: SatId::new(System::Gps, 1),
        pseudorange_m: 0.0,
        position_m: [0.0; 3],
        sigma_m,
    }; 6];
    for (i, (o, d)) in out.iter_mut().zip(dirs.iter()).enumerate() {
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let sat = [
            rx[0] + 2.0e7 * d[0] / n,
            rx[1] + 2.0e7 * d[1] / n,
            rx[2] + 2.0e7 * d[2] / n,
        ];
        // A deterministic +-1 m pattern that changes with the epoch.
        let noise = if (i + k).is_multiple_of(2) { 1.0 } else { -1.0 };
        *o = RangeObservation {
            id: SatId::new(System::Gps, i as u8 + 1),
            pseudorange_m: 2.0e7 + 100.0 + noise,
            position_m: sat,
            sigma_m,
        };
    }
    out
}

/// An observation without a sigma is weighted with `PfConfig::sigma_m`:
/// the same epochs with that sigma written out give the same output.
#[test]
fn a_missing_sigma_is_the_configurations() {
    let cfg = PfConfig::default();
    let mut with = std::boxed::Box::new(PfRaim::<f64, Ekf<f64>, 8>::new(5));
    let mut without = std::boxed::Box::new(PfRaim::<f64, Ekf<f64>, 8>::new(5));
    let mut other = std::boxed::Box::new(PfRaim::<f64, Ekf<f64>, 8>::new(5));
    let mut differs = false;
    for k in 0..4 {
        let t = 1000.0 + k as f64;
        let a = with.process(&cfg, t, &epoch(k, Some(cfg.sigma_m))).unwrap();
        let b = without.process(&cfg, t, &epoch(k, None)).unwrap();
        let c = other
            .process(&cfg, t, &epoch(k, Some(4.0 * cfg.sigma_m)))
            .unwrap();
        assert_eq!(a, b, "epoch {k}");
        differs |= c.llr != a.llr;
    }
    // And the sigma does matter (the comparison can fail).
    assert!(differs);
}

fn term(pseudorange_m: f64, sigma_m: f64) -> SatTerm<f64> {
    SatTerm::new(
        SatId::new(System::Gps, 1),
        pseudorange_m,
        &[2.0e7, 0.0, 0.0],
        sigma_m,
        &Reference::ZERO,
    )
}

/// The EKF refuses an innovation whose variance is not positive and
/// finite (a zero covariance with a zero sigma; an infinite sigma) and a
/// non-finite log-density (a NaN range): each is a collapse with a NaN
/// predictive density, never a finite one.
#[test]
fn ekf_collapses_on_a_degenerate_innovation() {
    let cfg = PfConfig::default();
    let mut rng = rng::seeded(1);
    // BLANK has a zero covariance: with sigma 0, S = 0.
    let mut f = Ekf::<f64>::BLANK;
    let s = f.update(&cfg, &[term(2.0e7, 0.0)], None, &mut rng);
    assert!(s.collapsed && s.ln_predictive.is_nan());
    let mut f = Ekf::<f64>::BLANK;
    f.init(&cfg, &mut rng);
    let s = f.update(&cfg, &[term(2.0e7, f64::INFINITY)], None, &mut rng);
    assert!(s.collapsed && s.ln_predictive.is_nan());
    let mut f = Ekf::<f64>::BLANK;
    f.init(&cfg, &mut rng);
    let s = f.update(&cfg, &[term(f64::NAN, 3.0)], None, &mut rng);
    assert!(s.collapsed && s.ln_predictive.is_nan());
    // The same filter with a sound range does not collapse: its
    // log-density is the Gaussian's of the innovation 5 m over
    // S = init_position_m^2 + init_clock_m^2 + sigma^2 (the line of sight
    // is the x axis, so H P H^T is the x and clock variances).
    let mut f = Ekf::<f64>::BLANK;
    f.init(&cfg, &mut rng);
    let s = f.update(&cfg, &[term(2.0e7 + 5.0, 3.0)], None, &mut rng);
    let var = cfg.init_position_m.powi(2)
        + cfg.init_clock_m.powi(2)
        + 9.0 * cfg.likelihood.variance_factor();
    let expect = -0.5 * (2.0 * core::f64::consts::PI * var).ln() - 12.5 / var;
    assert!(!s.collapsed);
    assert!(
        (s.ln_predictive - expect).abs() < 1e-9,
        "{} {expect}",
        s.ln_predictive
    );
}

/// ln(sum exp v): a NaN after the first term poisons the sum, -inf adds
/// nothing, +inf twice stays +inf, and an empty sum is -inf.
#[test]
fn log_sum_exp_handles_non_finite_terms() {
    let empty = LogSumExp::<f64>::default();
    assert_eq!(empty.value(), f64::NEG_INFINITY);
    let mut a = LogSumExp::<f64>::default();
    a.push(0.0);
    a.push(f64::NEG_INFINITY);
    assert_eq!(a.value(), 0.0);
    a.push(0.0);
    assert!((a.value() - 2f64.ln()).abs() < 1e-15);
    a.push(f64::NAN);
    assert!(a.value().is_nan());
    let mut b = LogSumExp::<f64>::default();
    b.push(f64::INFINITY);
    b.push(f64::INFINITY);
    assert_eq!(b.value(), f64::INFINITY);
}

#[test]
fn llr_window_reports_emptiness() {
    let mut w = LlrWindow::default();
    assert!(w.is_empty());
    w.push(1.5);
    assert!(!w.is_empty());
    assert_eq!(w.len(), 1);
    w.clear();
    assert!(w.is_empty());
}
