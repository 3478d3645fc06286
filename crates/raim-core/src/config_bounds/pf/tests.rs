//! The PF bounds: each field's ends accepted and just outside refused, the
//! threshold's ceiling from the LLR's scale, the calibrated table inside
//! it, and the review's values refused.
extern crate std;
use super::*;

fn oor(b: Bound, value: f64) -> PfError {
    PfError::OutOfRange {
        field: b.field,
        value,
        min: b.min,
        max: b.max,
    }
}

fn float_bound(b: Bound, set: fn(&mut PfConfig, f64)) {
    assert!(b.min < b.max, "{}", b.field);
    let with = |v: f64| {
        let mut c = PfConfig::default();
        set(&mut c, v);
        c.validate()
    };
    for v in [b.min, b.max, 0.5 * (b.min + b.max)] {
        assert_eq!(with(v), Ok(()), "{} = {v}", b.field);
    }
    let below = if b.min > 0.0 {
        b.min * 0.999
    } else {
        b.min - 1e-9
    };
    for v in [below, b.max * 1.001 + 1e-9] {
        assert_eq!(with(v), Err(oor(b, v)), "{} = {v}", b.field);
    }
    for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert!(
            matches!(with(v), Err(PfError::OutOfRange { field, .. }) if field == b.field),
            "{} = {v}",
            b.field
        );
    }
}

#[test]
fn the_default_is_inside() {
    assert_eq!(PfConfig::default().validate(), Ok(()));
}

#[test]
fn every_field_is_bounded() {
    float_bound(POSITION_M_PER_SQRT_S, |c, v| {
        c.process.position_m_per_sqrt_s = v
    });
    float_bound(CLOCK_M_PER_SQRT_S, |c, v| c.process.clock_m_per_sqrt_s = v);
    float_bound(DRIFT_M_S_PER_SQRT_S, |c, v| {
        c.process.drift_m_s_per_sqrt_s = v
    });
    float_bound(SIGMA_M, |c, v| c.sigma_m = v);
    float_bound(INIT_POSITION_M, |c, v| c.init_position_m = v);
    float_bound(INIT_CLOCK_M, |c, v| c.init_clock_m = v);
    float_bound(INIT_DRIFT_M_S, |c, v| c.init_drift_m_s = v);
    float_bound(MUTATION_M, |c, v| c.mutation_m = v);
    float_bound(READMIT_S, |c, v| c.readmit_s = v);
    float_bound(CLOCK_JUMP_M, |c, v| c.clock_jump_m = v);
    float_bound(COLLAPSE_SIGMA, |c, v| c.collapse_sigma = v);
    float_bound(PFA, |c, v| c.pfa = v);
    float_bound(NU, |c, v| c.likelihood = Likelihood::StudentT { nu: v });
    float_bound(OUTLIER_PROB, |c, v| {
        c.likelihood = Likelihood::Mixture {
            outlier_prob: v,
            outlier_scale: 10.0,
        }
    });
    float_bound(OUTLIER_SCALE, |c, v| {
        c.likelihood = Likelihood::Mixture {
            outlier_prob: 0.01,
            outlier_scale: v,
        }
    });
    for w in [0usize, MAX_WINDOW + 1] {
        let c = PfConfig {
            window: w,
            ..PfConfig::default()
        };
        assert_eq!(c.validate(), Err(oor(WINDOW, w as f64)));
    }
    // The threshold, for each law and window.
    for law in [
        Likelihood::Gaussian,
        Likelihood::StudentT { nu: 3.0 },
        Likelihood::Mixture {
            outlier_prob: 0.01,
            outlier_scale: 10.0,
        },
    ] {
        for window in [1usize, 10, MAX_WINDOW] {
            let b = threshold_bound(&law, window);
            let with = |t: f64| b.check_pf(t);
            assert!(b.max > 0.0, "{law:?} {window}: {}", b.max);
            assert_eq!(with(b.max), Ok(()));
            assert_eq!(with(b.min), Ok(()));
            let above = b.max * 1.001;
            assert_eq!(with(above), Err(oor(b, above)));
            assert_eq!(with(b.min - 1.0), Err(oor(b, b.min - 1.0)));
        }
    }
}

/// DETECT_SIGMA is the snapshot monitor's pbias at the floors of its Pfa
/// and Pmd bounds, 1 dof (the core's own non-central chi-square), rounded
/// up by less than 0.01 sigma.
#[test]
fn detect_sigma_is_the_snapshot_pbias_at_the_floors() {
    let b = crate::stats::dist::pbias(super::super::PFA.min, super::super::PMD.min, 1).unwrap();
    assert!(DETECT_SIGMA >= b && DETECT_SIGMA - b < 0.01, "{b}");
}

/// The LLR scale: the Gaussian's s(delta) is (delta^2 - 1) / 2; the
/// default's ceiling (Gaussian, U = 10) and the Student-t (3 dof) one are
/// the numbers of the module doc and docs/PROTOCOL.md.
#[test]
fn threshold_ceiling_follows_the_llr_scale() {
    const NATS_TOL: f64 = 1e-9;
    for d in [0.0, 1.0, 5.0, DETECT_SIGMA] {
        let s = llr_per_epoch(&Likelihood::Gaussian, d);
        assert!((s - 0.5 * (d * d - 1.0)).abs() < NATS_TOL, "{d}: {s}");
    }
    let g = threshold_bound(&Likelihood::Gaussian, 10).max;
    let t = threshold_bound(&Likelihood::StudentT { nu: 3.0 }, 10).max;
    std::println!("threshold ceilings, U = 10: Gaussian {g:.1}, Student-t 3 dof {t:.1}");
    assert!((g - 728.3).abs() < 0.1, "{g}");
    assert!((t - 68.5).abs() < 0.1, "{t}");
    // The Student-t's s grows only as ln(delta): the Gaussian's ceiling
    // would be out of its reach.
    assert!(llr_per_epoch(&Likelihood::StudentT { nu: 3.0 }, 1e6) < 0.1 * g);
}

/// The calibrated table against the detectability ceiling: a certified
/// threshold above it is one no DETECT_SIGMA fault can reach, so
/// `PfRaim::process` refuses that configuration (`OutOfRange`, the
/// threshold's bound). Every row of the default profile (the device's
/// configuration) and the Gaussian 300-particle and EKF rows of the other
/// profiles at U >= 5 are inside; the refused entries are printed.
#[test]
fn the_calibrated_table_against_the_bound() {
    use crate::pf::threshold_table::{PROFILES, ROWS, WINDOWS};
    let mut refused = 0usize;
    for r in ROWS.iter() {
        let name = PROFILES.get(r.profile).map_or("?", |p| p.name);
        for (t, &window) in r.threshold.iter().zip(WINDOWS.iter()) {
            let b = threshold_bound(&r.likelihood, window);
            for &v in t.iter().filter(|v| v.is_finite()) {
                if b.check_pf(v).is_err() {
                    refused += 1;
                    std::println!(
                        "refused: {name} {} {} {:?} U = {window}: {v:.2} > {:.2}",
                        r.kind,
                        r.particles,
                        r.likelihood,
                        b.max
                    );
                }
                let must_pass = r.profile == 0
                    || (r.likelihood == Likelihood::Gaussian
                        && window >= 5
                        && (r.kind == "ekf" || r.particles == 300)
                        && name != "geodetic_30s");
                if must_pass {
                    assert_eq!(
                        b.check_pf(v),
                        Ok(()),
                        "{name} {} {} U = {window}",
                        r.kind,
                        r.particles
                    );
                }
            }
        }
    }
    std::println!("{refused} certified entries above the ceiling");
}

/// The review's values: a threshold of 1e300 (a 160 m fault never
/// alarms), a Pfa of 1e-300 and sigmas far outside the model.
///
/// Verifies: SAFE-T5
#[test]
fn the_review_values_are_refused() {
    let b = threshold_bound(&Likelihood::Gaussian, 10);
    assert_eq!(b.check_pf(1e300), Err(oor(b, 1e300)));
    let c = PfConfig {
        pfa: 1e-300,
        ..PfConfig::default()
    };
    assert_eq!(c.validate(), Err(oor(PFA, 1e-300)));
    for s in [1e-30, 1e30] {
        let c = PfConfig {
            sigma_m: s,
            ..PfConfig::default()
        };
        assert_eq!(c.validate(), Err(oor(SIGMA_M, s)));
    }
}
