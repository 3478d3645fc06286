//! One test per bound: its two ends are accepted, a value just outside
//! each end and NaN are refused with the field, the value and the bound.
extern crate std;
use super::*;
use crate::config::{Config, FiRule, Phase};
use crate::measurement::{Epoch, SatId, System};
use crate::monitor::Raim;
use crate::result::Decision;
use crate::testutil::{range_epoch, Rng};
use std::vec::Vec;

/// The configuration with one field set to `v` (through `set`).
fn with(set: fn(&mut Config, f64), v: f64) -> Config {
    let mut c = Config::default();
    set(&mut c, v);
    c
}

fn refused(b: Bound, c: &Config, v: f64) {
    match c.validate() {
        Err(RaimError::OutOfRange {
            field,
            value,
            min,
            max,
        }) => {
            assert_eq!(field, b.field);
            assert!(value == v || (value.is_nan() && v.is_nan()), "{value} {v}");
            assert_eq!((min, max), (b.min, b.max));
        }
        other => panic!("{} = {v}: {other:?}", b.field),
    }
}

/// Checks a float field: both ends pass, just outside and NaN fail.
fn float_bound(b: Bound, set: fn(&mut Config, f64)) {
    assert!(b.min < b.max);
    for v in [b.min, b.max, 0.5 * (b.min + b.max)] {
        assert_eq!(with(set, v).validate(), Ok(()), "{} = {v}", b.field);
    }
    let below = if b.min > 0.0 { b.min * 0.999 } else { -1e-12 };
    for v in [below, b.max * 1.001, f64::NAN, f64::INFINITY] {
        refused(b, &with(set, v), v);
    }
}

/// Checks an integer field: both ends pass, one past each end fails.
fn int_bound(b: Bound, set: fn(&mut Config, f64)) {
    for v in [b.min, b.max] {
        assert_eq!(with(set, v).validate(), Ok(()), "{} = {v}", b.field);
    }
    if b.min >= 1.0 {
        refused(b, &with(set, b.min - 1.0), b.min - 1.0);
    }
    refused(b, &with(set, b.max + 1.0), b.max + 1.0);
}

#[test]
fn every_preset_is_within_the_bounds() {
    for p in [Phase::EnRoute, Phase::Terminal, Phase::Npa] {
        assert_eq!(Config::preset(p).validate(), Ok(()));
        let split = Config::preset(p).split_false_alarm_budget(0.5);
        assert_eq!(split.validate(), Ok(()));
    }
}

#[test]
fn pfa_bound() {
    float_bound(PFA, |c, v| c.pfa = v);
}

#[test]
fn pmd_bound() {
    float_bound(PMD, |c, v| c.pmd = v);
}

#[test]
fn pwe_bound() {
    float_bound(PWE, |c, v| c.pwe = v);
}

#[test]
fn kappa_bound() {
    float_bound(KAPPA, |c, v| c.rule = FiRule::LraimGaussian { kappa: v });
    // The other rules carry no kappa.
    let c = Config {
        rule: FiRule::Mle,
        ..Config::default()
    };
    assert_eq!(c.validate(), Ok(()));
}

#[test]
fn hal_bound() {
    float_bound(HAL_M, |c, v| c.alert.hal_m = v);
}

#[test]
fn val_bound() {
    float_bound(VAL_M, |c, v| c.alert.val_m = Some(v));
}

#[test]
fn min_s_ii_bound() {
    float_bound(MIN_S_II, |c, v| c.min_s_ii = v);
}

#[test]
fn convergence_bound() {
    float_bound(CONVERGENCE_M, |c, v| c.convergence_m = v);
}

#[test]
fn max_iterations_bound() {
    int_bound(MAX_ITERATIONS, |c, v| c.max_iterations = v as u32);
}

#[test]
fn max_exclusions_bound() {
    assert_eq!(MAX_EXCLUSIONS_BOUND.max, 4.0);
    int_bound(MAX_EXCLUSIONS_BOUND, |c, v| c.max_exclusions = v as u8);
    refused(
        MAX_EXCLUSIONS_BOUND,
        &with(|c, _| c.max_exclusions = u8::MAX, 0.0),
        255.0,
    );
}

#[test]
fn ura_bound() {
    float_bound(URA_M, |c, v| c.sigma_model.ura_m = v);
}

#[test]
fn iono_bound() {
    float_bound(IONO_VERTICAL_M, |c, v| c.sigma_model.iono_vertical_m = v);
}

#[test]
fn noise_bound() {
    float_bound(NOISE_M, |c, v| c.sigma_model.noise_m = v);
}

#[test]
fn min_elevation_bound() {
    float_bound(MIN_ELEVATION_RAD, |c, v| {
        c.sigma_model.min_elevation_rad = v
    });
}

#[test]
fn hold_bound_applies_whether_the_mcusum_runs_or_not() {
    float_bound(HOLD_S, |c, v| {
        *c = c.split_false_alarm_budget(0.5);
        c.mcusum.hold_s = v;
    });
    // Disabled, the MCUSUM settings are checked all the same.
    float_bound(HOLD_S, |c, v| c.mcusum.hold_s = v);
}

#[test]
fn correlation_time_bound_applies_whether_the_mcusum_runs_or_not() {
    float_bound(CORRELATION_TIME_S, |c, v| {
        *c = c.split_false_alarm_budget(0.5);
        c.mcusum.correlation_time_s = v;
    });
    float_bound(CORRELATION_TIME_S, |c, v| c.mcusum.correlation_time_s = v);
    // The default is white noise (0), inside the bound.
    assert_eq!(Config::default().mcusum.correlation_time_s, 0.0);
    assert_eq!(Config::default().validate(), Ok(()));
}

/// A disabled MCUSUM with k = NaN, ARL0 = -1 or hold = infinity is
/// refused, with the field: a disabled part is validated too.
///
/// Verifies: SAFE-T7
#[test]
fn a_disabled_mcusum_is_validated() {
    let c = Config::default();
    assert!(!c.mcusum.enabled);
    let mut bad = c;
    bad.mcusum.k = f64::NAN;
    assert!(matches!(
        bad.validate(),
        Err(RaimError::OutOfRange {
            field: "mcusum_k",
            ..
        })
    ));
    let mut bad = c;
    bad.mcusum.arl0 = -1.0;
    assert!(matches!(
        bad.validate(),
        Err(RaimError::OutOfRange { field: "mcusum_arl0", value, .. }) if value == -1.0
    ));
    let mut bad = c;
    bad.mcusum.hold_s = f64::INFINITY;
    refused(HOLD_S, &bad, f64::INFINITY);
}

/// The per-satellite sigma bound brackets the elevation model: with every
/// term at its floor the model stays above the bound's floor, with every
/// term at its ceiling (at the horizon) below its ceiling.
#[test]
fn sigma_bound_brackets_the_elevation_model() {
    let mut lo = Config::default().sigma_model;
    lo.ura_m = URA_M.min;
    lo.iono_vertical_m = IONO_VERTICAL_M.min;
    lo.noise_m = NOISE_M.min;
    lo.min_elevation_rad = MIN_ELEVATION_RAD.max;
    let mut hi = lo;
    hi.ura_m = URA_M.max;
    hi.iono_vertical_m = IONO_VERTICAL_M.max;
    hi.noise_m = NOISE_M.max;
    hi.min_elevation_rad = MIN_ELEVATION_RAD.min;
    for el_deg in [0.0f64, 2.0, 10.0, 45.0, 90.0] {
        let el = el_deg.to_radians();
        assert!(lo.sigma_m(el) >= SIGMA_M.min, "{el_deg}");
        assert!(hi.sigma_m(el) <= SIGMA_M.max, "{el_deg}");
    }
    let top = hi.sigma_m(0.0);
    std::println!("largest modelled sigma {top:.1} m");
    assert!((137.0..139.0).contains(&top), "{top}");
}

/// A host sigma outside the bound is refused with the satellite's index,
/// in both epoch forms; the ends are accepted. 1e30 used to remove the
/// satellite silently, 1e-9 to shrink every protection level to ~0.
///
/// Verifies: SAFE-T6, WIRE-SigmaOutOfRange
#[test]
fn per_satellite_sigma_is_bounded() {
    let sky: Vec<(System, u8, f64, f64)> = crate::testutil::SKY8
        .iter()
        .enumerate()
        .map(|(i, &(az, el))| (System::Gps, i as u8 + 1, az, el))
        .collect();
    let rx = crate::testutil::RX_ECEF_M;
    let clock = [100.0, 0.0, 0.0, 0.0, 0.0];
    let mut raim = Raim::<16>::new();
    let cfg = Config::default();
    for v in [SIGMA_M.min, SIGMA_M.max] {
        let mut sats = range_epoch(rx, &sky, &clock, 1.0, &mut Rng::new(1), &[]);
        sats[3].sigma_m = Some(v);
        assert!(raim.process(&cfg, &Epoch::ranges(0.0, &sats, None)).is_ok());
    }
    for v in [1e30, 1e-9, SIGMA_M.max * 1.001, SIGMA_M.min * 0.999] {
        let mut sats = range_epoch(rx, &sky, &clock, 1.0, &mut Rng::new(1), &[]);
        sats[3].sigma_m = Some(v);
        let want = RaimError::SigmaOutOfRange {
            index: 3,
            sigma_m: v,
            min_m: SIGMA_M.min,
            max_m: SIGMA_M.max,
        };
        assert_eq!(
            raim.process(&cfg, &Epoch::ranges(0.0, &sats, None)).err(),
            Some(want)
        );
        let lin: Vec<crate::measurement::LinearObservation> = sky
            .iter()
            .enumerate()
            .map(|(i, &(sys, prn, az, el))| {
                let mut o = crate::measurement::LinearObservation::from_az_el(
                    SatId::new(sys, prn),
                    f64::to_radians(az),
                    f64::to_radians(el),
                    0.0,
                );
                o.sigma_m = Some(if i == 3 { v } else { 1.0 });
                o
            })
            .collect();
        assert_eq!(
            raim.process(&cfg, &Epoch::linear(0.0, &lin)).err(),
            Some(want)
        );
    }
}

/// The floors keep every modelled sigma at or above 0.36 m (the claim of
/// the IONO_VERTICAL_M doc): the smallest sigma the model can give with
/// every term at its floor, at zenith (the smallest elevation terms).
#[test]
fn sigma_floors_keep_the_modelled_sigma_above_0_36_m() {
    const SIGMA_FLOOR_M: f64 = 0.36;
    let mut c = Config::default();
    c.sigma_model.ura_m = URA_M.min;
    c.sigma_model.iono_vertical_m = IONO_VERTICAL_M.min;
    c.sigma_model.noise_m = NOISE_M.min;
    c.sigma_model.min_elevation_rad = MIN_ELEVATION_RAD.max;
    assert_eq!(c.validate(), Ok(()));
    for el_deg in [0.0f64, 5.0, 10.0, 30.0, 60.0, 90.0] {
        let s = c.sigma_model.sigma_m(el_deg.to_radians());
        assert!(s >= SIGMA_FLOOR_M, "el {el_deg}: {s}");
    }
    // Independent: the root sum square of the floors and the DO-229D
    // zenith tropo (0.12 m) and multipath (0.13 m + 0.53 e^-9) terms.
    let zenith = (0.3f64.powi(2)
        + 0.1f64.powi(2)
        + 0.12f64.powi(2)
        + (0.13 + 0.53 * (-9.0f64).exp()).powi(2))
    .sqrt();
    const SIGMA_TOL_M: f64 = 1e-4;
    let z = c.sigma_model.sigma_m(core::f64::consts::FRAC_PI_2);
    assert!((z - zenith).abs() < SIGMA_TOL_M, "{z} vs {zenith}");
}

/// One `Configure` with Pfa = 1e-300 made a 160 m step on one of
/// 8 satellites pass. The default configuration excludes it; Pfa = 1e-300
/// is refused; and the all-in-view statistic of that epoch is indeed below
/// the 1e-300 threshold (the chi-square quantile, computed independently
/// of `validate` by the core's distribution code), so the bound is what
/// stands between that frame and a passed fault.
#[test]
fn pfa_1e_300_is_refused_and_160_m_is_excluded() {
    const STEP_M: f64 = 160.0;
    const FAULTY: usize = 2;
    let sky: Vec<(System, u8, f64, f64)> = crate::testutil::SKY8
        .iter()
        .enumerate()
        .map(|(i, &(az, el))| (System::Gps, i as u8 + 1, az, el))
        .collect();
    // A receiver at 45 N 10 E on the ellipsoid, GPS clock 100 m.
    let rx = crate::frames::geodetic_to_ecef(crate::frames::Geodetic {
        lat_rad: 45f64.to_radians(),
        lon_rad: 10f64.to_radians(),
        height_m: 0.0,
    });
    let clock = [100.0, 0.0, 0.0, 0.0, 0.0];
    let mut raim = Raim::<16>::new();
    let cfg = Config::default();
    for seed in 0..20 {
        let mut sats = range_epoch(
            rx,
            &sky,
            &clock,
            0.5,
            &mut Rng::new(seed),
            &[(FAULTY, STEP_M)],
        );
        // The default elevation model supplies the sigmas.
        for s in sats.iter_mut() {
            s.sigma_m = None;
        }
        let epoch = Epoch::ranges(seed as f64, &sats, None);
        let r = raim.process(&cfg, &epoch).unwrap();
        assert_eq!(
            r.decision,
            Decision::Excluded,
            "seed {seed}: {:?}",
            r.alarm_cause
        );
        assert_eq!(r.exclusions.len(), 1, "seed {seed}");
        assert_eq!(
            r.exclusions[0].id,
            SatId::new(System::Gps, FAULTY as u8 + 1)
        );
        assert!(!r.satellites[FAULTY].used);

        let evil = Config { pfa: 1e-300, ..cfg };
        assert_eq!(
            raim.process(&evil, &epoch).unwrap_err(),
            RaimError::OutOfRange {
                field: "pfa",
                value: 1e-300,
                min: 1e-9,
                max: 1e-2
            }
        );
        let t2 = crate::stats::dist::chi2_quantile_upper(1e-300, r.initial_test.dof).unwrap();
        assert!(
            r.initial_test.statistic < t2,
            "seed {seed}: D^2 {} T^2(1e-300) {t2}",
            r.initial_test.statistic
        );
    }
}

/// The initial result storage (what an epoch that never reached the PLs
/// leaves) holds unbounded protection levels, never 0.
#[test]
fn empty_result_has_unbounded_pls() {
    let r = crate::result::EpochResult::<16>::empty();
    assert_eq!(r.protection.hpl_m, f64::INFINITY);
    assert_eq!(r.protection.vpl_m, f64::INFINITY);
    assert!(!r.pl_available);
}
