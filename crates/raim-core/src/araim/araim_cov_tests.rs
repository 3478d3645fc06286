//! The satellite bit of the ARAIM mode masks: satellites past bit 63
//! have none (the epoch holds at most 64 satellites, `MAX_SATS`).

use super::*;

#[test]
fn satellite_bits_end_at_63() {
    assert_eq!(bit(0), 1);
    assert_eq!(bit(5), 32);
    assert_eq!(bit(63), 1u64 << 63);
    assert_eq!(bit(64), 0);
    assert_eq!(bit(usize::MAX), 0);
}

extern crate std;

use crate::measurement::{SatId, System};

/// `n` satellites alternating GPS and Galileo, spread in azimuth and
/// elevation, with prior `p_sat`, unit variances and no residual.
fn sky(n: usize, p_sat: f64) -> std::vec::Vec<AraimSat<f64>> {
    (0..n)
        .map(|i| {
            let az = i as f64 * 2.4;
            let el = 0.2 + 1.2 * ((i * 7) % 11) as f64 / 11.0;
            let system = if i % 2 == 0 {
                System::Gps
            } else {
                System::Galileo
            };
            AraimSat {
                id: SatId {
                    system,
                    prn: (i / 2 + 1) as u8,
                },
                g_enu: [-el.cos() * az.sin(), -el.cos() * az.cos(), -el.sin()],
                c_int_m2: 1.0,
                c_acc_m2: 0.5,
                b_nom_m: 0.5,
                p_sat,
                residual_m: 0.0,
            }
        })
        .collect()
}

/// The availability limits read the configured PL output: with
/// `PlOutput::Exact` they are the exact roots' against VAL and HAL.
#[test]
fn limits_follow_the_exact_output_when_configured() {
    let cfg = AraimConfig {
        pl_output: PlOutput::Exact,
        ..AraimConfig::default()
    };
    let ism = Ism::with(&[System::Gps, System::Galileo], 1e-4);
    let mut e = std::boxed::Box::new(Araim::<f64, 16, 64>::new());
    let out = e.process(&cfg, &ism, &sky(12, 1e-5)).unwrap();
    assert!(out.unavailable.is_none(), "{:?}", out.unavailable);
    assert_eq!(out.limits.vpl, out.pl_exact.vpl_m <= cfg.val_m);
    assert_eq!(out.limits.hpl, out.pl_exact.hpl_m <= cfg.hal_m);
    assert!(out.pl_exact.vpl_m.is_finite() && out.pl_exact.vpl_m > 0.0);
}

/// 60 satellites at P_sat = 1e-3 (the bound's ceiling) and two
/// constellations at P_const = 1e-3, P_THRES = 1e-10 (its floor): more
/// than MAX_EVENTS = 4 simultaneous events have a probability above
/// P_THRES, so the epoch is unavailable with `TooManyEvents`, whose
/// P(more than 4 events) matches the Poisson-binomial tail computed here
/// by its own recursion.
#[test]
fn too_many_events_make_the_epoch_unavailable() {
    let cfg = AraimConfig {
        p_thres: 1e-10,
        ..AraimConfig::default()
    };
    assert_eq!(cfg.validate(), Ok(()));
    let ism = Ism::with(&[System::Gps, System::Galileo], 1e-3);
    let mut e = std::boxed::Box::new(Araim::<f64, 64, 64>::new());
    let sats = sky(60, 1e-3);
    let out = e.process(&cfg, &ism, &sats).unwrap();
    // P(k events) over the 62 independent events, by the textbook
    // recursion on the distribution (not the engine's tail recursion).
    let mut dist = std::vec![0.0f64; 63];
    dist[0] = 1.0;
    let probs: std::vec::Vec<f64> = core::iter::repeat_n(1e-3, 62).collect();
    for (count, &p) in probs.iter().enumerate() {
        for k in (1..=count + 1).rev() {
            dist[k] = dist[k] * (1.0 - p) + dist[k - 1] * p;
        }
        dist[0] *= 1.0 - p;
    }
    let tail: f64 = dist[5..].iter().sum();
    match out.unavailable {
        Some(Unavailable::TooManyEvents { p_exceed_at_max }) => {
            assert!(
                (p_exceed_at_max - tail).abs() < 1e-6 * tail,
                "{p_exceed_at_max} {tail}"
            );
            assert!(tail > 1e-10);
        }
        other => panic!("{other:?}"),
    }
}

/// LPV judges all four limits, H-ARAIM the HPL alone: every one of the 16
/// combinations against the rule written out.
#[test]
fn criteria_judge_their_limits() {
    for bits in 0u8..16 {
        let l = Limits {
            vpl: bits & 1 != 0,
            hpl: bits & 2 != 0,
            emt: bits & 4 != 0,
            sigma_acc: bits & 8 != 0,
        };
        assert_eq!(l.met(Criteria::Vertical), bits == 15, "{bits}");
        assert_eq!(l.met(Criteria::HorizontalOnly), bits & 2 != 0, "{bits}");
    }
}
