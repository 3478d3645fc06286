//! ESQ tests: P_Sigma against the PL equation's right-hand side (the
//! exact root makes the sum equal the allocated risk), every P_k against
//! statrs' normal, N* bounds, dT_e, and the resampler against a brute-force
//! schedule.

extern crate std;
use std::vec::Vec;

use super::*;
use crate::araim::tests::appendix_d;
use crate::araim::{Araim, AraimConfig, AraimSat, Ism};
use crate::measurement::{SatId, System};
use statrs::distribution::{ContinuousCDF, Normal};

/// Relative agreement of P_Sigma with the PL equation's right-hand side at
/// the exact root (the root is converged to 1e-10 m; the solver bounds
/// terms beyond z = 10 by Q(10), 1e-23 absolute).
const TOL_RISK_REL: f64 = 1e-6;
/// P_k against an independent normal tail (statrs), relative.
const TOL_PK_REL: f64 = 1e-9;

fn sats(residual_g3_m: f64) -> [AraimSat<f64>; 10] {
    let mut out = [AraimSat::default(); 10];
    for (i, (s, r)) in out.iter_mut().zip(appendix_d::ROWS.iter()).enumerate() {
        let system = if i < 5 { System::Gps } else { System::Galileo };
        *s = AraimSat {
            id: SatId {
                system,
                prn: (i % 5 + 1) as u8,
            },
            g_enu: r.g,
            c_int_m2: r.c_int,
            c_acc_m2: r.c_acc,
            b_nom_m: 0.5,
            p_sat: 1e-5,
            residual_m: if i == 2 { residual_g3_m } else { 0.0 },
        };
    }
    out
}

fn ism() -> Ism {
    Ism::with(&[System::Gps, System::Galileo], 1e-4)
}

fn q(z: f64) -> f64 {
    Normal::new(0.0, 1.0).unwrap().sf(z)
}

/// Verifies: SPEC-9.2
#[test]
fn p_sigma_is_the_allocated_risk_at_the_exact_root() {
    let cfg = AraimConfig::default();
    let mut e = Araim::<f64, 16, 64>::new();
    let out = e.process(&cfg, &ism(), &sats(0.0)).unwrap().clone();
    let factor = 1.0 - out.p_unmon / (cfg.phmi_vert + cfg.phmi_hor);
    let v = effective_samples(&out, 2, PlOutput::Exact).unwrap();
    let rhs = cfg.phmi_vert * factor;
    assert!(
        ((v.p_sigma - rhs) / rhs).abs() < TOL_RISK_REL,
        "{} {}",
        v.p_sigma,
        rhs
    );
    for axis in 0..2 {
        let h = effective_samples(&out, axis, PlOutput::Exact).unwrap();
        let rhs = 0.5 * cfg.phmi_hor * factor;
        assert!(
            ((h.p_sigma - rhs) / rhs).abs() < TOL_RISK_REL,
            "axis {axis}"
        );
    }
    // The ADD bracket output is above the root, so the risk is below.
    let a = effective_samples(&out, 2, PlOutput::AddBracket).unwrap();
    assert!(a.p_sigma < v.p_sigma);
}

#[test]
fn every_p_k_matches_an_independent_normal_tail() {
    let cfg = AraimConfig::default();
    let mut e = Araim::<f64, 16, 64>::new();
    let out = e.process(&cfg, &ism(), &sats(0.0)).unwrap().clone();
    let v = effective_samples(&out, 2, PlOutput::Exact).unwrap();
    let pl = out.pl_exact.vpl_m;
    let p0 = 2.0 * q((pl - out.bias0_m[2]) / out.sigma0_m[2]);
    let mut all = std::vec![p0];
    for m in out.modes.iter() {
        let z = (pl - m.threshold_m[2] - m.stats.bias_m[2]) / m.stats.sigma_m[2];
        all.push(m.events.prior * q(z));
    }
    let sum: f64 = all.iter().sum();
    let max = all.iter().cloned().fold(0.0, f64::max);
    assert!(((v.p_fault_free - p0) / p0).abs() < TOL_PK_REL);
    assert!(((v.p_sigma - sum) / sum).abs() < TOL_PK_REL);
    assert!(((v.p_max - max) / max).abs() < TOL_PK_REL);
    assert!(((v.n_star - sum / max) / (sum / max)).abs() < TOL_PK_REL);
    assert_eq!(v.n_modes, 12);
    // N* is between 1 and the number of terms.
    assert!(v.n_star >= 1.0 && v.n_star <= 13.0);
    let argmax = all
        .iter()
        .enumerate()
        .fold((0, 0.0), |b, (i, &p)| if p > b.1 { (i, p) } else { b })
        .0;
    let expect = if argmax == 0 {
        WorstMode::FaultFree
    } else {
        WorstMode::Mode { index: argmax - 1 }
    };
    assert_eq!(v.worst, expect);
    std::println!(
        "App. D vertical: P0 {:.4e} P_Sigma {:.4e} P_max {:.4e} N* {:.4} worst {:?}",
        v.p_fault_free,
        v.p_sigma,
        v.p_max,
        v.n_star,
        v.worst
    );
    // dT_e = T / N*.
    let dt = v.interval_s(300.0).unwrap();
    assert!((dt * v.n_star - 300.0).abs() < 1e-9);
    assert!(v.interval_s(0.0).is_err() && v.interval_s(f64::NAN).is_err());
}

#[test]
fn errors_are_typed() {
    let cfg = AraimConfig::default();
    let mut e = Araim::<f64, 16, 64>::new();
    let out = e.process(&cfg, &ism(), &sats(0.0)).unwrap().clone();
    assert_eq!(
        effective_samples(&out, 3, PlOutput::Exact),
        Err(EsqError::BadAxis { axis: 3 })
    );
    let mut none = out.clone();
    none.pl_exact = Default::default();
    assert_eq!(
        effective_samples(&none, 2, PlOutput::Exact),
        Err(EsqError::NoProtectionLevel { axis: 2 })
    );
    let mut nan = out.clone();
    nan.sigma0_m[2] = f64::NAN;
    assert!(matches!(
        effective_samples(&nan, 2, PlOutput::Exact),
        Err(EsqError::NotFinite { .. })
    ));
    // A PL far out: every term underflows.
    let mut far = out;
    far.pl_exact.vpl_m = 1e6;
    assert_eq!(
        effective_samples(&far, 2, PlOutput::Exact),
        Err(EsqError::ZeroRisk)
    );
}

#[test]
fn separation_statistic_flags_a_fault() {
    let cfg = AraimConfig::default();
    let mut e = Araim::<f64, 16, 64>::new();
    let clean = statistic(e.process(&cfg, &ism(), &sats(0.0)).unwrap());
    assert!(clean.passed && clean.ratio == 0.0);
    let out = e.process(&cfg, &ism(), &sats(30.0)).unwrap();
    let s = statistic(out);
    assert!(!s.passed && s.ratio > 1.0);
    // Independent: the largest ratio over the published per-mode tests.
    let mut best: f64 = 0.0;
    for m in out.modes.iter() {
        for q in 0..3 {
            best = best.max(m.stats.separation_m[q].abs() / m.threshold_m[q]);
        }
    }
    assert_eq!(s.ratio, best);
    assert!((s.separation_m.abs() / s.threshold_m - best).abs() < 1e-12);
}

/// The brute-force schedule: inside each window [t0, t0 + T), the first
/// epoch at or after each t0 + j dT_e (each epoch at most once).
fn brute_force(times: &[f64], window_s: f64, n_star: impl Fn(f64) -> f64) -> Vec<f64> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < times.len() {
        let t0 = times[i];
        let dt = window_s / n_star(t0);
        let end = times.partition_point(|&t| t < t0 + window_s - TIME_TOL_S);
        let win = &times[i..end];
        let mut last = None;
        let mut j = 0.0;
        while t0 + j * dt < t0 + window_s - TIME_TOL_S {
            let target = t0 + j * dt;
            if let Some(&t) = win.iter().find(|&&t| t >= target - TIME_TOL_S) {
                if last != Some(t) {
                    out.push(t);
                    last = Some(t);
                }
            }
            j += 1.0;
        }
        i = end;
    }
    out
}

fn run(times: &[f64], window_s: f64, n_star: impl Fn(f64) -> f64) -> Vec<f64> {
    let mut r = Resampler::new(window_s).unwrap();
    let mut out = Vec::new();
    for &t in times {
        let n = r.opens_window(t).then(|| n_star(t));
        if let Sample::Emit { .. } = r.offer(t, n).unwrap() {
            out.push(t);
        }
    }
    out
}

/// Verifies: SPEC-9.2
#[test]
fn resampler_matches_the_brute_force_schedule() {
    // 30 s epochs over 3 h, with a gap of 7 epochs and a jittered time tag.
    let mut times: Vec<f64> = (0..360).map(|k| 1000.0 + 30.0 * k as f64).collect();
    times.retain(|t| !(3000.0..3210.0).contains(t));
    times[50] += 2e-4;
    for (window, n) in [
        (300.0, 2.4),
        (300.0, 1.0),
        (600.0, 3.7),
        (120.0, 13.0),
        (900.0, 7.0),
    ] {
        let got = run(&times, window, |_| n);
        assert_eq!(got, brute_force(&times, window, |_| n), "T {window} N* {n}");
        if window / n >= 30.0 {
            // Solves per full window: ceil(N*) (when dT_e >= the epoch step).
            let per = got
                .iter()
                .filter(|&&t| (1000.0..1000.0 + window - 1.0).contains(&t))
                .count();
            assert_eq!(per as f64, libm::ceil(n), "T {window} N* {n}");
        }
    }
    // N* varying from window to window.
    let f = |t: f64| 1.0 + (t / 700.0) % 5.0;
    assert_eq!(run(&times, 300.0, f), brute_force(&times, 300.0, f));
}

#[test]
fn resampler_refuses_bad_input() {
    assert!(Resampler::new(0.0).is_err());
    assert!(Resampler::new(f64::INFINITY).is_err());
    let mut r = Resampler::new(300.0).unwrap();
    assert!(matches!(
        r.offer(0.0, None),
        Err(EsqError::OutOfRange {
            field: "n_star",
            ..
        })
    ));
    assert!(matches!(
        r.offer(0.0, Some(0.5)),
        Err(EsqError::OutOfRange { .. })
    ));
    assert!(r.offer(0.0, Some(2.0)).is_ok());
    assert_eq!(
        r.offer(0.0, None),
        Err(EsqError::NonMonotonicTime {
            previous_s: 0.0,
            now_s: 0.0
        })
    );
    assert!(matches!(
        r.offer(f64::NAN, None),
        Err(EsqError::NotFinite { .. })
    ));
    // Issue 35: outside the GPS era (`measurement::EPOCH_TIME_S`).
    for t in [1e300, -1e300] {
        assert_eq!(
            r.offer(t, None),
            Err(EsqError::OutOfRange {
                field: "t_s",
                value: t
            })
        );
    }
    assert_eq!(r.offer(30.0, None), Ok(Sample::Skip));
    assert!(matches!(
        r.offer(150.0, None),
        Ok(Sample::Emit { index: 1, .. })
    ));
}
