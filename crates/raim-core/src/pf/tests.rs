//! Tests of the `pf` monitor on synthetic epochs: determinism, f32 vs
//! f64, collapse, too few satellites, a satellite leaving view, a step
//! fault detected and isolated by all three filters, and the EKF against a
//! closed-form linear Kalman/least-squares result.

use super::*;
use crate::measurement::{RangeObservation, SatId, System};
use crate::real::Real;
use nalgebra::{DMatrix, DVector};

const RECEIVER_M: [f64; 3] = [3_512_000.0, 778_000.0, 5_248_000.0];
const CLOCK_M: f64 = 12_345.0;
const SIGMA_M: f64 = 3.0;

/// `n` GPS satellites at 20 200 km altitude spread in azimuth and
/// elevation above the receiver.
fn satellites(n: usize) -> [[f64; 3]; 12] {
    let r = RECEIVER_M;
    let norm = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
    let up = [r[0] / norm, r[1] / norm, r[2] / norm];
    let east = {
        let e = [-up[1], up[0], 0.0];
        let m = (e[0] * e[0] + e[1] * e[1]).sqrt();
        [e[0] / m, e[1] / m, 0.0]
    };
    let north = [
        up[1] * east[2] - up[2] * east[1],
        up[2] * east[0] - up[0] * east[2],
        up[0] * east[1] - up[1] * east[0],
    ];
    let mut out = [[0.0; 3]; 12];
    for (k, s) in out.iter_mut().enumerate().take(n) {
        let az = k as f64 * 2.4;
        let el = 0.3 + 1.1 * ((k * 7) % 12) as f64 / 12.0;
        let los = [
            el.cos() * az.sin() * east[0] + el.cos() * az.cos() * north[0] + el.sin() * up[0],
            el.cos() * az.sin() * east[1] + el.cos() * az.cos() * north[1] + el.sin() * up[1],
            el.cos() * az.sin() * east[2] + el.cos() * az.cos() * north[2] + el.sin() * up[2],
        ];
        // Range along los to a sphere of radius 26 560 km.
        let b = 2.0 * (los[0] * r[0] + los[1] * r[1] + los[2] * r[2]);
        let c = norm * norm - 26_560_000.0f64.powi(2);
        let d = (-b + (b * b - 4.0 * c).sqrt()) / 2.0;
        *s = [r[0] + d * los[0], r[1] + d * los[1], r[2] + d * los[2]];
    }
    out
}

/// One epoch: true range + clock + seeded Gaussian noise + `bias` on
/// satellite index `faulty`.
fn epoch(
    n: usize,
    k: usize,
    noise: &mut rng::PfRng,
    faulty: Option<(usize, f64)>,
) -> heapless::Vec<RangeObservation, 12> {
    let sats = satellites(n);
    let mut v = heapless::Vec::new();
    for (i, s) in sats.iter().enumerate().take(n) {
        let d = [
            s[0] - RECEIVER_M[0],
            s[1] - RECEIVER_M[1],
            s[2] - RECEIVER_M[2],
        ];
        let range = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let bias = match faulty {
            Some((f, b)) if f == i => b,
            _ => 0.0,
        };
        let pr = range + CLOCK_M + 0.5 * k as f64 + SIGMA_M * rng::normal(noise) + bias;
        v.push(RangeObservation {
            id: SatId::new(System::Gps, i as u8 + 1),
            pseudorange_m: pr,
            position_m: *s,
            sigma_m: Some(SIGMA_M),
        })
        .unwrap();
    }
    v
}

fn cfg() -> PfConfig {
    PfConfig {
        process: ProcessModel {
            position_m_per_sqrt_s: 1.0,
            clock_m_per_sqrt_s: 1.0,
            drift_m_s_per_sqrt_s: 0.1,
        },
        sigma_m: SIGMA_M,
        init_position_m: 10.0,
        init_clock_m: 10.0,
        init_drift_m_s: 1.0,
        mutation_m: 0.5,
        window: 8,
        pfa: 1e-3,
        ..PfConfig::default()
    }
}

fn error_m(p: &[f64; 3]) -> f64 {
    let d = [
        p[0] - RECEIVER_M[0],
        p[1] - RECEIVER_M[1],
        p[2] - RECEIVER_M[2],
    ];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// Runs `epochs` epochs with a step `bias_m` on satellite index 3 from
/// epoch `onset`; returns (first alarm epoch, isolated, alarms before onset,
/// RMS position error before onset).
fn scenario<T: Real, E: Estimator<T>>(
    seed: u64,
    epochs: usize,
    onset: usize,
    bias_m: f64,
) -> (Option<usize>, Option<SatId>, usize, f64) {
    let c = cfg();
    let mut m = std::boxed::Box::new(PfRaim::<T, E, 12>::new(seed));
    let mut noise = rng::seeded(seed ^ 0xABCD);
    let (mut first, mut iso, mut false_alarms, mut se, mut ne) = (None, None, 0, 0.0, 0);
    for k in 0..epochs {
        let f = (k >= onset).then_some((3, bias_m));
        let obs = epoch(8, k, &mut noise, f);
        let out = m.process(&c, k as f64, &obs).unwrap();
        if out.alarm && k < onset {
            false_alarms += 1;
        }
        if out.alarm && k >= onset && first.is_none() {
            first = Some(k);
            iso = out.isolated;
        }
        if k < onset && k >= 5 {
            se += error_m(&out.position_m.unwrap()).powi(2);
            ne += 1;
        }
    }
    (first, iso, false_alarms, (se / ne as f64).sqrt())
}

extern crate std;

/// A 40 m step on G4 from epoch 40: every filter stays quiet before it,
/// alarms within 10 epochs after it and isolates G4; the fault-free
/// position error is within 5 m RMS (sigma 3 m, 8 satellites).
///
/// Verifies: SPEC-10
#[test]
fn step_fault_detected_and_isolated_by_all_three() {
    const MAX_DELAY_EPOCHS: usize = 10;
    const RMS_BOUND_M: f64 = 5.0;
    let g4 = Some(SatId::new(System::Gps, 4));
    let runs = [
        ("ekf", scenario::<f64, Ekf<f64>>(1, 60, 40, 40.0)),
        ("pf", scenario::<f64, SirPf<f64, 300>>(1, 60, 40, 40.0)),
        ("gapf", scenario::<f64, GaPf<f64, 300>>(1, 60, 40, 40.0)),
    ];
    for (name, (first, iso, fa, rms)) in runs {
        std::println!("{name}: alarm {first:?} isolated {iso:?} false alarms {fa} rms {rms:.2} m");
    }
    for (name, (first, iso, fa, rms)) in runs {
        assert_eq!(fa, 0, "{name} false alarms");
        let first = first.unwrap_or_else(|| panic!("{name} never alarmed"));
        assert!(first < 40 + MAX_DELAY_EPOCHS, "{name} alarm at {first}");
        assert_eq!(iso, g4, "{name} isolated");
        assert!(rms < RMS_BOUND_M, "{name} rms {rms}");
    }
}

/// Same seed, bit-identical outputs; another seed, different particles.
#[test]
fn same_seed_same_output() {
    let run = |seed| {
        let c = cfg();
        let mut m = std::boxed::Box::new(PfRaim::<f64, GaPf<f64, 100>, 12>::new(seed));
        let mut noise = rng::seeded(99);
        let mut v = std::vec::Vec::new();
        for k in 0..15 {
            let out = m
                .process(&c, k as f64, &epoch(8, k, &mut noise, None))
                .unwrap();
            v.push((
                out.position_m.unwrap(),
                out.decision.to_bits(),
                out.n_eff.to_bits(),
            ));
        }
        v
    };
    assert_eq!(run(5), run(5));
    assert_ne!(run(5), run(6));
}

/// `restart` in place equals a fresh monitor: a monitor that ran 6 epochs
/// with a fault and an exclusion, restarted with seed 5, then fed 8 epochs
/// from t = 100 s, answers bit for bit like `new(5)` fed the same epochs.
#[test]
fn restart_equals_new() {
    let c = cfg();
    let fresh = |m: &mut PfRaim<f32, GaPf<f32, 100>, 12>| {
        let mut noise = rng::seeded(77);
        (0..8)
            .map(|k| {
                let out = m
                    .process(&c, 100.0 + k as f64, &epoch(8, k, &mut noise, None))
                    .unwrap();
                std::format!("{out:?}")
            })
            .collect::<std::vec::Vec<_>>()
    };
    let mut used = std::boxed::Box::new(PfRaim::<f32, GaPf<f32, 100>, 12>::new(9));
    let mut noise = rng::seeded(4);
    for k in 0..6 {
        let faulty = (k >= 2).then_some((3, 500.0));
        used.process(&c, k as f64, &epoch(8, k, &mut noise, faulty))
            .unwrap();
    }
    assert!(!used.excluded().is_empty());
    used.restart(5);
    assert!(used.excluded().is_empty());
    let mut new = std::boxed::Box::new(PfRaim::<f32, GaPf<f32, 100>, 12>::new(5));
    assert_eq!(fresh(&mut used), fresh(&mut new));
}

/// The compile-time engine (the device's static storage) runs exactly as
/// one made by `new(0)`, and `restart` makes it any seed's.
#[test]
fn empty_equals_new_zero() {
    let c = cfg();
    let run = |m: &mut PfRaim<f32, GaPf<f32, 100>, 12>| {
        let mut noise = rng::seeded(31);
        (0..8)
            .map(|k| {
                let faulty = (k >= 4).then_some((2, 300.0));
                let out = m
                    .process(&c, 10.0 + k as f64, &epoch(8, k, &mut noise, faulty))
                    .unwrap();
                std::format!("{out:?}")
            })
            .collect::<std::vec::Vec<_>>()
    };
    let mut empty = std::boxed::Box::new(PfRaim::<f32, GaPf<f32, 100>, 12>::EMPTY);
    let mut new = std::boxed::Box::new(PfRaim::<f32, GaPf<f32, 100>, 12>::new(0));
    assert_eq!(run(&mut empty), run(&mut new));
    let mut empty = std::boxed::Box::new(PfRaim::<f64, Ekf<f64>, 12>::EMPTY);
    empty.restart(6);
    let mut new = std::boxed::Box::new(PfRaim::<f64, Ekf<f64>, 12>::new(6));
    let mut a = std::vec::Vec::new();
    let mut b = std::vec::Vec::new();
    let mut noise_a = rng::seeded(5);
    let mut noise_b = rng::seeded(5);
    for k in 0..8 {
        a.push(std::format!(
            "{:?}",
            empty
                .process(&c, k as f64, &epoch(8, k, &mut noise_a, None))
                .unwrap()
        ));
        b.push(std::format!(
            "{:?}",
            new.process(&c, k as f64, &epoch(8, k, &mut noise_b, None))
                .unwrap()
        ));
    }
    assert_eq!(a, b);
}

/// f32 particle state against f64 on the same seed and data: the GA-PF
/// positions agree within 1.5 m (Monte Carlo spread: rounding changes some
/// resampling draws, so the clouds differ by about sigma/sqrt(N)), the EKF
/// within 1 cm.
#[test]
fn f32_state_matches_f64() {
    const TOL_PF_M: f64 = 1.5;
    const TOL_EKF_M: f64 = 0.01;
    fn run<T: Real, E: Estimator<T>>() -> std::vec::Vec<[f64; 3]> {
        let c = cfg();
        let mut m = std::boxed::Box::new(PfRaim::<T, E, 12>::new(11));
        let mut noise = rng::seeded(12);
        (0..30)
            .map(|k| {
                m.process(&c, k as f64, &epoch(8, k, &mut noise, None))
                    .unwrap()
                    .position_m
                    .unwrap()
            })
            .collect()
    }
    let check = |a: &[[f64; 3]], b: &[[f64; 3]], tol: f64, name: &str| {
        for (k, (p, q)) in a.iter().zip(b).enumerate().skip(5) {
            let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            assert!(d < tol, "{name} epoch {k}: {d} m");
        }
    };
    check(
        &run::<f64, GaPf<f64, 300>>(),
        &run::<f32, GaPf<f32, 300>>(),
        TOL_PF_M,
        "gapf",
    );
    check(
        &run::<f64, Ekf<f64>>(),
        &run::<f32, Ekf<f32>>(),
        TOL_EKF_M,
        "ekf",
    );
}

/// A gross inconsistency (+-100 km on alternate satellites) collapses the
/// main filter: it is reported, no position is given, and the next good
/// epoch gives a position again.
#[test]
fn collapse_is_reported_and_reinitialised() {
    let c = cfg();
    let mut m = std::boxed::Box::new(PfRaim::<f64, GaPf<f64, 100>, 12>::new(3));
    let mut noise = rng::seeded(4);
    for k in 0..5 {
        m.process(&c, k as f64, &epoch(8, k, &mut noise, None))
            .unwrap();
    }
    let mut bad = epoch(8, 5, &mut noise, None);
    for (i, o) in bad.iter_mut().enumerate() {
        o.pseudorange_m += if i % 2 == 0 { 1e5 } else { -1e5 };
    }
    let out = m.process(&c, 5.0, &bad).unwrap();
    assert!(out.main_collapsed);
    assert_eq!(out.position_m, None);
    assert!(!out.alarm);
    let out = m.process(&c, 6.0, &epoch(8, 6, &mut noise, None)).unwrap();
    assert!(!out.main_collapsed);
    assert!(error_m(&out.position_m.unwrap()) < 50.0);
}

/// Too few satellites: a typed error, and the filters are untouched (the
/// next epoch with enough satellites continues); bad input is typed too.
///
/// Verifies: WIRE-TimeNotIncreasing, WIRE-SigmaOutOfRange
#[test]
fn too_few_satellites_and_bad_input() {
    let c = cfg();
    let mut m = std::boxed::Box::new(PfRaim::<f64, SirPf<f64, 100>, 12>::new(3));
    let mut noise = rng::seeded(4);
    let four = epoch(4, 0, &mut noise, None);
    assert_eq!(
        m.process(&c, 0.0, &four),
        Err(PfError::TooFewSatellites { have: 4, need: 5 })
    );
    m.process(&c, 1.0, &epoch(8, 1, &mut noise, None)).unwrap();
    let r0 = *m.reference();
    assert!(matches!(
        m.process(&c, 2.0, &epoch(4, 2, &mut noise, None)),
        Err(PfError::TooFewSatellites { .. })
    ));
    assert_eq!(*m.reference(), r0);
    let mut nan = epoch(8, 3, &mut noise, None);
    nan[2].pseudorange_m = f64::NAN;
    assert!(matches!(
        m.process(&c, 3.0, &nan),
        Err(PfError::NotFinite {
            field: "pseudorange_m",
            index: 2,
            ..
        })
    ));
    // A host sigma outside the bound (1e30 m removed the satellite).
    for v in [1e30, 1e-9] {
        let mut wide = epoch(8, 3, &mut noise, None);
        wide[5].sigma_m = Some(v);
        assert_eq!(
            m.process(&c, 3.0, &wide).err(),
            Some(PfError::SigmaOutOfRange {
                index: 5,
                sigma_m: v,
                min_m: crate::config_bounds::SIGMA_M.min,
                max_m: crate::config_bounds::SIGMA_M.max,
            })
        );
    }
    assert_eq!(*m.reference(), r0);
    let mut dup = epoch(8, 3, &mut noise, None);
    dup[1].id = dup[0].id;
    assert!(matches!(
        m.process(&c, 3.0, &dup),
        Err(PfError::DuplicateSatellite { .. })
    ));
    assert!(matches!(
        m.process(&c, 1.0, &epoch(8, 3, &mut noise, None)),
        Err(PfError::TimeNotIncreasing { .. })
    ));
    // Issue 35: a time outside the GPS era, and satellite numbers outside
    // their system's range (PRN 0, 255), are refused as well.
    let era = crate::measurement::EPOCH_TIME_S;
    for t in [1e300, era.max * 2.0] {
        assert_eq!(
            m.process(&c, t, &epoch(8, 3, &mut noise, None)).err(),
            Some(PfError::OutOfRange {
                field: "time_s",
                value: t,
                min: era.min,
                max: era.max
            })
        );
    }
    for prn in [0u8, 255] {
        let mut odd = epoch(8, 3, &mut noise, None);
        odd[4].id.prn = prn;
        assert_eq!(
            m.process(&c, 3.0, &odd).err(),
            Some(PfError::PrnOutOfRange {
                index: 4,
                id: odd[4].id,
                max: odd[4].id.system.max_prn()
            })
        );
    }
    assert_eq!(*m.reference(), r0);
    let bad_cfg = PfConfig { window: 0, ..c };
    assert!(matches!(
        m.process(&bad_cfg, 3.0, &epoch(8, 3, &mut noise, None)),
        Err(PfError::OutOfRange {
            field: "window",
            ..
        })
    ));
    m.process(&c, 3.0, &epoch(8, 3, &mut noise, None)).unwrap();
}

/// A satellite leaving view mid-window drops its auxiliary filter; one
/// that comes back gets a fresh one; no alarm either way.
#[test]
fn satellite_leaving_view() {
    let c = cfg();
    let mut m = std::boxed::Box::new(PfRaim::<f64, GaPf<f64, 100>, 12>::new(8));
    let mut noise = rng::seeded(9);
    for k in 0..30 {
        let mut obs = epoch(8, k, &mut noise, None);
        if (10..20).contains(&k) {
            obs.remove(5);
        }
        let out = m.process(&c, k as f64, &obs).unwrap();
        assert!(!out.alarm, "epoch {k}: {}", out.decision);
        let expect = if (10..20).contains(&k) { 7 } else { 8 };
        assert_eq!(out.llr.len(), expect);
        assert_eq!(out.used, expect);
    }
}

/// The EKF on a linear toy problem (1/R0 = 0, static state, no process
/// noise) against the closed form: after K epochs, the posterior mean and
/// covariance equal the batch least squares with the prior,
/// P = (P0^-1 + sum H^T R^-1 H)^-1, x = P sum H^T R^-1 z, and the first
/// epoch's predictive density is N(z; 0, H P0 H^T + R).
#[test]
fn ekf_matches_linear_closed_form() {
    const TOL_M: f64 = 1e-6;
    const TOL_LN: f64 = 1e-8;
    let c = PfConfig {
        process: ProcessModel {
            position_m_per_sqrt_s: 0.0,
            clock_m_per_sqrt_s: 0.0,
            drift_m_s_per_sqrt_s: 0.0,
        },
        ..cfg()
    };
    let mut rng = rng::seeded(1);
    let sats = satellites(6);
    let r = model::Reference {
        position_m: RECEIVER_M,
        clock_m: [0.0; 5],
        drift_m_s: 0.0,
    };
    let truth = [1.0, -2.0, 0.5, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let mut ekf = Ekf::<f64>::BLANK;
    ekf.init(&c, &mut rng);
    let s0 = model::init_sigmas(&c);
    let p0 = DMatrix::from_diagonal(&DVector::from_iterator(9, s0.iter().map(|v| v * v)));
    let mut info = p0.clone().try_inverse().unwrap();
    let mut rhs = DVector::zeros(9);
    let mut noise = rng::seeded(2);
    for k in 0..4 {
        let mut terms: std::vec::Vec<model::SatTerm<f64>> = std::vec::Vec::new();
        let mut h = DMatrix::zeros(6, 9);
        let mut z = DVector::zeros(6);
        for (i, s) in sats.iter().enumerate().take(6) {
            let mut t = model::SatTerm::<f64>::new(
                SatId::new(System::Gps, i as u8 + 1),
                0.0,
                s,
                SIGMA_M,
                &r,
            );
            t.inv_range = 0.0;
            let zi = t.predict(&truth) + SIGMA_M * rng::normal(&mut noise);
            t.z0 = zi;
            let row = t.jacobian(&[0.0; 9]);
            for j in 0..9 {
                h[(i, j)] = row[j];
            }
            z[i] = zi;
            terms.push(t);
        }
        let rinv = 1.0 / (SIGMA_M * SIGMA_M);
        if k == 0 {
            let s = &h * &p0 * h.transpose() + DMatrix::identity(6, 6) * (SIGMA_M * SIGMA_M);
            let ln = -0.5 * (z.transpose() * s.clone().try_inverse().unwrap() * &z)[(0, 0)]
                - 0.5 * s.determinant().ln()
                - 3.0 * (2.0 * core::f64::consts::PI).ln();
            let step = ekf.update(&c, &terms, None, &mut rng);
            assert!(
                (step.ln_predictive - ln).abs() < TOL_LN,
                "{} vs {ln}",
                step.ln_predictive
            );
        } else {
            ekf.update(&c, &terms, None, &mut rng);
        }
        info += h.transpose() * &h * rinv;
        rhs += h.transpose() * &z * rinv;
    }
    let p = info.try_inverse().unwrap();
    let x = &p * rhs;
    let m = ekf.mean();
    for j in 0..9 {
        assert!(
            (m[j] - x[j]).abs() < TOL_M,
            "state {j}: {} vs {}",
            m[j],
            x[j]
        );
        for i in 0..9 {
            assert!((ekf.covariance()[(i, j)] - p[(i, j)]).abs() < TOL_M);
        }
    }
}

/// The RAM of the monitor against the closed form (S + 1) filters of
/// P (DIM + 1) scalars + DIM, plus S LLR windows of MAX_WINDOW f64; and
/// the table docs/PF.md quotes (run with --nocapture to print it).
#[test]
fn memory_matches_formula() {
    fn formula(p: usize, s: usize, t: usize) -> usize {
        let filter = p * (model::DIM + 1) * t + model::DIM * t;
        let window = config::MAX_WINDOW * 8 + 2 * 8;
        (s + 1) * filter + s * window
    }
    macro_rules! row {
        ($t:ty, $p:literal, $s:literal) => {{
            let b = PfRaim::<$t, GaPf<$t, $p>, $s>::BYTES;
            let f = formula($p, $s, core::mem::size_of::<$t>());
            // Slack: the reference, times, exclusion list and RNG state.
            assert!(b >= f && b <= f + 160 + $s * 24, "{b} vs {f}");
            std::println!(
                "| {} | {} | {} | {:.1} | {} |",
                <$t as Real>::NAME,
                $p,
                $s,
                b as f64 / 1024.0,
                if b <= 192 * 1024 - 32 * 1024 {
                    "yes"
                } else {
                    "no"
                }
            );
        }};
    }
    row!(f32, 100, 6);
    row!(f32, 100, 12);
    row!(f32, 300, 6);
    row!(f32, 300, 8);
    row!(f32, 300, 10);
    row!(f32, 300, 12);
    row!(f32, 500, 8);
    row!(f64, 100, 12);
    row!(f64, 300, 6);
    row!(f64, 300, 12);
    let ekf = PfRaim::<f32, Ekf<f32>, 12>::BYTES;
    std::println!("| f32 EKF | - | 12 | {:.1} | yes |", ekf as f64 / 1024.0);
}

/// Exclusion: after the alarm the faulty satellite is out (7 used) and the
/// persisting fault raises no further alarm; with `readmit_s` it comes back
/// after that time (8 used) and, the fault persisting, is caught again.
#[test]
fn exclusion_and_readmission() {
    let c = PfConfig {
        readmit_s: 10.0,
        ..cfg()
    };
    let mut m = std::boxed::Box::new(PfRaim::<f64, Ekf<f64>, 12>::new(1));
    let mut noise = rng::seeded(2);
    let g4 = SatId::new(System::Gps, 4);
    let mut excluded_at = None;
    let mut readmitted = false;
    let mut second_alarm = false;
    for k in 0..60 {
        let f = (k >= 20).then_some((3, 40.0));
        let out = m
            .process(&c, k as f64, &epoch(8, k, &mut noise, f))
            .unwrap();
        if let Some(t) = excluded_at {
            if k < t + 10 {
                assert_eq!(out.used, 7, "epoch {k}");
                assert!(!out.alarm, "epoch {k}");
            } else if out.used == 8 {
                readmitted = true;
            }
            if readmitted && out.alarm && out.isolated == Some(g4) {
                second_alarm = true;
            }
        } else if out.excluded == Some(g4) {
            assert!(k >= 20);
            assert_eq!(m.excluded(), &[(g4, k as f64)]);
            excluded_at = Some(k);
        } else {
            assert!(!out.alarm, "epoch {k}");
        }
    }
    assert!(excluded_at.is_some() && readmitted && second_alarm);
}

/// The particle filters' measurement laws (SPEC §10: the likelihood of
/// each residual, `PfConfig::likelihood`) against statrs's densities at
/// residuals from the core to 12 sigma: the Gaussian, the Student-t with
/// nu = 3, 4 and 30 degrees of freedom and scale sigma, and the Gaussian
/// mixture (1 - eps) N(0, sigma^2) + eps N(0, (k sigma)^2) with eps =
/// 0.05, k = 10 (its log-sum-exp form keeps the far tail finite where the
/// plain sum of the two densities underflows). The EKF's law is the
/// Gaussian whatever the configuration.
///
/// Verifies: SPEC-10
#[test]
fn measurement_laws_match_statrs_densities() {
    use crate::pf::model::{Lik, SatTerm};
    use statrs::distribution::{Continuous, Normal, StudentsT};
    let sigma = 2.5;
    let term = SatTerm::<f64> {
        id: SatId::new(System::Gps, 1),
        sys: 0,
        los: [1.0, 0.0, 0.0],
        inv_range: 1.0 / 2.0e7,
        z0: 0.0,
        sigma,
        ln_sigma: libm::log(sigma),
    };
    let with = |likelihood| PfConfig {
        likelihood,
        ..PfConfig::default()
    };
    let residuals = [0.0, 0.3, -1.7, 4.0, -9.5, 30.0];
    let normal = Normal::new(0.0, sigma).unwrap();
    let gauss = Lik::<f64>::new(&with(Likelihood::Gaussian));
    let ekf = Lik::<f64>::gaussian();
    for r in residuals {
        let want = normal.ln_pdf(r);
        assert!((gauss.ln_density(r, &term) - want).abs() < 1e-12, "{r}");
        assert!((ekf.ln_density(r, &term) - want).abs() < 1e-12, "{r}");
    }
    for nu in [3.0, 4.0, 30.0] {
        let t = StudentsT::new(0.0, sigma, nu).unwrap();
        let lik = Lik::<f64>::new(&with(Likelihood::StudentT { nu }));
        for r in residuals {
            let (got, want) = (lik.ln_density(r, &term), t.ln_pdf(r));
            assert!((got - want).abs() < 1e-10, "nu {nu} r {r}: {got} vs {want}");
        }
    }
    let (eps, k) = (0.05, 10.0);
    let lik = Lik::<f64>::new(&with(Likelihood::Mixture {
        outlier_prob: eps,
        outlier_scale: k,
    }));
    let wide = Normal::new(0.0, k * sigma).unwrap();
    for r in residuals {
        let want = libm::log((1.0 - eps) * normal.pdf(r) + eps * wide.pdf(r));
        let got = lik.ln_density(r, &term);
        assert!((got - want).abs() < 1e-10, "r {r}: {got} vs {want}");
    }
    // 1e3 sigma out: the core's density underflows to 0 in f64, the
    // mixture's log-density is the outlier component's.
    let r = 1e3 * sigma;
    assert_eq!(normal.pdf(r), 0.0);
    let got = lik.ln_density(r, &term);
    let want = libm::log(eps) + wide.ln_pdf(r);
    assert!((got - want).abs() < 1e-9, "{got} vs {want}");
}

/// The PF monitor's refusals of an epoch (SPEC §10 inputs): a non-finite
/// time, a NaN decision threshold given to `process_at`, and more
/// satellites than the filter holds (`S` = 8 here) are typed errors with
/// their values, and leave the filter as it was: the next good epoch
/// answers exactly what a filter that never saw the refused ones answers.
///
/// Verifies: SPEC-10, SAFE-INPUTS
#[test]
fn refused_pf_epochs_leave_the_filter_untouched() {
    let c = cfg();
    let mut noise = rng::seeded(21);
    let good: std::vec::Vec<_> = (0..3).map(|k| epoch(8, k, &mut noise, None)).collect();
    let mut refused = std::boxed::Box::new(PfRaim::<f64, GaPf<f64, 100>, 8>::new(4));
    let mut clean = std::boxed::Box::new(PfRaim::<f64, GaPf<f64, 100>, 8>::new(4));
    let first = refused.process(&c, 0.0, &good[0]).unwrap();
    assert_eq!(first, clean.process(&c, 0.0, &good[0]).unwrap());
    assert_eq!(
        refused.process(&c, f64::INFINITY, &good[1]).unwrap_err(),
        PfError::NotFinite {
            field: "time_s",
            index: 0,
            value: f64::INFINITY
        }
    );
    let e = refused.process_at(&c, f64::NAN, 1.0, &good[1]).unwrap_err();
    assert!(
        matches!(e, PfError::InvalidConfig { field: "threshold", value } if value.is_nan()),
        "{e:?}"
    );
    let extra = epoch(9, 1, &mut rng::seeded(3), None)[8];
    let nine: std::vec::Vec<_> = good[1].iter().copied().chain([extra]).collect();
    assert_eq!(
        refused.process(&c, 1.0, &nine).unwrap_err(),
        PfError::Capacity {
            field: "observations",
            have: 9,
            max: 8
        }
    );
    for (k, e) in good.iter().enumerate().skip(1) {
        let t = k as f64;
        assert_eq!(
            refused.process(&c, t, e).unwrap(),
            clean.process(&c, t, e).unwrap(),
            "{k}"
        );
    }
}

/// A receiver clock jump of 3000 m on every satellite (beyond
/// `clock_jump_m` = 1000 m) is absorbed into the reference clock: the
/// epoch reports it, the reference clock moves by the jump (within 3
/// sigma of the median of 8 residuals plus the filter's spread, 10 m), and
/// no satellite alarms, the LLRs being unaffected. With `clock_jump_m` = 0
/// (absorption off) the same epoch reports no jump and the reference
/// takes only the filter's gain of it (over 100 m short of the jump). After each epoch the main filter is centred on
/// the reference (its mean state offset is zero).
#[test]
fn clock_jump_is_absorbed_into_the_reference() {
    const JUMP_M: f64 = 3000.0;
    const JUMP_TOL_M: f64 = 10.0;
    for absorb in [true, false] {
        let c = PfConfig {
            clock_jump_m: if absorb { 1000.0 } else { 0.0 },
            ..cfg()
        };
        let mut m = std::boxed::Box::new(PfRaim::<f64, Ekf<f64>, 12>::new(4));
        let mut noise = rng::seeded(5);
        let mut before = 0.0;
        for k in 0..14 {
            let mut obs = epoch(8, k, &mut noise, None);
            if k >= 10 {
                for o in obs.iter_mut() {
                    o.pseudorange_m += JUMP_M;
                }
            }
            let out = m.process(&c, k as f64, &obs).unwrap();
            let mean = m.main().mean();
            assert!(mean[..3].iter().all(|v| v.abs() < 1e-6), "{mean:?}");
            if k == 9 {
                before = out.clock_m[0];
            }
            if k == 10 {
                assert_eq!(out.clock_jump, absorb);
                let moved = out.clock_m[0] - before;
                if absorb {
                    assert!((moved - JUMP_M).abs() < JUMP_TOL_M, "{moved}");
                    assert!(!out.alarm, "{}", out.decision);
                } else {
                    assert!((moved - JUMP_M).abs() > 10.0 * JUMP_TOL_M, "{moved}");
                }
            } else if absorb {
                assert!(!out.clock_jump && !out.alarm, "epoch {k}");
            }
        }
    }
}

/// With `exclude` off, a 40 m step on G4 alarms and isolates G4 but
/// excludes nothing: every later epoch still uses all 8 satellites.
#[test]
fn isolation_without_exclusion_keeps_every_satellite() {
    let c = PfConfig {
        exclude: false,
        ..cfg()
    };
    let mut m = std::boxed::Box::new(PfRaim::<f64, Ekf<f64>, 12>::new(1));
    let mut noise = rng::seeded(2);
    let g4 = SatId::new(System::Gps, 4);
    let mut alarms = 0;
    for k in 0..40 {
        let f = (k >= 20).then_some((3, 40.0));
        let out = m
            .process(&c, k as f64, &epoch(8, k, &mut noise, f))
            .unwrap();
        assert_eq!(out.used, 8, "epoch {k}");
        assert_eq!(out.excluded, None);
        if out.alarm {
            assert!(k >= 20, "epoch {k}");
            assert_eq!(out.isolated, Some(g4));
            alarms += 1;
        }
    }
    assert!(alarms > 0 && m.excluded().is_empty());
}

/// The first-epoch fix: exact pseudoranges of 8 satellites (and a ninth,
/// consistent one placed at the start point, the Earth's centre, which
/// gives no line of sight in the first iteration and is skipped there)
/// give the receiver and its clock within 1 mm; a constellation index beyond MAX_SYSTEMS is a capacity error
/// naming it; two satellites leave the normal matrix singular and a NaN
/// pseudorange a NaN step, both `NoInitialFix` (with the iteration
/// reached; the NaN step reported).
#[test]
fn first_fix_solves_and_refuses() {
    use super::init::{fix, FixInput};
    use crate::measurement::MAX_SYSTEMS;
    const TOL_M: f64 = 1e-3;
    let sats = satellites(8);
    let mut input: std::vec::Vec<FixInput> = sats
        .iter()
        .take(8)
        .map(|s| {
            let d = [
                s[0] - RECEIVER_M[0],
                s[1] - RECEIVER_M[1],
                s[2] - RECEIVER_M[2],
            ];
            FixInput {
                sat_m: *s,
                pseudorange_m: (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() + CLOCK_M,
                sigma_m: SIGMA_M,
                sys: 0,
            }
        })
        .collect();
    let centre_m = (RECEIVER_M[0].powi(2) + RECEIVER_M[1].powi(2) + RECEIVER_M[2].powi(2)).sqrt();
    input.push(FixInput {
        sat_m: [0.0; 3],
        pseudorange_m: centre_m + CLOCK_M,
        sigma_m: SIGMA_M,
        sys: 0,
    });
    let r = fix(&input, [0.0; 3]).unwrap();
    assert!(error_m(&r.position_m) < TOL_M, "{:?}", r.position_m);
    assert!((r.clock_m[0] - CLOCK_M).abs() < TOL_M, "{:?}", r.clock_m);
    let mut bad_sys = input.clone();
    bad_sys[2].sys = MAX_SYSTEMS;
    assert_eq!(
        fix(&bad_sys, [0.0; 3]),
        Err(PfError::Capacity {
            field: "sys",
            have: MAX_SYSTEMS,
            max: MAX_SYSTEMS - 1
        })
    );
    // Rank 2 of 4 unknowns: the factorisation fails within the first
    // iterations (rounding may let the first one through).
    match fix(&input[..2], [0.0; 3]) {
        Err(PfError::NoInitialFix { iterations, .. }) => assert!(iterations <= 2, "{iterations}"),
        other => panic!("{other:?}"),
    }
    let mut nan = input;
    nan[1].pseudorange_m = f64::NAN;
    match fix(&nan, [0.0; 3]) {
        Err(PfError::NoInitialFix { step_m, .. }) => assert!(step_m.is_nan()),
        other => panic!("{other:?}"),
    }
}
