//! PCA tests: the sorted SVD against nalgebra's dense symmetric eigen
//! decomposition, k against a brute-force count, the WLS gain against
//! S0 G = [I 0], the separation of one tested epoch against a dense
//! recomputation, and the behaviour on injected faults (synthetic sky).

#![allow(clippy::needless_range_loop)]
extern crate std;
use std::vec::Vec;

use super::*;
use crate::araim::AraimSat;
use crate::measurement::{SatId, System};
use nalgebra::{DMatrix, DVector};

/// Relative agreement of singular values with the dense eigenvalues.
const TOL_EIG_REL: f64 = 1e-9;
/// Agreement of the separation with the dense recomputation (m).
const TOL_SEP_M: f64 = 1e-9;

/// xorshift64* and Box-Muller: a deterministic normal stream.
struct Rng(u64);
impl Rng {
    fn u(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (a, b) = (self.u(), self.u());
        libm::sqrt(-2.0 * libm::log(a)) * libm::cos(2.0 * core::f64::consts::PI * b)
    }
}

#[test]
fn principal_matches_dense_symmetric_eigen() {
    let mut rng = Rng(7);
    for n in [3usize, 6, 12] {
        for _ in 0..20 {
            // A random covariance of rank n (padded to 12).
            let a = DMatrix::<f64>::from_fn(n, 2 * n, |_, _| rng.normal());
            let c = &a * a.transpose() / (2 * n) as f64;
            let mut m = nalgebra::OMatrix::<f64, Const<12>, Const<12>>::zeros();
            for i in 0..n {
                for j in 0..n {
                    m[(i, j)] = c[(i, j)];
                }
            }
            let p = principal(m, 0.9).unwrap();
            let mut eig: Vec<f64> = c
                .clone()
                .symmetric_eigen()
                .eigenvalues
                .iter()
                .copied()
                .collect();
            eig.sort_by(|a, b| b.partial_cmp(a).unwrap());
            for (i, e) in eig.iter().enumerate() {
                assert!((p.values[i] - e).abs() <= TOL_EIG_REL * eig[0], "{n} {i}");
            }
            for i in n..12 {
                assert!(p.values[i].abs() <= TOL_EIG_REL * eig[0]);
            }
            // k by brute force.
            let total: f64 = eig.iter().sum();
            let k = (1..=n)
                .find(|&k| eig[..k].iter().sum::<f64>() >= 0.9 * total)
                .unwrap();
            assert_eq!(p.k, k);
            // Sigma = V diag(s) V^T on the used block.
            for i in 0..n {
                for j in 0..n {
                    let r: f64 = (0..12).map(|l| p.v[l][i] * p.values[l] * p.v[l][j]).sum();
                    assert!((r - c[(i, j)]).abs() < 1e-9 * eig[0]);
                }
            }
        }
    }
}

fn sky(n_gps: usize, n_gal: usize) -> Vec<AraimSat<f64>> {
    let mut out = Vec::new();
    for i in 0..n_gps + n_gal {
        let system = if i < n_gps {
            System::Gps
        } else {
            System::Galileo
        };
        let az = (i as f64 * 137.5f64).to_radians();
        let el = (15.0 + (i as f64 * 23.0) % 70.0).to_radians();
        out.push(AraimSat {
            id: SatId {
                system,
                prn: (i + 1) as u8,
            },
            g_enu: AraimSat::g_from_az_el(az, el),
            c_int_m2: 1.0,
            c_acc_m2: 1.0,
            b_nom_m: 0.0,
            p_sat: 1e-5,
            residual_m: 0.0,
        });
    }
    out
}

#[test]
fn gain_inverts_the_geometry() {
    let s = sky(6, 6);
    let mut gain = [[0.0; 16]; 3];
    gain_rows(&s, &mut gain).unwrap();
    for q in 0..3 {
        // S0 applied to each geometry column: position columns give e_q,
        // each clock column 0.
        for c in 0..3 {
            let v: f64 = s
                .iter()
                .enumerate()
                .map(|(i, x)| gain[q][i] * x.g_enu[c])
                .sum();
            assert!((v - f64::from(u8::from(q == c))).abs() < 1e-12);
        }
        for sys in [System::Gps, System::Galileo] {
            let v: f64 = s
                .iter()
                .enumerate()
                .filter(|(_, x)| x.id.system == sys)
                .map(|(i, _)| gain[q][i])
                .sum();
            assert!(v.abs() < 1e-12);
        }
    }
    assert_eq!(
        gain_rows::<f64, 16>(&s[..3], &mut gain),
        Err(PcaError::TooFewSatellites { have: 3, need: 4 })
    );
}

const W: usize = 60;

/// Residuals: a common receiver clock (random walk, metres) + white noise
/// 0.3 m + `fault(epoch, sat index)`.
fn stream(
    epochs: usize,
    seed: u64,
    fault: impl Fn(usize, &AraimSat<f64>) -> f64,
) -> (Vec<Vec<AraimSat<f64>>>, Vec<f64>) {
    let base = sky(6, 6);
    let mut rng = Rng(seed);
    let mut clock = 0.0;
    let mut out = Vec::new();
    let mut times = Vec::new();
    for t in 0..epochs {
        clock += 3.0 * rng.normal();
        let mut e = base.clone();
        for s in e.iter_mut() {
            s.residual_m = clock + 0.3 * rng.normal();
            s.residual_m += fault(t, s);
        }
        out.push(e);
        times.push(30.0 * t as f64);
    }
    (out, times)
}

fn run(cfg: &PcaConfig, epochs: &[Vec<AraimSat<f64>>], times: &[f64]) -> Vec<PcaOutcome<16>> {
    let mut pca = Pca::<f64, 16, W>::new();
    epochs
        .iter()
        .zip(times)
        .map(|(e, &t)| pca.process(cfg, t, e).unwrap())
        .collect()
}

fn tested(o: &PcaOutcome<16>) -> Option<&PcaTest<16>> {
    match o {
        PcaOutcome::Tested(t) => Some(t),
        _ => None,
    }
}

#[test]
fn warms_up_for_w_epochs_then_tests() {
    let (e, t) = stream(W + 5, 1, |_, _| 0.0);
    let out = run(&PcaConfig::default(), &e, &t);
    assert!(out[..W]
        .iter()
        .all(|o| matches!(o, PcaOutcome::WarmingUp { .. })));
    assert!(out[W..].iter().all(|o| tested(o).is_some()));
    // The common clock dominates: k is small, 11 redundant directions left
    // or close to it.
    let t0 = tested(&out[W]).unwrap();
    assert_eq!(t0.n_complete, 12);
    assert!(t0.k >= 1 && t0.k < 12, "k {}", t0.k);
}

#[test]
fn separation_matches_a_dense_recomputation() {
    let (e, t) = stream(
        W + 1,
        3,
        |k, s| if k == W && s.id.prn == 4 { 5.0 } else { 0.0 },
    );
    let cfg = PcaConfig::default();
    let out = run(&cfg, &e, &t);
    let got = tested(&out[W]).unwrap();
    // Dense: covariance of the W previous epochs, eigen, k, projection.
    let n = 12;
    let x = DMatrix::<f64>::from_fn(W, n, |r, c| e[r][c].residual_m);
    let mean = DVector::<f64>::from_fn(n, |c, _| x.column(c).mean());
    let mut cov = DMatrix::<f64>::zeros(n, n);
    for r in 0..W {
        let d = x.row(r).transpose() - &mean;
        cov += &d * d.transpose();
    }
    cov /= (W - 1) as f64;
    let eig = cov.clone().symmetric_eigen();
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&a, &b| eig.eigenvalues[b].partial_cmp(&eig.eigenvalues[a]).unwrap());
    let total: f64 = eig.eigenvalues.iter().sum();
    let mut acc = 0.0;
    let mut k = 0;
    for &i in &idx {
        acc += eig.eigenvalues[i];
        k += 1;
        if acc >= cfg.variance_share * total {
            break;
        }
    }
    assert_eq!(got.k, k);
    let z = DVector::<f64>::from_fn(n, |c, _| e[W][c].residual_m) - &mean;
    let mut zh = DVector::<f64>::zeros(n);
    for &i in &idx[..k] {
        let v = eig.eigenvectors.column(i);
        zh += v * v.dot(&z);
    }
    let mut gain = [[0.0; 16]; 3];
    gain_rows(&e[W], &mut gain).unwrap();
    for q in 0..3 {
        let s = DVector::<f64>::from_fn(n, |c, _| gain[q][c]);
        let dx = s.dot(&(&zh - &z));
        assert!((dx - got.separation_m[q]).abs() < TOL_SEP_M, "axis {q}");
        let var: f64 = idx[k..]
            .iter()
            .map(|&i| eig.eigenvalues[i] * eig.eigenvectors.column(i).dot(&s).powi(2))
            .sum();
        assert!((var.sqrt() - got.sigma_m[q]).abs() < 1e-9);
    }
}

/// Epochs of the fault-free stream (after warm-up) with a fault.
fn false_alarms(out: &[PcaOutcome<16>]) -> usize {
    out.iter().filter_map(tested).filter(|t| t.fault).count()
}

#[test]
fn clean_stream_false_alarms_stay_near_the_budget() {
    // p_fa 1e-3 so that alarms can be counted: expected about 1.9 in 1940
    // tested epochs under a known covariance; the window estimate (60
    // samples) fattens the tail, so allow a factor 5.
    let cfg = PcaConfig {
        p_fa: 1e-3,
        ..PcaConfig::default()
    };
    let (e, t) = stream(2000, 11, |_, _| 0.0);
    let fa = false_alarms(&run(&cfg, &e, &t));
    std::println!("PCA clean synthetic: {fa} alarms in {} epochs", 2000 - W);
    assert!(fa <= 10, "{fa}");
}

#[test]
fn single_satellite_step_is_detected_at_onset() {
    let onset = 200;
    let (e, t) = stream(400, 5, |k, s| {
        if k >= onset && s.id.prn == 3 {
            10.0
        } else {
            0.0
        }
    });
    let out = run(&PcaConfig::default(), &e, &t);
    assert!(tested(&out[onset]).unwrap().fault);
    // Absorbed by the window afterwards: it stops alarming within W epochs.
    assert!(!tested(&out[onset + W + 5]).unwrap().fault);
}

#[test]
fn galileo_wide_common_bias_is_invisible_and_harmless() {
    // A bias common to one constellation lies on that constellation's
    // clock column: S0 maps it to zero in position, so dx cannot see it
    // (and it moves no position). Same for ARAIM's constellation mode.
    let onset = 200;
    let (e, t) = stream(260, 9, |k, s| {
        if k >= onset && s.id.system == System::Galileo {
            20.0
        } else {
            0.0
        }
    });
    let (c, _) = stream(260, 9, |_, _| 0.0);
    let cfg = PcaConfig::default();
    let out = run(&cfg, &e, &t);
    let clean = run(&cfg, &c, &t);
    let ratio_f = tested(&out[onset]).unwrap().ratio;
    let ratio_c = tested(&clean[onset]).unwrap().ratio;
    std::println!("Galileo-wide 20 m at onset: ratio {ratio_f:.3} (clean {ratio_c:.3})");
    assert!(!tested(&out[onset]).unwrap().fault);
}

/// Synthetic constellation-wide faults on Galileo (6 of 12 satellites),
/// through the PCA and ARAIM on the same epochs: the table printed in
/// docs/ESQ.md. Independent check: a bias common to one constellation is
/// on its clock column, so ARAIM's separations are unchanged to rounding
/// (S0 of any subset annihilates it) and the PCA cannot see it either.
///
/// Verifies: SPEC-9.3
#[test]
fn synthetic_constellation_faults_table() {
    use crate::araim::{Araim, AraimConfig, Ism};
    let onset = 200;
    let n = 320;
    // Ephemeris-like: 0.97-1.0 of the radial error, fixed per satellite.
    let eph = |s: &AraimSat<f64>| 0.985 + 0.015 * libm::cos(f64::from(s.id.prn));
    type Fault = fn(usize, &AraimSat<f64>, f64, &dyn Fn(&AraimSat<f64>) -> f64) -> f64;
    let cases: [(&str, f64, Fault); 6] = [
        ("bias", 5.0, |k, _, x, _| if k >= 200 { x } else { 0.0 }),
        ("bias", 20.0, |k, _, x, _| if k >= 200 { x } else { 0.0 }),
        ("ramp m/epoch", 0.3, |k, _, x, _| {
            if k >= 200 {
                x * (k - 200) as f64
            } else {
                0.0
            }
        }),
        ("ramp m/epoch", 1.5, |k, _, x, _| {
            if k >= 200 {
                x * (k - 200) as f64
            } else {
                0.0
            }
        }),
        (
            "ephemeris",
            50.0,
            |k, s, x, e| if k >= 200 { x * e(s) } else { 0.0 },
        ),
        (
            "ephemeris",
            200.0,
            |k, s, x, e| if k >= 200 { x * e(s) } else { 0.0 },
        ),
    ];
    let cfg = PcaConfig::default();
    let acfg = AraimConfig::default();
    let ism = Ism::with(&[System::Gps, System::Galileo], 1e-4);
    let mut araim = std::boxed::Box::new(Araim::<f64, 16, 256>::new());
    let (clean, t) = stream(n, 21, |_, _| 0.0);
    let clean_ratio: Vec<f64> = clean
        .iter()
        .map(|e| crate::araim::esq::statistic(araim.process(&acfg, &ism, e).unwrap()).ratio)
        .collect();
    for (name, size, f) in cases {
        let (e, _) = stream(n, 21, |k, s| {
            if s.id.system == System::Galileo {
                f(k, s, size, &eph)
            } else {
                0.0
            }
        });
        let out = run(&cfg, &e, &t);
        let pca_first = (onset..n).find(|&k| tested(&out[k]).is_some_and(|x| x.fault));
        let pca_onset = tested(&out[onset]).unwrap().ratio;
        let mut araim_first = None;
        let mut max_change: f64 = 0.0;
        for k in 0..n {
            let a = araim.process(&acfg, &ism, &e[k]).unwrap();
            let r = crate::araim::esq::statistic(a).ratio;
            max_change = max_change.max((r - clean_ratio[k]).abs());
            if k >= onset && !a.detection_passed && araim_first.is_none() {
                araim_first = Some(k - onset);
            }
        }
        std::println!(
            "synthetic E-wide {name} {size}: PCA first alarm {:?} epochs after onset (ratio at onset {pca_onset:.2}); ARAIM first alarm {:?}; max |ARAIM ratio change| {max_change:.2e}",
            pca_first.map(|k| k - onset),
            araim_first
        );
        if name != "ephemeris" {
            // Common to the constellation: invisible to ARAIM, exactly.
            assert!(max_change < 1e-9, "{name} {size}: {max_change}");
            assert!(araim_first.is_none());
        }
    }
}

/// Issue 35: an epoch time outside the GPS era
/// (`measurement::EPOCH_TIME_S`) is refused, and the history is left as it
/// was (the next epoch in order is taken).
#[test]
fn times_outside_the_gps_era_are_refused() {
    let (e, _) = stream(2, 1, |_, _| 0.0);
    let mut pca = Pca::<f64, 16, W>::new();
    let cfg = PcaConfig::default();
    pca.process(&cfg, 30.0, &e[0]).unwrap();
    let era = crate::measurement::EPOCH_TIME_S;
    for t in [1e300, -1e300, -1.0] {
        assert_eq!(
            pca.process(&cfg, t, &e[1]).err(),
            Some(PcaError::TimeOutOfRange {
                t_s: t,
                min_s: era.min,
                max_s: era.max
            })
        );
    }
    assert_eq!(pca.filled(), 1);
    pca.process(&cfg, 60.0, &e[1]).unwrap();
    assert_eq!(pca.filled(), 2);
}

/// Every bad input of the PCA monitor (SPEC §9.3) is refused with its
/// typed error and the offending value, and leaves the history as it was
/// (the next good epoch in order is taken): a variance share outside (0,
/// 1], a false-alert probability outside (0, 1), a non-finite time, more
/// satellites than the slots, a non-finite geometry, residual or
/// variance, a non-positive variance, a satellite given twice, fewer
/// satellites than the unknowns, and a time that does not advance. Each
/// refusal's text names its values.
///
/// Verifies: SPEC-9.3, SAFE-INPUTS
#[test]
fn bad_inputs_are_refused_with_their_values_and_the_history_kept() {
    let mut pca = Pca::<f64, 8, W>::new();
    let good = sky(4, 3);
    let cfg = PcaConfig::default();
    pca.process(&cfg, 30.0, &good).unwrap();
    let refused = |pca: &mut Pca<f64, 8, W>, c: &PcaConfig, t: f64, s: &[AraimSat<f64>]| {
        let e = pca.process(c, t, s).expect_err("refused");
        assert_eq!(pca.filled(), 1, "{e}");
        e
    };
    for v in [0.0, 1.5, f64::NAN] {
        let c = PcaConfig {
            variance_share: v,
            ..cfg
        };
        let e = refused(&mut pca, &c, 60.0, &good);
        assert!(
            matches!(e, PcaError::BadConfig { field: "variance_share", value } if value.to_bits() == v.to_bits())
        );
    }
    for v in [0.0, 1.0, -1e-3] {
        let c = PcaConfig { p_fa: v, ..cfg };
        assert_eq!(
            refused(&mut pca, &c, 60.0, &good),
            PcaError::BadConfig {
                field: "p_fa",
                value: v
            }
        );
    }
    assert_eq!(
        std::format!(
            "{}",
            PcaError::BadConfig {
                field: "p_fa",
                value: 2.0
            }
        ),
        "configuration p_fa = 2 is out of range"
    );
    let e = refused(&mut pca, &cfg, f64::INFINITY, &good);
    assert_eq!(
        e,
        PcaError::NotFinite {
            field: "t_s",
            index: 0,
            value: f64::INFINITY
        }
    );
    assert_eq!(std::format!("{e}"), "non-finite t_s at index 0: inf");
    let e = refused(&mut pca, &cfg, 60.0, &sky(5, 4));
    assert_eq!(
        e,
        PcaError::CapacityExceeded {
            have: 9,
            capacity: 8
        }
    );
    assert_eq!(std::format!("{e}"), "9 satellites exceed capacity 8");
    let fields = ["g_e", "g_n", "g_u", "residual_m", "c_int_m2"];
    for (k, field) in fields.iter().enumerate() {
        let mut bad = good.clone();
        let s = &mut bad[2];
        match k {
            0..=2 => s.g_enu[k] = f64::NAN,
            3 => s.residual_m = f64::NEG_INFINITY,
            _ => s.c_int_m2 = f64::INFINITY,
        }
        let e = refused(&mut pca, &cfg, 60.0, &bad);
        assert!(
            matches!(e, PcaError::NotFinite { field: f, index: 2, .. } if f == *field),
            "{e:?}"
        );
    }
    let mut bad = good.clone();
    bad[3].c_int_m2 = 0.0;
    assert_eq!(
        refused(&mut pca, &cfg, 60.0, &bad),
        PcaError::NotFinite {
            field: "c_int_m2",
            index: 3,
            value: 0.0
        }
    );
    let mut bad = good.clone();
    bad[5].id = bad[1].id;
    let e = refused(&mut pca, &cfg, 60.0, &bad);
    assert_eq!(
        e,
        PcaError::DuplicateSatellite {
            first: 1,
            second: 5
        }
    );
    assert_eq!(
        std::format!("{e}"),
        "duplicate satellite at indices 1 and 5"
    );
    // GPS and Galileo: 3 + 2 unknowns.
    let e = refused(&mut pca, &cfg, 60.0, &sky(2, 2));
    assert_eq!(e, PcaError::TooFewSatellites { have: 4, need: 5 });
    assert_eq!(std::format!("{e}"), "too few satellites: have 4, need 5");
    let e = refused(&mut pca, &cfg, 30.0, &good);
    assert_eq!(
        e,
        PcaError::NonMonotonicTime {
            previous_s: 30.0,
            now_s: 30.0
        }
    );
    assert_eq!(std::format!("{e}"), "time 30 s does not follow 30 s");
    pca.process(&cfg, 60.0, &good).unwrap();
    assert_eq!(pca.filled(), 2);
}

/// The texts of the refusals no input above reaches name what failed.
///
/// Verifies: WIRE-TEXT
#[test]
fn the_other_refusals_texts() {
    assert_eq!(
        std::format!("{}", PcaError::RankDeficient),
        "the all-in-view normal matrix is singular"
    );
    assert_eq!(
        std::format!("{}", PcaError::SvdFailed),
        "the SVD of the residual covariance did not converge"
    );
    assert_eq!(
        std::format!(
            "{}",
            PcaError::TimeOutOfRange {
                t_s: -1.0,
                min_s: 0.0,
                max_s: 5.0
            }
        ),
        "time -1 s outside [0, 5] s"
    );
}

/// A satellite that leaves view loses its slot and its history: with 12
/// satellites tested after W epochs, the epoch without satellite 6 tests
/// the 11 others, and when it comes back its history restarts, so it is
/// not complete again until W more epochs have passed.
#[test]
fn a_satellite_leaving_view_restarts_its_history() {
    let (mut e, t) = stream(W + 4, 3, |_, _| 0.0);
    e[W + 1].remove(5);
    let out = run(&PcaConfig::default(), &e, &t);
    assert_eq!(tested(&out[W]).unwrap().n_complete, 12);
    assert_eq!(tested(&out[W + 1]).unwrap().n_complete, 11);
    assert_eq!(tested(&out[W + 2]).unwrap().n_complete, 11);
    assert_eq!(tested(&out[W + 3]).unwrap().n_complete, 11);
}
