//! The snapshot monitor end to end, through `Raim::process`.
extern crate std;
use crate::config::Config;
use crate::config::{AlertLimits, FiRule, Phase};
use crate::error::RaimError;
use crate::measurement::{Epoch, LinearObservation, RangeObservation, SatId, System};
use crate::monitor::Raim;
use crate::result::Decision;
use crate::snapshot::fde::AlarmCause;
use crate::testutil::{
    at_stat, linear_epoch, range_epoch, Rng, CLOCKS_GE_M, RX_ECEF_M, SKY8, SKY_GE8,
};
use std::vec::Vec;

fn cfg() -> Config {
    Config::preset(Phase::Npa)
}

/// A 50 m step on one of 8 satellites (sigma 1 m) is detected,
/// identified and excluded, for every seed of noise tried and for each
/// rule; the subset passes. Sat 2 (row 1) is a mid-leverage satellite.
///
/// Verifies: SPEC-5
#[test]
fn fde_excludes_a_50_m_step_on_one_of_eight() {
    let mut raim = Raim::<16>::new();
    for rule in [FiRule::Mle, FiRule::LraimFlat, FiRule::default()] {
        let c = Config { rule, ..cfg() };
        for seed in 0..50 {
            let sats = linear_epoch(&SKY8, 1.0, &mut Rng::new(seed), &[(1, 50.0)]);
            let r = raim
                .process(&c, &Epoch::linear(seed as f64, &sats))
                .unwrap();
            assert!(r.initial_test.alarm(), "seed {seed}: {:?}", r.initial_test);
            assert_eq!(
                r.decision,
                Decision::Excluded,
                "seed {seed} {rule:?}: {:?}",
                r.alarm_cause
            );
            assert_eq!(r.exclusions.len(), 1);
            let e = r.exclusions[0];
            assert_eq!(e.id, SatId::new(System::Gps, 2));
            assert!(e.before.statistic > e.before.threshold);
            assert!(e.after.statistic < e.after.threshold);
            assert_eq!(e.after.dof, 3);
            // The bias estimate is the 50 m step within 5 sigma of its
            // estimation noise (1 m / sqrt(S_ii)).
            let s = r.satellites[1];
            assert!(
                (e.bias_m - 50.0).abs() < 5.0 / s.s_ii.sqrt(),
                "{}",
                e.bias_m
            );
            assert!(!s.used && r.satellites.iter().filter(|s| s.used).count() == 7);
            assert!(r.detection_available && r.exclusion_available);
        }
    }
}

/// Two simultaneous faults (60 m and -45 m) on 10 satellites: both are
/// excluded, one after the other, and the final subset passes.
///
/// Verifies: SPEC-5
#[test]
fn fde_excludes_two_faults() {
    let sky10: Vec<(f64, f64)> = SKY8
        .iter()
        .copied()
        .chain([(120.0, 70.0), (280.0, 65.0)])
        .collect();
    let mut raim = Raim::<16>::new();
    for seed in 0..30 {
        let sats = linear_epoch(
            &sky10,
            1.0,
            &mut Rng::new(100 + seed),
            &[(2, 60.0), (5, -45.0)],
        );
        let r = raim.process(&cfg(), &Epoch::linear(0.0, &sats)).unwrap();
        assert_eq!(
            r.decision,
            Decision::Excluded,
            "seed {seed}: {:?} {:?}",
            r.alarm_cause,
            r.exclusions
        );
        let mut ids: Vec<u8> = r.exclusions.iter().map(|e| e.id.prn).collect();
        ids.sort();
        assert_eq!(ids, [3, 6], "seed {seed}");
        // One exclusion cannot explain two faults, so FDE finds the
        // pair in closed form (docs/CORE.md); the subset passes.
        assert!(!r.exclusions[1].after.alarm());
        for e in &r.exclusions {
            assert_eq!(e.before, r.initial_test);
        }
        // The joint bias estimates recover the injected 60 m and -45 m
        // within 5 sigma of their estimation noise.
        for e in &r.exclusions {
            let truth = if e.id.prn == 3 { 60.0 } else { -45.0 };
            assert!((e.bias_m - truth).abs() < 5.0 / 0.3f64.sqrt(), "{e:?}");
        }
        assert_eq!(r.test.dof, 4);
    }
}

/// With no fault, 1000 noise draws give no exclusion at Pfa 3.3e-7.
///
/// Verifies: SPEC-3
#[test]
fn clean_epochs_pass() {
    let mut raim = Raim::<16>::new();
    for seed in 0..1000 {
        let sats = linear_epoch(&SKY8, 1.0, &mut Rng::new(seed), &[]);
        let r = raim.process(&cfg(), &Epoch::linear(0.0, &sats)).unwrap();
        assert_eq!(r.decision, Decision::Ok, "seed {seed}");
        assert!(r.exclusions.is_empty() && r.identified.is_none());
    }
}

/// Slope PLs checked against a brute-force computation: for each
/// satellite, the bias that gives non-centrality lambda_md,
/// b_i = sqrt(lambda / S_ii), pushed through a dense nalgebra
/// least-squares solve (normal equations, independent of the QR path),
/// gives a horizontal error whose maximum over i is the HPL.
///
/// Verifies: SPEC-6
#[test]
fn protection_levels_match_brute_force_worst_bias() {
    use nalgebra::{DMatrix, DVector};
    let mut raim = Raim::<16>::new();
    let sats = linear_epoch(&SKY8, 1.0, &mut Rng::new(7), &[]);
    let r = raim.process(&cfg(), &Epoch::linear(0.0, &sats)).unwrap();
    let n = sats.len();
    let mut h = DMatrix::zeros(n, 4);
    for (i, s) in sats.iter().enumerate() {
        for k in 0..3 {
            h[(i, k)] = -s.los_enu[k];
        }
        h[(i, 3)] = 1.0;
    }
    let a = (h.transpose() * &h).try_inverse().unwrap() * h.transpose();
    let s_mat = DMatrix::identity(n, n) - &h * &a;
    let (mut hpl, mut vpl) = (0.0f64, 0.0f64);
    for i in 0..n {
        let b = (r.lambda_md / s_mat[(i, i)]).sqrt();
        let mut f = DVector::zeros(n);
        f[i] = b;
        let dx = &a * f;
        hpl = hpl.max((dx[0] * dx[0] + dx[1] * dx[1]).sqrt());
        vpl = vpl.max(dx[2].abs());
    }
    // 1e-9 m in f64. In f32 the slopes carry eps x cond(H)^2 through
    // S_ii and the gains (docs/CORE.md "Precision"): 1.2e-6 m measured on
    // this 8 m HPL, 1e-5 m stated.
    const PL_TOL_M: f64 = at_stat(1e-9, 1e-5);
    assert!(
        (r.protection.hpl_m - hpl).abs() < PL_TOL_M,
        "{} {hpl}",
        r.protection.hpl_m
    );
    assert!(
        (r.protection.vpl_m - vpl).abs() < PL_TOL_M,
        "{} {vpl}",
        r.protection.vpl_m
    );
    // The 1-sigma accuracy is the diagonal of (H^T H)^-1.
    let cov = (h.transpose() * &h).try_inverse().unwrap();
    // 1e-12 m in f64; in f32 a few eps of a metre-sized sigma, 1e-6 m.
    const SIGMA_TOL_M: f64 = at_stat(1e-12, 1e-6);
    for k in 0..3 {
        let (got, want) = (r.sigma_enu_m[k], cov[(k, k)].sqrt());
        assert!((got - want).abs() < SIGMA_TOL_M, "{k}: {got} vs {want}");
    }
    // An alert limit below the HPL makes the epoch unavailable, not
    // alarmed: the smallest HAL the bounds allow (40 m), with 10 m sigmas.
    let tight = Config {
        alert: AlertLimits {
            hal_m: 40.0,
            val_m: None,
        },
        ..cfg()
    };
    let noisy = linear_epoch(&SKY8, 10.0, &mut Rng::new(7), &[]);
    let r2 = raim.process(&tight, &Epoch::linear(0.0, &noisy)).unwrap();
    assert!(r2.protection.hpl_m > 40.0, "{}", r2.protection.hpl_m);
    assert_eq!(r2.decision, Decision::Unavailable);
    assert!(!r2.pl_available);
}

/// Gauss-Newton from the Earth's centre recovers a receiver and two
/// clocks (GPS + Galileo) from noise-free pseudoranges.
///
/// Verifies: SPEC-1
#[test]
fn gauss_newton_recovers_position_and_clocks() {
    let (rx, clock, sky) = (RX_ECEF_M, CLOCKS_GE_M, SKY_GE8);
    let sats = range_epoch(rx, &sky, &clock, 1.0, &mut Rng::new(1), &[]);
    // Remove the noise to test the solver alone.
    let clean: Vec<RangeObservation> = range_epoch(rx, &sky, &clock, 0.0, &mut Rng::new(1), &[])
        .into_iter()
        .map(|o| RangeObservation {
            sigma_m: Some(1.0),
            ..o
        })
        .collect();
    let mut raim = Raim::<16>::new();
    let r = raim
        .process(&cfg(), &Epoch::ranges(0.0, &clean, None))
        .unwrap();
    let p = r.position_ecef_m.unwrap();
    const POSITION_TOL_M: f64 = 1e-6;
    for k in 0..3 {
        assert!((p[k] - rx[k]).abs() < POSITION_TOL_M, "{p:?}");
    }
    assert!((r.clock_m[0].unwrap() - clock[0]).abs() < POSITION_TOL_M);
    assert!((r.clock_m[1].unwrap() - clock[1]).abs() < POSITION_TOL_M);
    assert_eq!(r.test.dof, 8 - 5);
    assert_eq!(r.decision, Decision::Ok);
    // With noise and a 50 m step on Galileo 8, FDE excludes it and
    // re-solves the position by Gauss-Newton on the subset.
    let mut faulty = sats.clone();
    faulty[6].pseudorange_m += 50.0;
    let r = raim
        .process(&cfg(), &Epoch::ranges(0.0, &faulty, Some(rx)))
        .unwrap();
    assert_eq!(r.decision, Decision::Excluded, "{:?}", r.alarm_cause);
    assert_eq!(r.exclusions[0].id, SatId::new(System::Galileo, 8));
    let p = r.position_ecef_m.unwrap();
    let err = ((p[0] - rx[0]).powi(2) + (p[1] - rx[1]).powi(2) + (p[2] - rx[2]).powi(2)).sqrt();
    assert!(err < 10.0, "{err}");
}

fn sample() -> Vec<LinearObservation> {
    linear_epoch(&SKY8, 1.0, &mut Rng::new(3), &[])
}

/// Every error variant is reachable from input and carries the
/// offending value.
///
/// Verifies: WIRE-TooFewSatellites, WIRE-DuplicateSatellite, WIRE-NonPositiveSigma, WIRE-NoConvergence, WIRE-InvalidDof
#[test]
fn bad_input_gets_typed_errors() {
    let mut raim = Raim::<8>::new();
    let c = cfg();
    // NotFinite
    let mut s = sample();
    s[3].residual_m = f64::NAN;
    match raim.process(&c, &Epoch::linear(0.0, &s)) {
        Err(RaimError::NotFinite {
            field: "residual_m",
            index: 3,
            value,
        }) => assert!(value.is_nan()),
        other => panic!("{other:?}"),
    }
    let mut s = sample();
    s[0].los_enu[1] = f64::INFINITY;
    assert!(matches!(
        raim.process(&c, &Epoch::linear(0.0, &s)),
        Err(RaimError::NotFinite {
            field: "los_enu",
            index: 0,
            ..
        })
    ));
    assert!(matches!(
        raim.process(&c, &Epoch::linear(f64::NAN, &sample())),
        Err(RaimError::NotFinite {
            field: "time_s",
            ..
        })
    ));
    // DuplicateSatellite
    let mut s = sample();
    s[5].id = s[2].id;
    assert_eq!(
        raim.process(&c, &Epoch::linear(0.0, &s)).unwrap_err(),
        RaimError::DuplicateSatellite {
            system: System::Gps,
            prn: 3,
            first: 2,
            second: 5
        }
    );
    // TooFewSatellites: 4 satellites, 4 unknowns.
    let s = sample();
    assert_eq!(
        raim.process(&c, &Epoch::linear(0.0, &s[..4])).unwrap_err(),
        RaimError::TooFewSatellites { have: 4, need: 5 }
    );
    // RankDeficient: every line of sight identical.
    let mut s = sample();
    for o in s.iter_mut() {
        o.los_enu = [0.0, 0.6, 0.8];
    }
    assert!(matches!(
        raim.process(&c, &Epoch::linear(0.0, &s)),
        Err(RaimError::RankDeficient { .. })
    ));
    // NonPositiveSigma
    let mut s = sample();
    s[4].sigma_m = Some(-1.0);
    assert_eq!(
        raim.process(&c, &Epoch::linear(0.0, &s)).unwrap_err(),
        RaimError::NonPositiveSigma {
            index: 4,
            sigma_m: -1.0
        }
    );
    // CapacityExceeded
    let sky9: Vec<(f64, f64)> = SKY8.iter().copied().chain([(10.0, 10.0)]).collect();
    let s = linear_epoch(&sky9, 1.0, &mut Rng::new(1), &[]);
    assert_eq!(
        raim.process(&c, &Epoch::linear(0.0, &s)).unwrap_err(),
        RaimError::CapacityExceeded {
            have: 9,
            capacity: 8
        }
    );
    // OutOfRange: configuration and a non-unit line of sight.
    let bad = Config { pfa: 0.7, ..c };
    assert_eq!(
        raim.process(&bad, &Epoch::linear(0.0, &sample()))
            .unwrap_err(),
        RaimError::OutOfRange {
            field: "pfa",
            value: 0.7,
            min: 1e-9,
            max: 1e-2
        }
    );
    let mut s = sample();
    s[1].los_enu = [0.0, 0.0, 3.0];
    assert!(matches!(
        raim.process(&c, &Epoch::linear(0.0, &s)),
        Err(RaimError::OutOfRange {
            field: "los_enu_norm",
            ..
        })
    ));
    // NoConvergence: one Gauss-Newton iteration from the Earth's centre.
    let rx = [4_000_000.0, 3_000_000.0, 3_900_000.0];
    let sky: Vec<(System, u8, f64, f64)> = SKY8
        .iter()
        .enumerate()
        .map(|(i, &(a, e))| (System::Gps, i as u8 + 1, a, e))
        .collect();
    let ranges = range_epoch(rx, &sky, &[0.0; 5], 1.0, &mut Rng::new(2), &[]);
    let one = Config {
        max_iterations: 1,
        ..c
    };
    assert!(matches!(
        raim.process(&one, &Epoch::ranges(0.0, &ranges, None)),
        Err(RaimError::NoConvergence { iterations: 1, .. })
    ));
    // OutOfRange on a satellite at the receiver.
    let mut at_rx = ranges.clone();
    at_rx[0].position_m = rx;
    assert!(matches!(
        raim.process(&c, &Epoch::ranges(0.0, &at_rx, Some(rx))),
        Err(RaimError::OutOfRange {
            field: "range_m",
            ..
        })
    ));
    // InvalidDof: a threshold for dof 0 or beyond the capacity.
    assert_eq!(
        raim.thresholds(&c, 0).unwrap_err(),
        RaimError::InvalidDof { dof: 0, max: 7 }
    );
    assert_eq!(
        raim.thresholds(&c, 8).unwrap_err(),
        RaimError::InvalidDof { dof: 8, max: 7 }
    );
}

/// With only one redundant measurement, a fault is detected but cannot
/// be excluded: the result says so.
///
/// Verifies: SPEC-5
#[test]
fn alarm_without_exclusion_capability() {
    let mut raim = Raim::<8>::new();
    let s = linear_epoch(&SKY8[..5], 1.0, &mut Rng::new(1), &[(2, 80.0)]);
    let r = raim.process(&cfg(), &Epoch::linear(0.0, &s)).unwrap();
    assert!(r.initial_test.alarm(), "{:?}", r.initial_test);
    assert_eq!(r.decision, Decision::Alarm);
    assert_eq!(r.alarm_cause, Some(AlarmCause::NoRedundancy));
    assert!(r.exclusions.is_empty());
    assert!(r.detection_available && !r.exclusion_available);
}

/// An engine reused across epochs gives, bit for bit, what a fresh engine
/// gives on each epoch (the outcome's two solutions are no
/// longer zero-filled between epochs, so every solve must overwrite every
/// field it is read through). The epochs alternate sizes (10, 8, 9 rows),
/// forms (linearised, pseudoranges with GPS + Galileo and with GPS alone),
/// and outcomes (Ok, one exclusion, a pair, an alarm), so that a longer
/// earlier solution leaves rows beyond a shorter later one. Compared
/// through `Debug`, which prints every float's shortest round-trip form
/// (equal strings are equal bits, NaN and -0.0 included).
#[test]
fn a_reused_engine_equals_a_fresh_one() {
    let sky10: Vec<(f64, f64)> = SKY8
        .iter()
        .copied()
        .chain([(120.0, 70.0), (280.0, 65.0)])
        .collect();
    let (rx, clock) = (RX_ECEF_M, CLOCKS_GE_M);
    let ranges_sky: Vec<_> = SKY_GE8
        .iter()
        .copied()
        .chain([(System::Galileo, 19, 150.0, 15.0)])
        .collect();
    let gps_only: Vec<_> = ranges_sky
        .iter()
        .copied()
        .filter(|s| s.0 == System::Gps)
        .chain([
            (System::Gps, 22, 40.0, 25.0),
            (System::Gps, 25, 200.0, 65.0),
        ])
        .collect();
    let c = cfg();
    let mut reused = Raim::<16>::new();
    let mut decisions = Vec::new();
    for seed in 0..12u64 {
        let mut rng = Rng::new(500 + seed);
        let faults: &[(usize, f64)] = match seed % 4 {
            0 => &[],
            1 => &[(2, 60.0)],
            2 => &[(2, 60.0), (5, -45.0)],
            _ => &[(1, 8.0)],
        };
        let lin10 = linear_epoch(&sky10, 1.0, &mut rng, faults);
        let lin8 = linear_epoch(&SKY8, 1.0, &mut rng, faults);
        let rng9 = range_epoch(rx, &ranges_sky, &clock, 1.0, &mut rng, faults);
        let rng_g = range_epoch(rx, &gps_only, &clock, 1.0, &mut rng, faults);
        let apriori = Some(rx.map(|v| v + 50.0));
        let epochs = [
            Epoch::linear(seed as f64, &lin10),
            Epoch::ranges(seed as f64, &rng9, apriori),
            Epoch::linear(seed as f64, &lin8),
            Epoch::ranges(seed as f64, &rng_g, apriori),
        ];
        for e in &epochs {
            let a = reused.process(&c, e);
            let b = Raim::<16>::new().process(&c, e);
            assert_eq!(std::format!("{a:?}"), std::format!("{b:?}"), "seed {seed}");
            if let Ok(r) = a {
                decisions.push(r.decision);
            }
        }
    }
    // The sequence exercises the paths it is meant to.
    for d in [Decision::Ok, Decision::Excluded] {
        assert!(decisions.contains(&d), "{d:?} missing: {decisions:?}");
    }
}

/// FDE's first ranking comes from the per-satellite output:
/// for every rule, on 300 noisy 8- and 10-satellite epochs with 0-2
/// faults, it is bit for bit `lraim::rank`'s best, and `None` when not
/// asked for.
///
/// Verifies: SPEC-4.1
#[test]
fn per_satellite_ranking_equals_rank() {
    use crate::real::Real;
    use crate::snapshot::{lraim, per_satellite};
    use crate::solve::solve;
    let sky10: Vec<(f64, f64)> = SKY8
        .iter()
        .copied()
        .chain([(120.0, 70.0), (280.0, 65.0)])
        .collect();
    let mut ranked = 0;
    for rule in [FiRule::Mle, FiRule::LraimFlat, FiRule::default()] {
        let c = Config { rule, ..cfg() };
        for seed in 0..100u64 {
            let sky: &[(f64, f64)] = if seed % 2 == 0 { &SKY8 } else { &sky10 };
            let faults: &[(usize, f64)] = match seed % 3 {
                0 => &[],
                1 => &[(1, 40.0)],
                _ => &[(1, 40.0), (4, -30.0)],
            };
            let sats = linear_epoch(sky, 1.0, &mut Rng::new(900 + seed), faults);
            let mut mask = [true; 16];
            for m in mask.iter_mut().skip(sats.len()) {
                *m = false;
            }
            let sol = solve::<16>(&c, &Epoch::linear(0.0, &sats), &mask).unwrap();
            let mut out = heapless::Vec::new();
            let got = per_satellite(&c, &sol, &mut out, true);
            let want = lraim::rank(&sol.parity, c.rule, c.min_s_ii).0;
            let bits = |x: Option<lraim::Candidate<crate::real::Stat>>| {
                x.map(|c| {
                    (
                        c.row,
                        c.w.to_f64().to_bits(),
                        c.bias_sigma.to_f64().to_bits(),
                        c.score.to_f64().to_bits(),
                    )
                })
            };
            assert_eq!(bits(got), bits(want), "{rule:?} seed {seed}");
            ranked += usize::from(want.is_some());
            assert!(per_satellite(&c, &sol, &mut out, false).is_none());
        }
    }
    assert!(ranked > 250, "{ranked}");
}

/// Thresholds off the precomputed table (pfa 1e-4, pwe 2e-3) are computed
/// on first use: T^2 and the wrong-exclusion quantile equal statrs'
/// chi-square quantiles (1e-9 relative); a new pmd at the same pfa keeps
/// T^2 and recomputes lambda, larger for a smaller pmd; a dof outside
/// 1..N is `InvalidDof` naming it.
#[test]
fn thresholds_off_the_table_match_statrs() {
    use crate::snapshot::detection::Thresholds;
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    let q = |p: f64, dof: usize| ChiSquared::new(dof as f64).unwrap().inverse_cdf(1.0 - p);
    let mut th = Thresholds::<16>::empty();
    let (t2, lambda_2) = th.get(1e-4, 1e-2, 5).unwrap();
    assert!((t2 - q(1e-4, 5)).abs() <= 1e-9 * t2, "{t2}");
    let (t2_again, lambda_3) = th.get(1e-4, 1e-3, 5).unwrap();
    assert_eq!(t2_again, t2);
    assert!(
        lambda_3 > lambda_2 && lambda_2 > 0.0,
        "{lambda_2} {lambda_3}"
    );
    let we = th.wrong_exclusion(2e-3, 4).unwrap();
    assert!((we - q(2e-3, 4)).abs() <= 1e-9 * we, "{we}");
    for dof in [0, 16] {
        assert!(matches!(
            th.get(1e-4, 1e-3, dof),
            Err(RaimError::InvalidDof { dof: d, .. }) if d as usize == dof
        ));
        assert!(matches!(
            th.wrong_exclusion(2e-3, dof),
            Err(RaimError::InvalidDof { dof: d, .. }) if d as usize == dof
        ));
    }
}

/// The snapshot engine on its own equals the monitor's snapshot path
/// (same decision, statistic and exclusions); turning the warm start
/// off drops the last fix, so with it back on the next epoch starts cold
/// and equals a fresh engine's bit for bit, where an engine that kept the
/// fix starts from it (another iteration count or position bits).
#[test]
fn snapshot_engine_alone_and_warm_start_off() {
    use crate::snapshot::Snapshot;
    let c = cfg();
    let sats = linear_epoch(&SKY8, 1.0, &mut Rng::new(3), &[(1, 50.0)]);
    let e = Epoch::linear(0.0, &sats);
    let alone = Snapshot::<16>::new().process(&c, &e).unwrap();
    let full = Raim::<16>::new().process(&c, &e).unwrap();
    assert_eq!(alone.decision, full.decision);
    assert_eq!(
        alone.test.statistic.to_bits(),
        full.test.statistic.to_bits()
    );
    assert_eq!(alone.exclusions, full.exclusions);
    let ranges = range_epoch(
        RX_ECEF_M,
        &SKY_GE8,
        &CLOCKS_GE_M,
        1.0,
        &mut Rng::new(5),
        &[],
    );
    let first = Epoch::ranges(0.0, &ranges, Some(RX_ECEF_M));
    let later = Epoch::ranges(1.0, &ranges, Some(RX_ECEF_M));
    let mut warm = Snapshot::<16>::new();
    warm.set_warm_start(true);
    warm.process(&c, &first).unwrap();
    let mut kept = Snapshot::<16>::new();
    kept.set_warm_start(true);
    kept.process(&c, &first).unwrap();
    warm.set_warm_start(false);
    warm.set_warm_start(true);
    let a = warm.process(&c, &later).unwrap();
    let b = Snapshot::<16>::new().process(&c, &later).unwrap();
    assert_eq!(a.position_ecef_m, b.position_ecef_m);
    assert_eq!(a.iterations, b.iterations);
    let k = kept.process(&c, &later).unwrap();
    assert!(
        k.iterations != b.iterations || k.position_ecef_m != b.position_ecef_m,
        "{} {}",
        k.iterations,
        b.iterations
    );
}
