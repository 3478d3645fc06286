//! ESQ's refusals and its statistic's rarer arms: every error's text
//! against the text written out with its values, a non-finite bias or
//! window, modes that are not monitored, and NaN separation ratios (a
//! NaN is a failed test, never an all clear).

extern crate std;
use std::format;

use super::resample::Resampler;
use super::*;
use crate::araim::tests::appendix_d;
use crate::araim::{Araim, AraimConfig, AraimSat, Ism, ModeStatus};
use crate::measurement::{SatId, System};
use statrs::distribution::{ContinuousCDF, Normal};

fn output(residual_g3_m: f64) -> AraimOutput<f64, 64> {
    let mut sats = [AraimSat::default(); 10];
    for (i, (s, r)) in sats.iter_mut().zip(appendix_d::ROWS.iter()).enumerate() {
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
    let ism = Ism::with(&[System::Gps, System::Galileo], 1e-4);
    let mut e = Araim::<f64, 16, 64>::new();
    e.process(&AraimConfig::default(), &ism, &sats)
        .unwrap()
        .clone()
}

#[test]
fn every_error_reads_with_its_values() {
    let cases = [
        (
            EsqError::NoProtectionLevel { axis: 2 },
            "the epoch has no protection level on axis 2",
        ),
        (
            EsqError::BadAxis { axis: 7 },
            "axis 7 outside 0..3 (E, N, U)",
        ),
        (EsqError::ZeroRisk, "every mode's P_k underflowed to zero"),
        (
            EsqError::NotFinite {
                field: "p_k",
                value: f64::INFINITY,
            },
            "non-finite p_k: inf",
        ),
        (
            EsqError::OutOfRange {
                field: "window_s",
                value: -1.5,
            },
            "window_s = -1.5 is out of range",
        ),
        (
            EsqError::NonMonotonicTime {
                previous_s: 10.0,
                now_s: 9.5,
            },
            "time 9.5 s does not follow 10 s",
        ),
    ];
    for (e, text) in cases {
        assert_eq!(format!("{e}"), text);
    }
}

#[test]
fn an_infinite_window_or_n_star_is_refused() {
    let out = output(0.0);
    let v = effective_samples(&out, 2, PlOutput::Exact).unwrap();
    assert_eq!(
        v.interval_s(f64::INFINITY),
        Err(EsqError::OutOfRange {
            field: "window_s",
            value: f64::INFINITY
        })
    );
    let mut r = Resampler::new(120.0).unwrap();
    assert_eq!(r.window_s(), 120.0);
    // Before the first window dT_e is the window itself.
    assert_eq!(r.interval_s(), 120.0);
    assert_eq!(
        r.offer(0.0, Some(f64::INFINITY)),
        Err(EsqError::OutOfRange {
            field: "n_star",
            value: f64::INFINITY
        })
    );
    assert!(r.offer(0.0, Some(4.0)).is_ok());
    assert_eq!(r.interval_s(), 30.0);
}

#[test]
fn a_non_finite_pl_or_bias_is_refused() {
    let out = output(0.0);
    let mut inf = out.clone();
    inf.pl_exact.hpl_axes_m[0] = f64::INFINITY;
    assert_eq!(
        effective_samples(&inf, 0, PlOutput::Exact),
        Err(EsqError::NoProtectionLevel { axis: 0 })
    );
    for v in [0.0, -3.0, f64::NAN] {
        let mut bad = out.clone();
        bad.pl_exact.vpl_m = v;
        assert_eq!(
            effective_samples(&bad, 2, PlOutput::Exact),
            Err(EsqError::NoProtectionLevel { axis: 2 })
        );
    }
    let mut nan = out.clone();
    nan.bias0_m[1] = f64::NAN;
    assert!(matches!(
        effective_samples(&nan, 1, PlOutput::Exact),
        Err(EsqError::NotFinite {
            field: "bias0_m",
            value
        }) if value.is_nan()
    ));
}

#[test]
fn unmonitored_modes_are_left_out_of_the_sum_and_the_statistic() {
    let out = output(30.0);
    let all = effective_samples(&out, 2, PlOutput::Exact).unwrap();
    let mut cut = out.clone();
    let first = cut.modes[0];
    cut.modes[0].status = ModeStatus::Unmonitorable {
        column: 0,
        pivot: 0.0,
    };
    let fewer = effective_samples(&cut, 2, PlOutput::Exact).unwrap();
    assert_eq!(fewer.n_modes + 1, all.n_modes);
    // The left-out mode's own P_k, written out (mode_risk's formula).
    let z = (all.pl_m - first.threshold_m[2] - first.stats.bias_m[2]) / first.stats.sigma_m[2];
    let pk = first.events.prior * Normal::new(0.0, 1.0).unwrap().sf(z);
    assert!((all.p_sigma - fewer.p_sigma - pk).abs() <= 1e-9 * all.p_sigma);
    // The statistic skips it too: the largest ratio over the others.
    let s = statistic(&cut);
    let mut best: f64 = 0.0;
    for m in cut.modes.iter().skip(1) {
        for q in 0..3 {
            best = best.max(m.stats.separation_m[q].abs() / m.threshold_m[q]);
        }
    }
    assert_eq!(s.ratio, best);
    assert_ne!(s.mode, Some(0));
}

#[test]
fn a_nan_ratio_is_kept_as_the_statistic() {
    let mut out = output(0.0);
    // 0 / 0 on two axes of the second mode: the first NaN is kept, and
    // nothing (not the second NaN, not a larger ratio) replaces it.
    out.modes[1].stats.separation_m[0] = 0.0;
    out.modes[1].threshold_m[0] = 0.0;
    out.modes[1].stats.separation_m[1] = 0.0;
    out.modes[1].threshold_m[1] = 0.0;
    out.modes[2].stats.separation_m[2] = 1e9;
    let s = statistic(&out);
    assert!(s.ratio.is_nan());
    assert_eq!((s.mode, s.axis), (Some(1), 0));
}
