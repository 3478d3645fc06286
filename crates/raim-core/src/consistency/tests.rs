//! The model check: its window arithmetic against an independent
//! computation, its false-alarm rate against the allocation with
//! residuals drawn from the model, and the red-team case of issue 35
//! (errors 5x the model sigma; 1 m of noise against an ISM at its floors).
extern crate std;
use std::vec::Vec;

use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::*;
use crate::araim::{AraimConfig, FdeLimits, Ism, Monitor, SatIsm};
use crate::config::Phase;
use crate::measurement::{Epoch, LinearObservation, SatId, System};
use crate::monitor::Raim;
use crate::result::Decision;
use crate::testutil::{linear_epoch, Rng, SKY8};
use crate::Config;

/// chi2 survival function from statrs (independent of `stats::dist`).
fn sf(q: f64, dof: u32) -> f64 {
    1.0 - ChiSquared::new(f64::from(dof)).unwrap().cdf(q)
}

fn cfg_of(spacing_s: f64, window: usize, p_fa_per_hour: f64) -> ModelCheckConfig {
    ModelCheckConfig {
        spacing_s,
        window,
        p_fa_per_hour,
    }
}

/// The spacing, the window and the test statistic, offer by offer, against
/// a plain list of the samples taken (the last `window` of them summed and
/// tested with statrs' chi-square), and the allocation written out.
///
/// Verifies: SAFE-MODEL
#[test]
fn window_arithmetic_matches_an_independent_computation() {
    let c = cfg_of(10.0, 3, 1e-3);
    // floor(3600 / 10) + 1 = 361 evaluations an hour at most.
    assert_eq!(c.evaluations_per_hour(), 361.0);
    assert_eq!(c.p_fa_per_evaluation(), 1e-3 / 361.0);
    let offers: [(f64, f64, u32); 9] = [
        (0.0, 3.0, 4),
        (4.0, 50.0, 4),  // 4 s after the last sample: skipped
        (10.0, 7.5, 5),  // 10 s: taken (spacing reached exactly)
        (15.0, 1.0, 4),  // skipped
        (20.5, 2.25, 3), // taken
        (30.5, 12.0, 6), // taken: the window is full (3)
        (41.0, 0.5, 2),  // taken: the first sample leaves the window
        (50.0, 9.0, 4),  // 9 s: skipped
        (61.0, 30.0, 4), // taken
    ];
    let mut mc = ModelCheck::<4>::new();
    let mut taken: Vec<(f64, f64, u32)> = Vec::new();
    let mut last_taken: Option<f64> = None;
    for &(t, q, dof) in &offers {
        let out = mc.offer(&c, t, q, dof).unwrap();
        let take = last_taken.is_none_or(|l| t - l >= 10.0);
        if !take {
            assert_eq!(out, Offer::Skipped, "t = {t}");
            continue;
        }
        last_taken = Some(t);
        taken.push((t, q, dof));
        let window = &taken[taken.len().saturating_sub(3)..];
        let q_sum: f64 = window.iter().map(|s| s.1).sum();
        let dof_sum: u32 = window.iter().map(|s| s.2).sum();
        let Offer::Evaluated(e) = out else {
            panic!("t = {t}: not evaluated");
        };
        assert_eq!(e.samples, window.len());
        assert!((e.q_sum - q_sum).abs() <= 1e-12 * q_sum);
        assert_eq!(e.dof_sum, dof_sum);
        let p = sf(q_sum, dof_sum);
        assert!(
            (e.p_value - p).abs() <= 1e-9 * p.max(1e-300),
            "t = {t}: p {} against statrs {p}",
            e.p_value
        );
        assert_eq!(e.rejects, p < c.p_fa_per_evaluation());
        let held: Vec<f64> = mc.samples().map(|s| s.time_s).collect();
        let want: Vec<f64> = window.iter().map(|s| s.0).collect();
        assert_eq!(held, want);
    }
    assert_eq!(taken.len(), 6);
    assert_eq!(mc.evaluations(), 6);
    // The last window is 12 + 0.5 + 30 = 42.5 at 12 dof: p = 2.7e-5, above
    // the 2.8e-6 per evaluation, and no earlier window is further out.
    assert!(!mc.broken());
    assert_eq!(mc.rejections(), 0);
}

/// Bad input is typed, carries the offending value, and changes nothing:
/// time going backwards (or standing still), NaN, a negative q, dof 0 or
/// above the largest, and every bad configuration field.
///
/// Verifies: SAFE-MODEL
#[test]
fn bad_input_is_refused_and_leaves_the_state_alone() {
    let c = cfg_of(10.0, 3, 1e-3);
    let mut mc = ModelCheck::<4>::new();
    mc.offer(&c, 100.0, 3.0, 4).unwrap();
    mc.offer(&c, 120.0, 5.0, 4).unwrap();
    let before = std::format!("{mc:?}");
    let refusals = [
        (
            mc.clone().offer(&c, 50.0, 1.0, 4),
            ModelCheckError::TimeNotIncreasing {
                time_s: 50.0,
                last_s: 120.0,
            },
        ),
        (
            mc.clone().offer(&c, 120.0, 1.0, 4),
            ModelCheckError::TimeNotIncreasing {
                time_s: 120.0,
                last_s: 120.0,
            },
        ),
        (
            mc.clone().offer(&c, 200.0, -1.0, 4),
            ModelCheckError::OutOfRange {
                field: "q",
                value: -1.0,
                min: 0.0,
                max: f64::INFINITY,
            },
        ),
        (
            mc.clone().offer(&c, 200.0, 1.0, 0),
            ModelCheckError::ZeroDof,
        ),
        (
            mc.clone().offer(&c, 200.0, 1.0, MAX_DOF + 1),
            ModelCheckError::DofOutOfRange {
                dof: MAX_DOF + 1,
                max: MAX_DOF,
            },
        ),
        (
            mc.clone().offer(&cfg_of(0.0, 3, 1e-3), 200.0, 1.0, 4),
            ModelCheckError::OutOfRange {
                field: "spacing_s",
                value: 0.0,
                min: SPACING_S.0,
                max: SPACING_S.1,
            },
        ),
        (
            mc.clone().offer(&cfg_of(10.0, 5, 1e-3), 200.0, 1.0, 4),
            ModelCheckError::WindowOutOfRange {
                window: 5,
                capacity: 4,
            },
        ),
        (
            mc.clone().offer(&cfg_of(10.0, 0, 1e-3), 200.0, 1.0, 4),
            ModelCheckError::WindowOutOfRange {
                window: 0,
                capacity: 4,
            },
        ),
        (
            mc.clone().offer(&cfg_of(10.0, 3, 1.0), 200.0, 1.0, 4),
            ModelCheckError::OutOfRange {
                field: "p_fa_per_hour",
                value: 1.0,
                min: P_FA_PER_HOUR.0,
                max: P_FA_PER_HOUR.1,
            },
        ),
    ];
    for (got, want) in refusals {
        assert_eq!(got, Err(want));
    }
    // NaN in each place (NaN != NaN, so matched by variant and field).
    for (t, q, s, p, field) in [
        (f64::NAN, 1.0, 10.0, 1e-3, "time_s"),
        (f64::INFINITY, 1.0, 10.0, 1e-3, "time_s"),
        (200.0, f64::NAN, 10.0, 1e-3, "q"),
        (200.0, 1.0, f64::NAN, 1e-3, "spacing_s"),
        (200.0, 1.0, 10.0, f64::NAN, "p_fa_per_hour"),
    ] {
        match mc.offer(&cfg_of(s, 3, p), t, q, 4) {
            Err(ModelCheckError::NotFinite { field: f, .. }) => assert_eq!(f, field),
            other => panic!("{field}: {other:?}"),
        }
    }
    assert_eq!(std::format!("{mc:?}"), before);
    // An infinite q is taken and rejects (fail safe).
    let Ok(Offer::Evaluated(e)) = mc.offer(&c, 200.0, f64::INFINITY, 4) else {
        panic!("infinite q not evaluated");
    };
    assert!(e.rejects && mc.broken());
}

/// Samples from a run of the snapshot monitor on `SKY8` (8 GPS, dof 4),
/// every `dt_s`, noise `noise_m` against a model sigma of `sigma_m`.
fn snapshot_run(
    mc: &mut ModelCheck<8>,
    c: &ModelCheckConfig,
    rng: &mut Rng,
    epochs: usize,
    dt_s: f64,
    noise_m: f64,
    sigma_m: f64,
) -> Vec<Evaluation> {
    let solver = Config::preset(Phase::Npa);
    let mut raim = Raim::<8>::new();
    let mut out = Vec::new();
    for k in 0..epochs {
        let t = k as f64 * dt_s;
        let mut sats = linear_epoch(&SKY8, noise_m, rng, &[]);
        for s in sats.iter_mut() {
            s.sigma_m = Some(sigma_m);
        }
        let r = raim.process(&solver, &Epoch::linear(t, &sats)).unwrap();
        // The snapshot test may alarm (5x noise): such epochs are not
        // offered; the check must still see the model is wrong.
        if let Some((q, dof)) = r.model_sample() {
            if let Offer::Evaluated(e) = mc.offer(c, t, q, dof).unwrap() {
                out.push(e);
            }
        }
    }
    out
}

/// Residuals drawn from the model, through the snapshot monitor: over
/// 4,000 independent windows (a fresh monitor each, 4 samples), the
/// count of full windows that reject matches the allocation, p_eval =
/// 0.1 / 7 per evaluation (spacing 600 s: 7 evaluations an hour), within
/// 4 binomial standard errors (4 sqrt(M p (1 - p)); seeded, so the count
/// is fixed, and 4 SE is the tolerance a fair test would pass with
/// probability 0.99994). Evaluations of the partial windows count as
/// well: each is tested at the same p_eval.
///
/// Verifies: SAFE-MODEL
#[test]
fn false_alarms_with_residuals_from_the_model_match_the_allocation() {
    let c = cfg_of(600.0, 4, 0.1);
    let p = c.p_fa_per_evaluation();
    assert_eq!(p, 0.1 / 7.0);
    let trials = 4000usize;
    let mut rng = Rng::new(35);
    let (mut evaluations, mut rejections) = (0usize, 0usize);
    for _ in 0..trials {
        let mut mc = ModelCheck::<8>::new();
        let ev = snapshot_run(&mut mc, &c, &mut rng, 4, 600.0, 1.0, 1.0);
        evaluations += ev.len();
        rejections += ev.iter().filter(|e| e.rejects).count();
    }
    // Every epoch offered (no alarm from a correct model at Pfa 3.3e-7 in
    // 16,000 epochs, with this seed) and every one a sample.
    assert_eq!(evaluations, 4 * trials);
    let n = evaluations as f64;
    let se = (n * p * (1.0 - p)).sqrt();
    let expected = n * p;
    std::eprintln!(
        "{rejections} rejections in {evaluations} evaluations, expected {expected:.1} +- {se:.1}"
    );
    assert!(
        (rejections as f64 - expected).abs() <= 4.0 * se,
        "{rejections} rejections in {evaluations} evaluations, expected {expected:.1} +- {se:.1}"
    );
}

/// The red-team ratio with the snapshot monitor: noise 1.5 m against a
/// sigma of 0.3 m (5x; 0.3 m is the smallest sigma an epoch may carry,
/// `config_bounds`), epochs every 30 s. The snapshot test alarms
/// on many epochs (not offered) and excludes on others; the samples it
/// delivers still reject within the window (the first `DEFAULT_WINDOW`
/// samples) at the default configuration (1e-6 per hour).
///
/// Verifies: SAFE-MODEL
#[test]
fn errors_five_times_the_model_sigma_are_rejected_within_the_window() {
    let c = ModelCheckConfig {
        window: DEFAULT_WINDOW,
        ..ModelCheckConfig::DEFAULT
    };
    let mut rng = Rng::new(5);
    let mut mc = ModelCheck::<8>::new();
    // Epochs every 30 s for two windows' worth of time.
    let epochs = (2.0 * DEFAULT_WINDOW as f64 * c.spacing_s / 30.0) as usize;
    let ev = snapshot_run(&mut mc, &c, &mut rng, epochs, 30.0, 1.5, 0.3);
    let first = ev.iter().position(|e| e.rejects);
    std::eprintln!(
        "5x: {} samples, first rejection at sample {first:?}, p {:?}",
        ev.len(),
        ev.iter().map(|e| e.p_value).collect::<Vec<_>>()
    );
    assert!(
        first.is_some_and(|k| k < DEFAULT_WINDOW),
        "first rejection at sample {first:?} of {}",
        ev.len()
    );
    assert!(mc.broken());
    // With the model right (noise 0.3 m), the same run declares nothing.
    let mut ok = ModelCheck::<8>::new();
    let ev = snapshot_run(&mut ok, &c, &mut Rng::new(5), epochs, 30.0, 0.3, 0.3);
    assert!(!ev.is_empty() && !ok.broken());
}

/// Ten satellites, five GPS and five Galileo (az, el in degrees).
const SKY_GE10: [(System, u8, f64, f64); 10] = [
    (System::Gps, 1, 10.0, 80.0),
    (System::Gps, 2, 80.0, 30.0),
    (System::Gps, 3, 170.0, 45.0),
    (System::Gps, 4, 250.0, 20.0),
    (System::Gps, 5, 320.0, 55.0),
    (System::Galileo, 1, 40.0, 25.0),
    (System::Galileo, 2, 120.0, 60.0),
    (System::Galileo, 3, 200.0, 65.0),
    (System::Galileo, 4, 290.0, 35.0),
    (System::Galileo, 5, 350.0, 15.0),
];

/// The ISM at the floors of the red-team case: sigma_URA 0.3 m,
/// sigma_URE 0.2 m (b_nom 0.5 m, P_sat 1e-5).
fn floor_ism() -> [SatIsm; 10] {
    SKY_GE10.map(|(system, prn, _, _)| SatIsm {
        id: SatId::new(system, prn),
        sigma_ura_m: 0.3,
        sigma_ure_m: 0.2,
        b_nom_m: 0.5,
        p_sat: 1e-5,
    })
}

/// The sky with Gaussian noise `noise_m` and a host sigma `sigma_m`.
fn ge_epoch(rng: &mut Rng, noise_m: f64, sigma_m: f64) -> [LinearObservation; 10] {
    SKY_GE10.map(|(system, prn, az, el)| LinearObservation {
        sigma_m: Some(sigma_m),
        ..LinearObservation::from_az_el(
            SatId::new(system, prn),
            f64::to_radians(az),
            f64::to_radians(el),
            noise_m * rng.normal(),
        )
    })
}

/// The accuracy fit equals an independent dense weighted least squares
/// (nalgebra, SVD of the whitened system) on the monitor's own geometry.
///
/// Verifies: SAFE-MODEL
#[test]
fn accuracy_fit_matches_a_dense_weighted_least_squares() {
    use nalgebra::{DMatrix, DVector};
    let entries = floor_ism();
    let ism = Ism::with(&[System::Gps, System::Galileo], 1e-4);
    let cfg = AraimConfig::default();
    let mut monitor = std::boxed::Box::new(Monitor::<f64, 16, 600>::new());
    let mut rng = Rng::new(9);
    for _ in 0..20 {
        let obs = ge_epoch(&mut rng, 0.3, 0.3);
        monitor
            .linear(&cfg, &ism, &entries[..], &obs, FdeLimits::UNLIMITED)
            .unwrap();
        let fit = monitor.accuracy_sample().unwrap();
        // Dense reference: C_acc = sigma_URE^2 + sigma^2 = 0.13 m^2 per
        // satellite (the observation's own sigma, module doc of
        // araim::monitor); rows -LOS (ENU, the ADD's sign) and a clock per
        // constellation.
        let w = 1.0 / (0.2f64 * 0.2 + 0.3 * 0.3).sqrt();
        let mut g = DMatrix::<f64>::zeros(10, 5);
        let mut y = DVector::<f64>::zeros(10);
        for (i, o) in obs.iter().enumerate() {
            for k in 0..3 {
                g[(i, k)] = -o.los_enu[k] * w;
            }
            g[(i, if o.id.system == System::Gps { 3 } else { 4 })] = w;
            y[i] = o.residual_m * w;
        }
        let x = g.clone().svd(true, true).solve(&y, 1e-12).unwrap();
        let q = (&y - &g * x).norm_squared();
        assert_eq!(fit.dof, 5);
        assert!((fit.q - q).abs() <= 1e-9 * q, "{} vs {q}", fit.q);
    }
}

/// The red-team case of issue 35 with ARAIM: noise 1 m against an ISM at
/// its floors (sigma_URA 0.3 m, sigma_URE 0.2 m) and a host sigma of 0.3 m
/// (so C_acc = 0.13 m^2, sigma 0.36 m: the errors are 2.8x it), 10
/// satellites G+E. Whatever ARAIM answers (it may exclude a constellation
/// and keep going), the model check declares the model broken within its
/// window at the default allocation; with noise at the model's own sigma
/// it declares nothing over the same run, and the mean of q / dof is 1
/// within 4 standard errors.
///
/// Verifies: SAFE-MODEL
#[test]
fn araim_red_team_noise_against_the_ism_floors_is_rejected_within_the_window() {
    let entries = floor_ism();
    let ism = Ism::with(&[System::Gps, System::Galileo], 1e-4);
    let cfg = AraimConfig::default();
    let c = ModelCheckConfig::DEFAULT;
    let run = |noise_m: f64, seed: u64, epochs: usize| {
        let mut monitor = std::boxed::Box::new(Monitor::<f64, 16, 600>::new());
        let mut mc = ModelCheck::<8>::new();
        let mut rng = Rng::new(seed);
        let (mut sum, mut dof, mut answered) = (0.0, 0u32, 0usize);
        for k in 0..epochs {
            let t = k as f64 * c.spacing_s;
            let obs = ge_epoch(&mut rng, noise_m, 0.3);
            let v = monitor
                .linear(&cfg, &ism, &entries[..], &obs, FdeLimits::UNLIMITED)
                .unwrap();
            if v.decision == Decision::Alarm {
                continue;
            }
            answered += 1;
            let f = monitor.accuracy_sample().unwrap();
            sum += f.q;
            dof += f.dof;
            mc.offer(&c, t, f.q, f.dof).unwrap();
        }
        (mc, sum, dof, answered)
    };
    let (mc, sum, dof, answered) = run(1.0, 2, DEFAULT_WINDOW);
    std::eprintln!(
        "red team: {answered} of {DEFAULT_WINDOW} answered, q {sum:.1} at {dof} dof, declared at {:?}",
        mc.broken_at_s()
    );
    assert!(answered > 0, "every epoch an alarm: nothing to check");
    assert!(mc.broken(), "not declared within {DEFAULT_WINDOW} samples");
    // The model right: 400 epochs, nothing declared; E[q] = dof.
    let (mc, sum, dof, answered) = run(0.36055512754639896, 3, 400);
    assert!(answered >= 390);
    assert!(!mc.broken());
    let se = (2.0 * f64::from(dof)).sqrt();
    assert!((sum - f64::from(dof)).abs() <= 4.0 * se, "{sum} vs {dof}");
}

/// The default window is the smallest with the design power: the full
/// window's test detects errors twice the model (q x 4) at 4 dof per
/// sample with probability >= `DESIGN_POWER` at W = `DEFAULT_WINDOW`, and
/// not at one sample fewer. The threshold from the crate's quantile, the
/// power from statrs (independent), and the quantile checked against
/// statrs too.
///
/// Verifies: SAFE-MODEL
#[test]
fn default_window_has_the_design_power() {
    use crate::stats::dist::chi2_quantile_upper;
    let c = ModelCheckConfig::DEFAULT;
    let p = c.p_fa_per_evaluation();
    let power = |w: usize| {
        let dof = 4 * w as u32;
        let t = chi2_quantile_upper(p, dof).unwrap();
        assert!((sf(t, dof) - p).abs() <= 1e-6 * p);
        sf(t / 4.0, dof)
    };
    let (below, at) = (power(DEFAULT_WINDOW - 1), power(DEFAULT_WINDOW));
    std::eprintln!("power: W - 1 {below:.4}, W {at:.4}");
    assert!(at >= DESIGN_POWER && below < DESIGN_POWER);
}

/// Residuals drawn from ARAIM's accuracy model (C_acc = sigma_URE^2 +
/// sigma^2 = 0.13 m^2 per satellite, the floors' ISM with a host sigma of
/// 0.3 m) through the ARAIM monitor and its accuracy fit: over 2,000
/// independent windows of 4 samples, the rejections match the allocation
/// p_eval = 0.1 / 7 within 4 binomial standard errors (as
/// `false_alarms_with_residuals_from_the_model_match_the_allocation`).
/// Epochs that ARAIM answers `Alarm` are not offered, as in service.
///
/// Verifies: SAFE-MODEL
#[test]
fn araim_false_alarms_with_residuals_from_c_acc_match_the_allocation() {
    let entries = floor_ism();
    let ism = Ism::with(&[System::Gps, System::Galileo], 1e-4);
    let cfg = AraimConfig::default();
    let c = cfg_of(600.0, 4, 0.1);
    let p = c.p_fa_per_evaluation();
    let sigma_acc_m = (0.2f64 * 0.2 + 0.3 * 0.3).sqrt();
    let mut monitor = std::boxed::Box::new(Monitor::<f64, 16, 600>::new());
    let mut rng = Rng::new(36);
    let (mut evaluations, mut rejections) = (0usize, 0usize);
    for _ in 0..2000 {
        let mut mc = ModelCheck::<8>::new();
        for k in 0..4 {
            let obs = ge_epoch(&mut rng, sigma_acc_m, 0.3);
            let v = monitor
                .linear(&cfg, &ism, &entries[..], &obs, FdeLimits::UNLIMITED)
                .unwrap();
            if v.decision == Decision::Alarm {
                continue;
            }
            let f = monitor.accuracy_sample().unwrap();
            if let Offer::Evaluated(e) = mc.offer(&c, k as f64 * 600.0, f.q, f.dof).unwrap() {
                evaluations += 1;
                rejections += usize::from(e.rejects);
            }
        }
    }
    let n = evaluations as f64;
    let se = (n * p * (1.0 - p)).sqrt();
    let expected = n * p;
    std::eprintln!(
        "ARAIM: {rejections} rejections in {evaluations} evaluations, expected {expected:.1} +- {se:.1}"
    );
    assert!(evaluations >= 7900);
    assert!((rejections as f64 - expected).abs() <= 4.0 * se);
}

/// The accuracy fit's refusals, each with its values: shapes with no
/// redundancy or beyond the capacity (`Geometry { n, m }`), a singular
/// normal matrix (two equal columns), a NaN C_acc (`NotFinite`) and a
/// C_acc that is 0, negative or infinite (`OutOfRange`). A well-posed
/// fit of 4 rows, 1 column with C_acc 1 is the sample variance sum:
/// y = 1, 2, 3, 6 about their mean 3 gives q = 4 + 1 + 0 + 9 = 14, dof 3.
#[test]
fn accuracy_fit_refusals_carry_their_values() {
    use crate::araim::subset::Geometry;
    use crate::consistency::fit::accuracy_fit;
    let mut geo = Geometry::<f64, 8>::empty();
    geo.n = 4;
    geo.m = 1;
    for (i, y) in [1.0, 2.0, 3.0, 6.0].into_iter().enumerate() {
        geo.g[i][0] = 1.0;
        geo.c_acc[i] = 1.0;
        geo.y[i] = y;
    }
    let fit = accuracy_fit(&geo).unwrap();
    assert_eq!(fit.dof, 3);
    assert!((fit.q - 14.0).abs() < 1e-12, "{fit:?}");
    let shape = |n: usize, m: usize| {
        let mut g = geo;
        g.n = n;
        g.m = m;
        accuracy_fit(&g)
    };
    for (n, m) in [
        (4, 4),
        (4, 0),
        (9, 1),
        (12, crate::measurement::MAX_STATES + 1),
    ] {
        assert_eq!(
            shape(n, m),
            Err(ModelCheckError::Geometry { n, m }),
            "{n} {m}"
        );
    }
    let mut twin = geo;
    twin.m = 2;
    for row in twin.g.iter_mut().take(4) {
        row[1] = row[0];
    }
    assert_eq!(
        accuracy_fit(&twin),
        Err(ModelCheckError::Geometry { n: 4, m: 2 })
    );
    let mut nan = geo;
    nan.c_acc[2] = f64::NAN;
    assert!(matches!(
        accuracy_fit(&nan),
        Err(ModelCheckError::NotFinite { field: "c_acc_m2", value }) if value.is_nan()
    ));
    for c in [0.0, -1.0, f64::INFINITY] {
        let mut bad = geo;
        bad.c_acc[1] = c;
        assert_eq!(
            accuracy_fit(&bad),
            Err(ModelCheckError::OutOfRange {
                field: "c_acc_m2",
                value: c,
                min: f64::MIN_POSITIVE,
                max: f64::MAX
            }),
            "{c}"
        );
    }
}

/// ARAIM's FDE limits and capacity: a 50 m fault (the model's sigma is
/// 0.36 m) fails the all-in-view test, and with `max_modes` 0 no
/// exclusion is attempted: an alarm reporting the monitored modes, with
/// nothing excluded. Ten satellites into an 8-satellite monitor are
/// refused with both counts.
#[test]
fn araim_fde_over_the_mode_limit_and_over_capacity() {
    use crate::araim::monitor::{Exclusion, MonitorError};
    use crate::araim::AraimError;
    let entries = floor_ism();
    let ism = Ism::with(&[System::Gps, System::Galileo], 1e-4);
    let cfg = AraimConfig::default();
    let mut obs = ge_epoch(&mut Rng::new(4), 0.3, 0.3);
    obs[3].residual_m += 50.0;
    let limits = FdeLimits {
        max_modes: 0,
        work_candidate_modes: usize::MAX,
    };
    let mut monitor = std::boxed::Box::new(Monitor::<f64, 16, 600>::new());
    let v = monitor
        .linear(&cfg, &ism, &entries[..], &obs, limits)
        .unwrap();
    assert_eq!(v.decision, Decision::Alarm);
    match v.exclusion {
        Exclusion::NotAttempted { monitored } => assert!(monitored >= 1, "{monitored}"),
        other => panic!("{other:?}"),
    }
    assert!(v.excluded.is_empty());
    let mut small = std::boxed::Box::new(Monitor::<f64, 8, 600>::new());
    assert_eq!(
        small
            .linear(&cfg, &ism, &entries[..], &obs, FdeLimits::UNLIMITED)
            .err(),
        Some(MonitorError::Araim(AraimError::CapacityExceeded {
            have: 10,
            capacity: 8
        }))
    );
}
