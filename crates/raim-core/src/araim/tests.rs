//! ARAIM tests: the ADD v3.0 Appendix D vector (SPEC §9.1), a dense
//! brute-force reference, the enumeration against all subsets, bad input
//! and f32 against f64.

#![allow(clippy::needless_range_loop)]

extern crate std;

pub(crate) mod appendix_d {
    pub struct Row {
        pub g: [f64; 3],
        pub c_int: f64,
        pub c_acc: f64,
    }
    const fn row(g: [f64; 3], c_int: f64, c_acc: f64) -> Row {
        Row { g, c_int, c_acc }
    }
    /// SPEC §9.1: GPS 1-5 then Galileo 1-5.
    pub const ROWS: [Row; 10] = [
        row([0.0225, 0.9951, -0.0966], 3.8865, 3.5740),
        row([0.6750, -0.6900, -0.2612], 1.4377, 1.1252),
        row([0.0723, -0.6601, -0.7477], 0.8604, 0.5479),
        row([-0.9398, 0.2553, -0.2269], 1.6383, 1.3258),
        row([-0.5907, -0.7539, -0.2877], 1.3229, 1.0104),
        row([-0.3236, -0.0354, -0.9455], 0.8434, 0.5309),
        row([-0.6748, 0.4356, -0.5957], 0.8963, 0.5838),
        row([0.0938, -0.7004, -0.7075], 0.8669, 0.5544),
        row([0.5571, 0.3088, -0.7709], 0.8573, 0.5448),
        row([0.6622, 0.6958, -0.2780], 1.3616, 1.0491),
    ];
}

use super::*;
use crate::measurement::{SatId, System};

pub(crate) fn appendix_d_sats() -> [AraimSat<f64>; 10] {
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
            residual_m: 0.0,
        };
    }
    out
}

fn ge_ism(p_const: f64) -> Ism {
    Ism::with(&[System::Gps, System::Galileo], p_const)
}

/// Intermediates, printed to 4 decimals by the ADD (m).
const TOL_INTERMEDIATE_M: f64 = 5e-4;
/// VPL, EMT, sigma_v,acc: printed to 0.1 m or 0.01 m.
const TOL_PRINTED_M: f64 = 0.05;
/// The exact HPL root of SPEC §9.1 (14.416 m).
const TOL_HPL_ROOT_M: f64 = 0.01;

mod add_appendix_d {
    use super::*;

    /// The one verdict: a failed test is an alarm even when the service is
    /// available, and an available, consistent epoch is Ok.
    #[test]
    fn decision_combines_the_test_and_the_availability() {
        use crate::result::Decision;
        let mut out = run();
        assert!(out.available() && out.detection_passed);
        assert_eq!(out.decision(), Decision::Ok);
        out.detection_passed = false;
        assert!(out.available());
        assert_eq!(out.decision(), Decision::Alarm);
        let mut worse = Araim::<f64, 16, 64>::new();
        let mut sats = appendix_d_sats();
        sats[2].residual_m += 30.0;
        let faulted = worse
            .process(&AraimConfig::default(), &ge_ism(1e-4), &sats)
            .unwrap();
        assert!(!faulted.detection_passed);
        assert_eq!(faulted.decision(), Decision::Alarm);
    }

    /// A horizontal-only (H-ARAIM) level: with the VAL at its floor of 10
    /// m, App. D's VPL (19.2 m) fails it, so the LPV criteria refuse the
    /// epoch, while its HPL (14.4 m) is within the HAL: horizontal-only
    /// available. At an HAL the HPL exceeds (App. D's geometry scaled up
    /// until it does) both refuse; a structural cause (mode capacity)
    /// refuses both, whatever the limits; with every limit met both agree
    /// with `available()`.
    ///
    /// Verifies: TOOL-AVAIL-HARAIM
    #[test]
    fn horizontal_only_judges_the_hal_alone() {
        let tight = AraimConfig {
            val_m: 10.0,
            emt_max_m: 10.0,
            ..AraimConfig::default()
        };
        let mut engine = Araim::<f64, 16, 64>::new();
        let sats = appendix_d_sats();
        let out = engine.process(&tight, &ge_ism(1e-4), &sats).unwrap();
        assert!(out.pl_add.vpl_m > 10.0 && out.pl_add.hpl_m < 40.0);
        assert!(!out.limits.vpl && out.limits.hpl);
        assert!(!out.available() && !out.available_for(Criteria::Vertical));
        assert!(out.available_for(Criteria::HorizontalOnly));
        // Both refuse when the HPL exceeds the HAL: the variances inflated
        // until the HPL passes 40 m.
        let mut wide = appendix_d_sats();
        for s in wide.iter_mut() {
            s.c_int_m2 *= 16.0;
            s.c_acc_m2 *= 16.0;
        }
        let out = engine
            .process(&AraimConfig::default(), &ge_ism(1e-4), &wide)
            .unwrap();
        assert!(out.pl_add.hpl_m > 40.0, "HPL {}", out.pl_add.hpl_m);
        assert!(!out.available_for(Criteria::HorizontalOnly));
        assert!(!out.available_for(Criteria::Vertical));
        // A structural cause refuses both.
        let mut small = Araim::<f64, 16, 4>::new();
        let out = small.process(&tight, &ge_ism(1e-4), &sats).unwrap();
        assert!(matches!(
            out.unavailable,
            Some(Unavailable::ModeCapacity { .. })
        ));
        assert!(!out.available_for(Criteria::HorizontalOnly));
        // Every limit met: all three agree.
        let out = run();
        assert!(out.available());
        assert!(
            out.available_for(Criteria::Vertical) && out.available_for(Criteria::HorizontalOnly)
        );
    }

    fn run() -> AraimOutput<f64, 64> {
        let mut engine = Araim::<f64, 16, 64>::new();
        let sats = appendix_d_sats();
        engine
            .process(&AraimConfig::default(), &ge_ism(1e-4), &sats)
            .unwrap()
            .clone()
    }

    /// Verifies: SPEC-9.1
    #[test]
    fn twelve_modes_and_k_fa() {
        let out = run();
        assert_eq!(out.modes.len(), 12);
        assert_eq!(out.n_monitored, 12);
        assert_eq!(out.max_faults, 1);
        assert!(
            (out.k_fa[2] - 5.1083).abs() < 1e-4,
            "K_fa,3 {}",
            out.k_fa[2]
        );
        // The 10 single-satellite modes then the 2 constellation modes.
        for (i, m) in out.modes.iter().enumerate().take(10) {
            assert_eq!(m.events.sats, 1 << i);
            assert_eq!(m.events.consts, 0);
            assert_eq!(m.events.prior, 1e-5);
        }
        assert_eq!(out.modes[10].events.consts, 1);
        assert_eq!(out.modes[11].events.consts, 2);
    }

    /// Verifies: SPEC-9.1
    #[test]
    fn constellation_modes_match_published_intermediates() {
        let out = run();
        // (sigma_3, sigma_ss,3, b_3): GPS-constellation mode, then Galileo.
        let published = [(2.5760, 1.5307, 2.8935), (2.5577, 1.5292, 2.0875)];
        for (m, (sigma, sigma_ss, b)) in out.modes[10..].iter().zip(published) {
            assert!(
                (m.stats.sigma_m[2] - sigma).abs() <= TOL_INTERMEDIATE_M,
                "{m:?}"
            );
            assert!(
                (m.stats.sigma_ss_m[2] - sigma_ss).abs() <= TOL_INTERMEDIATE_M,
                "{m:?}"
            );
            assert!((m.stats.bias_m[2] - b).abs() <= TOL_INTERMEDIATE_M, "{m:?}");
        }
    }

    /// Verifies: SPEC-9.1
    #[test]
    fn vpl_emt_sigma_acc_match_published() {
        let out = run();
        assert!(
            (out.pl_exact.vpl_m - 19.217).abs() <= 1e-3,
            "{}",
            out.pl_exact.vpl_m
        );
        assert!(
            (out.pl_add.vpl_m - 19.2).abs() <= TOL_PRINTED_M,
            "{}",
            out.pl_add.vpl_m
        );
        assert!((out.pl_exact.vpl_m - 19.2).abs() <= TOL_PRINTED_M);
        assert!(
            (out.emt_m - 7.8).abs() <= TOL_PRINTED_M,
            "EMT {}",
            out.emt_m
        );
        assert!(
            (out.sigma_v_acc_m - 1.47).abs() <= TOL_PRINTED_M,
            "{}",
            out.sigma_v_acc_m
        );
        assert!(out.available(), "{:?}", out.unavailable);
        assert!(out.detection_passed);
    }

    /// Verifies: SPEC-9.1
    #[test]
    fn hpl_exact_root_and_add_bracket_output() {
        let out = run();
        let root = out.pl_exact.hpl_m;
        assert!((root - 14.416).abs() <= TOL_HPL_ROOT_M, "HPL root {root}");
        assert!((out.pl_exact.hpl_axes_m[0] - 9.523).abs() <= TOL_HPL_ROOT_M);
        assert!((out.pl_exact.hpl_axes_m[1] - 10.823).abs() <= TOL_HPL_ROOT_M);
        let add = out.pl_add.hpl_m;
        assert!(
            root <= add && add <= root + 0.1,
            "ADD output {add}, root {root}"
        );
        // Per axis the bracket's upper end is within TOL_PL above the root.
        for q in 0..2 {
            let (e, a) = (out.pl_exact.hpl_axes_m[q], out.pl_add.hpl_axes_m[q]);
            assert!(e <= a && a <= e + 0.05 + 1e-9, "axis {q}: {a} vs {e}");
        }
    }
}

/// A seeded random sky: `n` satellites over the listed constellations
/// (each gets at least one), elevations 5-90 deg, the ADD error model
/// with sigma_URA 0.5-1.5 m, b_nom 0.5-0.75 m, residuals ~ N(0, C_acc).
pub(crate) fn random_sky(
    rng: &mut crate::testutil::Rng,
    n: usize,
    systems: &[System],
    p_sat: f64,
) -> std::vec::Vec<AraimSat<f64>> {
    let mut sats = std::vec::Vec::new();
    for i in 0..n {
        let system = systems[if i < systems.len() {
            i
        } else {
            (rng.uniform() * systems.len() as f64) as usize % systems.len()
        }];
        let az = rng.uniform() * 2.0 * core::f64::consts::PI;
        let el = (5.0 + 85.0 * rng.uniform()).to_radians();
        let ura = 0.5 + rng.uniform();
        let (c_int, c_acc) = error_model::variances_m2(el, ura, 0.6 * ura);
        sats.push(AraimSat {
            id: SatId {
                system,
                prn: (i + 1) as u8,
            },
            g_enu: AraimSat::g_from_az_el(az, el),
            c_int_m2: c_int,
            c_acc_m2: c_acc,
            b_nom_m: 0.5 + 0.25 * rng.uniform(),
            p_sat,
            residual_m: c_acc.sqrt() * rng.normal(),
        });
    }
    sats
}

/// The dense brute force: every mode a fresh weighted least squares
/// (nalgebra with std), every PL a dense bisection on statrs' normal tail.
mod brute_force {
    extern crate std;
    use super::*;
    use nalgebra::{DMatrix, DVector};
    use statrs::distribution::{ContinuousCDF, Normal};
    use std::vec::Vec;

    /// Agreement of the fast path with the dense reference (m).
    const TOL_M: f64 = 1e-9;
    /// Plus, for weak subsets, the rounding of any f64 solve: u * kappa
    /// relative, with kappa the condition number of the subset's normal
    /// matrix and u this multiple of the unit roundoff (a nearly singular
    /// subset with sigma of 1.5 km has kappa ~1e7; both sides then carry
    /// errors of 1e-9 relative, far above 1e-9 m).
    const U: f64 = 1e-14;

    fn close(a: f64, b: f64, kappa: f64) -> bool {
        (a - b).abs() <= TOL_M + U * kappa * a.abs()
    }

    pub(super) struct Dense {
        /// Position rows of S (3 x n, zero columns for removed satellites).
        pub(super) s: DMatrix<f64>,
        p_diag: [f64; 3],
        kappa: f64,
    }

    /// WLS gain of the kept satellites; None if rank-deficient.
    pub(super) fn dense_subset(sats: &[AraimSat<f64>], ism: &Ism, removed: u64) -> Option<Dense> {
        let n = sats.len();
        let kept: Vec<usize> = (0..n).filter(|i| removed & (1 << i) == 0).collect();
        let clocks: Vec<usize> = (0..5)
            .filter(|&j| ism.p_const[j].is_some())
            .filter(|&j| kept.iter().any(|&i| sats[i].id.system.index() == j))
            .collect();
        let m = 3 + clocks.len();
        if kept.len() < m {
            return None;
        }
        let mut g = DMatrix::<f64>::zeros(kept.len(), m);
        let mut w = DMatrix::<f64>::zeros(kept.len(), kept.len());
        for (r, &i) in kept.iter().enumerate() {
            for c in 0..3 {
                g[(r, c)] = sats[i].g_enu[c];
            }
            let col = clocks
                .iter()
                .position(|&j| j == sats[i].id.system.index())
                .unwrap();
            g[(r, 3 + col)] = 1.0;
            w[(r, r)] = 1.0 / sats[i].c_int_m2;
        }
        let a = g.transpose() * &w * &g;
        let sv = a.clone().svd(false, false).singular_values;
        if sv.min() <= 1e-9 * sv.max() {
            return None;
        }
        let kappa = sv.max() / sv.min();
        let p = a.try_inverse()?;
        let s_k = &p * g.transpose() * &w;
        let mut s = DMatrix::<f64>::zeros(3, n);
        for (r, &i) in kept.iter().enumerate() {
            for q in 0..3 {
                s[(q, i)] = s_k[(q, r)];
            }
        }
        Some(Dense {
            s,
            p_diag: [p[(0, 0)], p[(1, 1)], p[(2, 2)]],
            kappa,
        })
    }

    fn q(z: f64) -> f64 {
        Normal::standard().sf(z)
    }

    pub(super) fn q_inv(p: f64) -> f64 {
        -Normal::standard().inverse_cdf(p)
    }

    /// Dense bisection of the PL equation on [0, 1e4] m to 1e-12 m.
    fn dense_root(ff: (f64, f64), terms: &[(f64, f64, f64)], rhs: f64) -> f64 {
        let f = |x: f64| {
            2.0 * q((x - ff.0) / ff.1)
                + terms
                    .iter()
                    .map(|&(p, o, s)| p * q((x - o) / s))
                    .sum::<f64>()
        };
        let (mut lo, mut hi) = (0.0f64, 1e4f64);
        while hi - lo > 1e-12 {
            let mid = 0.5 * (lo + hi);
            if f(mid) > rhs {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// Checks one epoch; returns (modes, modes of condition number under
    /// 1e5, where the tolerance is 1e-9 m + 1e-9 relative at most).
    fn check_epoch(sats: &[AraimSat<f64>], ism: &Ism, cfg: &AraimConfig) -> (usize, usize) {
        let mut engine = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        let out = engine.process(cfg, ism, sats).unwrap().clone();
        check_output(sats, ism, cfg, &out, 1.0)
    }

    /// Checks an engine output for `sats` against the dense reference, the
    /// PL equations' right-hand side multiplied by `share` (1 for an
    /// epoch; 1 / N_ex after an exclusion).
    pub(super) fn check_output<const K: usize>(
        sats: &[AraimSat<f64>],
        ism: &Ism,
        cfg: &AraimConfig,
        out: &AraimOutput<f64, K>,
        share: f64,
    ) -> (usize, usize) {
        if matches!(
            out.unavailable,
            Some(Unavailable::ModeCapacity { .. }) | Some(Unavailable::TooManyEvents { .. })
        ) {
            return (0, 0);
        }
        let n = sats.len();
        let y = DVector::from_iterator(n, sats.iter().map(|s| s.residual_m));
        let dense0 = dense_subset(sats, ism, 0).unwrap();
        let s0 = &dense0.s;
        let cacc: Vec<f64> = sats.iter().map(|s| s.c_acc_m2).collect();
        let cint: Vec<f64> = sats.iter().map(|s| s.c_int_m2).collect();
        let bnom: Vec<f64> = sats.iter().map(|s| s.b_nom_m).collect();
        for qx in 0..3 {
            let sig: f64 = (0..n)
                .map(|i| s0[(qx, i)].powi(2) * cint[i])
                .sum::<f64>()
                .sqrt();
            assert!((sig - out.sigma0_m[qx]).abs() <= TOL_M);
            assert!((sig - dense0.p_diag[qx].sqrt()).abs() <= TOL_M);
            let b: f64 = (0..n).map(|i| s0[(qx, i)].abs() * bnom[i]).sum();
            assert!((b - out.bias0_m[qx]).abs() <= TOL_M);
        }
        let acc: f64 = (0..n)
            .map(|i| s0[(2, i)].powi(2) * cacc[i])
            .sum::<f64>()
            .sqrt();
        assert!((acc - out.sigma_v_acc_m).abs() <= TOL_M);
        let nm = out.n_monitored as f64;
        let kh = q_inv(cfg.pfa_hor / (4.0 * nm));
        let kv = q_inv(cfg.pfa_vert / (2.0 * nm));
        assert!(
            (kh - out.k_fa[0]).abs() <= 1e-9 * kh,
            "K_fa,h {kh} {}",
            out.k_fa[0]
        );
        assert!(
            (kv - out.k_fa[2]).abs() <= 1e-9 * kv,
            "K_fa,v {kv} {}",
            out.k_fa[2]
        );
        let mut terms: [Vec<(f64, f64, f64)>; 3] = Default::default();
        let mut unmon = out.p_exceed;
        let mut all_pass = true;
        let mut kappa_max = dense0.kappa;
        let mut strict = 0usize;
        for mode in out.modes.iter() {
            let mut removed = mode.events.sats;
            for (i, s) in sats.iter().enumerate() {
                if mode.events.consts & (1 << s.id.system.index()) != 0 {
                    removed |= 1 << i;
                }
            }
            let Some(dk) = dense_subset(sats, ism, removed) else {
                assert!(
                    matches!(mode.status, ModeStatus::Unmonitorable { .. }),
                    "dense subset singular, engine monitored: {mode:?}"
                );
                unmon += mode.events.prior;
                continue;
            };
            assert_eq!(mode.status, ModeStatus::Monitored, "{mode:?}");
            let kappa = dk.kappa.max(dense0.kappa);
            kappa_max = kappa_max.max(kappa);
            if kappa < 1e5 {
                strict += 1;
            }
            let diff = &dk.s - s0;
            let sep = &diff * &y;
            let mut pass = true;
            for qx in 0..3 {
                let sig: f64 = (0..n)
                    .map(|i| dk.s[(qx, i)].powi(2) * cint[i])
                    .sum::<f64>()
                    .sqrt();
                let b: f64 = (0..n).map(|i| dk.s[(qx, i)].abs() * bnom[i]).sum();
                let ss: f64 = (0..n)
                    .map(|i| diff[(qx, i)].powi(2) * cacc[i])
                    .sum::<f64>()
                    .sqrt();
                let st = &mode.stats;
                assert!(close(sig, st.sigma_m[qx], kappa), "sigma {sig} {mode:?}");
                assert!(close(b, st.bias_m[qx], kappa), "b {b} {mode:?}");
                assert!(close(ss, st.sigma_ss_m[qx], kappa), "ss {ss} {mode:?}");
                assert!(close(sep[qx], st.separation_m[qx], kappa), "sep {mode:?}");
                let k = if qx == 2 { kv } else { kh };
                let t = k * ss;
                assert!(
                    close(t, mode.threshold_m[qx], kappa),
                    "T {t} vs {} (K {k} vs {:?})",
                    mode.threshold_m[qx],
                    out.k_fa
                );
                pass &= sep[qx].abs() <= t;
                terms[qx].push((mode.events.prior, t + b, sig));
            }
            assert_eq!(pass, mode.passed);
            all_pass &= pass;
        }
        assert_eq!(all_pass, out.detection_passed);
        assert!((unmon - out.p_unmon).abs() <= 1e-12 * unmon.max(1e-30));
        if out
            .unavailable
            .is_some_and(|u| !matches!(u, Unavailable::Limits))
        {
            return (out.modes.len(), strict);
        }
        let factor = 1.0 - unmon / (cfg.phmi_vert + cfg.phmi_hor);
        let mut roots = [0.0; 3];
        for qx in 0..3 {
            let rhs = share
                * if qx == 2 {
                    cfg.phmi_vert * factor
                } else {
                    0.5 * cfg.phmi_hor * factor
                };
            roots[qx] = dense_root((out.bias0_m[qx], out.sigma0_m[qx]), &terms[qx], rhs);
        }
        let got = [
            out.pl_exact.hpl_axes_m[0],
            out.pl_exact.hpl_axes_m[1],
            out.pl_exact.vpl_m,
        ];
        let add = [
            out.pl_add.hpl_axes_m[0],
            out.pl_add.hpl_axes_m[1],
            out.pl_add.vpl_m,
        ];
        for qx in 0..3 {
            assert!(
                close(roots[qx], got[qx], kappa_max),
                "axis {qx}: {} vs {}",
                roots[qx],
                got[qx]
            );
            // The ADD output is the bracket's upper end: never below the
            // root, at most TOL_PL above it.
            assert!(add[qx] >= roots[qx] - TOL_M && add[qx] <= roots[qx] + cfg.tol_pl_m + TOL_M);
        }
        (out.modes.len(), strict)
    }

    #[test]
    fn appendix_d_matches_dense_reference() {
        let sats = appendix_d_sats();
        assert_eq!(
            check_epoch(&sats, &ge_ism(1e-4), &AraimConfig::default()),
            (12, 12)
        );
    }

    /// Random skies of 6-30 satellites over 1-3 constellations, P_sat 1e-5
    /// or 1e-4 (pairs), P_const 1e-8 or 1e-4 (satellite + constellation
    /// modes), each checked mode by mode and PL by PL.
    #[test]
    fn random_skies_match_dense_reference() {
        let mut rng = crate::testutil::Rng::new(12);
        let all = [System::Gps, System::Galileo, System::Beidou];
        let mut checked = 0;
        let mut with_pairs = 0;
        let mut modes_total = 0;
        let mut strict_total = 0;
        for trial in 0..60 {
            let nc = 1 + trial % 3;
            let n = 6 + (rng.uniform() * 25.0) as usize;
            let n = n.min(30).max(3 + nc + 1);
            let p_sat = if trial % 2 == 0 { 1e-4 } else { 1e-5 };
            let p_const = if trial % 4 < 2 { 1e-4 } else { 1e-8 };
            let sats = random_sky(&mut rng, n, &all[..nc], p_sat);
            let ism = Ism::with(&all[..nc], p_const);
            let (k, s) = check_epoch(&sats, &ism, &AraimConfig::default());
            strict_total += s;
            if k > 0 {
                checked += 1;
                modes_total += k;
                if k > n + nc {
                    with_pairs += 1;
                }
            }
        }
        assert!(checked >= 50, "only {checked} epochs checked");
        assert!(
            with_pairs >= 20,
            "only {with_pairs} epochs with multi-event modes"
        );
        assert!(modes_total > 5000, "{modes_total} modes");
        std::eprintln!("checked {checked} epochs, {with_pairs} with multi-event modes, {modes_total} modes, {strict_total} with kappa < 1e5");
        // Most modes are well conditioned: checked to 1e-9 m + 1e-9 rel.
        assert!(
            10 * strict_total >= 9 * modes_total,
            "{strict_total}/{modes_total}"
        );
    }

    /// b_nom = 0 on every satellite (the downdates skip the b^(k) pass:
    /// every b^(k) must be exactly 0) and on every other one (the pass
    /// runs with zero terms), against the dense reference.
    #[test]
    fn skies_without_nominal_bias_match_dense_reference() {
        let mut rng = crate::testutil::Rng::new(31);
        let all = [System::Gps, System::Galileo];
        let mut modes_total = 0;
        for trial in 0..12 {
            let n = 8 + (rng.uniform() * 20.0) as usize;
            let p_const = if trial % 2 == 0 { 1e-4 } else { 1e-8 };
            let mut sats = random_sky(&mut rng, n, &all, 1e-4);
            let none = trial < 6;
            for (i, s) in sats.iter_mut().enumerate() {
                if none || i % 2 == 0 {
                    s.b_nom_m = 0.0;
                }
            }
            let ism = Ism::with(&all, p_const);
            let (k, _) = check_epoch(&sats, &ism, &AraimConfig::default());
            modes_total += k;
            if none {
                let mut engine = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
                let out = engine
                    .process(&AraimConfig::default(), &ism, &sats)
                    .unwrap();
                assert_eq!(out.bias0_m, [0.0; 3]);
                for mode in out.modes.iter() {
                    assert_eq!(mode.stats.bias_m, [0.0; 3], "{mode:?}");
                }
            }
        }
        assert!(modes_total > 500, "{modes_total} modes");
    }
}

/// The mode list and the unmonitored probability against an explicit
/// enumeration of every subset of events on small skies.
mod enumeration {
    extern crate std;
    use super::*;
    use std::collections::BTreeMap;

    fn check(sats: &[AraimSat<f64>], ism: &Ism, p_thres: f64) {
        let n = sats.len();
        let consts: std::vec::Vec<(usize, f64)> = (0..5)
            .filter_map(|j| ism.p_const[j].map(|p| (j, p)))
            .collect();
        let e = n + consts.len();
        let prob = |k: usize| {
            if k < n {
                sats[k].p_sat
            } else {
                consts[k - n].1
            }
        };
        // Exact P(exactly this subset) summed by size; ADD priors by key.
        let mut by_size = std::vec![0.0f64; e + 1];
        for subset in 0u64..(1 << e) {
            let mut p = 1.0;
            for k in 0..e {
                p *= if subset & (1 << k) != 0 {
                    prob(k)
                } else {
                    1.0 - prob(k)
                };
            }
            by_size[subset.count_ones() as usize] += p;
        }
        let tail = |r: usize| by_size[r + 1..].iter().sum::<f64>();
        let r = (0..=e).find(|&r| tail(r) <= p_thres).unwrap();
        let mut reference: BTreeMap<(u64, u8), f64> = BTreeMap::new();
        for subset in 1u64..(1 << e) {
            if subset.count_ones() as usize > r {
                continue;
            }
            let mut cm = 0u8;
            let mut prior = 1.0;
            for k in 0..e {
                if subset & (1 << k) != 0 {
                    prior *= prob(k);
                    if k >= n {
                        cm |= 1 << consts[k - n].0;
                    }
                }
            }
            // Satellite events inside an excluded constellation are
            // redundant: the subset is the same.
            let mut sm = 0u64;
            for i in 0..n {
                if subset & (1 << i) != 0 && cm & (1 << sats[i].id.system.index()) == 0 {
                    sm |= 1 << i;
                }
            }
            *reference.entry((sm, cm)).or_insert(0.0) += prior;
        }
        let cfg = AraimConfig {
            p_thres,
            ..AraimConfig::default()
        };
        let mut engine = Araim::<f64, 16, 2048>::new();
        let out = engine.process(&cfg, ism, sats).unwrap();
        assert_eq!(out.max_faults, r);
        let t = tail(r);
        assert!(
            (out.p_exceed - t).abs() <= 1e-9 * t + 1e-300,
            "{} vs {t}",
            out.p_exceed
        );
        assert_eq!(out.modes.len(), reference.len());
        for m in out.modes.iter() {
            let p = reference[&(m.events.sats, m.events.consts)];
            assert!((m.events.prior - p).abs() <= 1e-12 * p, "{m:?} vs {p}");
        }
    }

    #[test]
    fn small_skies_match_all_subsets() {
        crate::testutil::on_big_stack(small_skies_match_all_subsets_body)
    }

    fn small_skies_match_all_subsets_body() {
        let mut rng = crate::testutil::Rng::new(7);
        let all = [System::Gps, System::Galileo, System::Beidou];
        let mut max_r = 0;
        for trial in 0..12 {
            let nc = 1 + trial % 3;
            let n = 5 + trial % 5 + nc;
            let p_sat = [1e-5, 1e-4, 1e-3][trial % 3];
            let p_const = [1e-4, 1e-3, 1e-8][(trial / 3) % 3];
            let sats = random_sky(&mut rng, n, &all[..nc], p_sat);
            let ism = Ism::with(&all[..nc], p_const);
            check(&sats, &ism, 8e-8);
            let mut engine = Araim::<f64, 16, 2048>::new();
            max_r = max_r.max(
                engine
                    .process(&AraimConfig::default(), &ism, &sats)
                    .unwrap()
                    .max_faults,
            );
        }
        assert!(max_r >= 2, "no multi-event skies: {max_r}");
    }

    /// The satellite + constellation modes are enumerated: 30 satellites,
    /// G15 + E15, P_sat 1e-4, P_const 1e-4 stays available.
    #[test]
    fn thirty_satellites_with_constellation_priors_stay_available() {
        let mut rng = crate::testutil::Rng::new(30);
        let systems = [System::Gps, System::Galileo];
        let mut sats = random_sky(&mut rng, 30, &systems, 1e-4);
        for (i, s) in sats.iter_mut().enumerate() {
            s.id.system = systems[i / 15];
            s.residual_m = 0.0;
        }
        let mut engine = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        let out = engine
            .process(&AraimConfig::default(), &ge_ism(1e-4), &sats)
            .unwrap();
        // 30 + 2 singles, 435 satellite pairs, 30 satellite + other
        // constellation, and the constellation pair (unmonitorable).
        assert_eq!(out.max_faults, 2);
        assert_eq!(out.modes.len(), 32 + 435 + 30 + 1);
        let both = out.modes.iter().filter(|m| m.events.consts == 3).count();
        assert_eq!(both, 1);
        assert!(out.p_unmon <= 8e-8, "{}", out.p_unmon);
        assert!(
            !matches!(out.unavailable, Some(Unavailable::Unmonitored { .. })),
            "{:?}",
            out.unavailable
        );
    }
}

mod bad_input {
    use super::*;

    fn run(sats: &[AraimSat<f64>], ism: &Ism) -> Result<(), AraimError> {
        let mut engine = Araim::<f64, 32, 256>::new();
        engine
            .process(&AraimConfig::default(), ism, sats)
            .map(|_| ())
    }

    /// Verifies: WIRE-Araim, SAFE-NAN
    #[test]
    fn nan_in_the_ism() {
        let mut sats = appendix_d_sats();
        sats[3].c_int_m2 = f64::NAN;
        assert!(matches!(
            run(&sats, &ge_ism(1e-4)),
            Err(AraimError::NotFinite {
                field: "c_int_m2",
                index: 3,
                ..
            })
        ));
        let sats = appendix_d_sats();
        let mut ism = ge_ism(1e-4);
        ism.p_const[1] = Some(f64::NAN);
        assert!(matches!(
            run(&sats, &ism),
            Err(AraimError::NotFinite {
                field: "p_const",
                index: 1,
                ..
            })
        ));
        let mut sats = appendix_d_sats();
        sats[0].b_nom_m = f64::INFINITY;
        assert!(matches!(
            run(&sats, &ge_ism(1e-4)),
            Err(AraimError::NotFinite {
                field: "b_nom_m",
                index: 0,
                ..
            })
        ));
        let cfg = AraimConfig {
            phmi_vert: f64::NAN,
            ..AraimConfig::default()
        };
        let mut engine = Araim::<f64, 32, 256>::new();
        assert!(matches!(
            engine.process(&cfg, &ge_ism(1e-4), &appendix_d_sats()),
            Err(AraimError::NotFinite {
                field: "phmi_vert",
                ..
            })
        ));
    }

    #[test]
    fn p_sat_zero_or_at_least_one() {
        for bad in [0.0, 1.0, 1.5, -1e-5] {
            let mut sats = appendix_d_sats();
            sats[7].p_sat = bad;
            let err = run(&sats, &ge_ism(1e-4)).unwrap_err();
            assert_eq!(
                err,
                AraimError::OutOfRange {
                    field: "p_sat",
                    index: 7,
                    value: bad,
                    min: crate::config_bounds::araim::P_SAT.min,
                    max: crate::config_bounds::araim::P_SAT.max
                }
            );
        }
    }

    #[test]
    fn constellation_without_satellites() {
        let ism = Ism::with(&[System::Gps, System::Galileo, System::Beidou], 1e-4);
        assert_eq!(
            run(&appendix_d_sats(), &ism),
            Err(AraimError::EmptyConstellation {
                system: System::Beidou
            })
        );
        let ism = Ism::with(&[System::Gps], 1e-4);
        assert_eq!(
            run(&appendix_d_sats(), &ism),
            Err(AraimError::MissingConstellationIsm {
                system: System::Galileo,
                index: 5
            })
        );
    }

    #[test]
    fn forty_satellites_at_capacity_32() {
        let mut rng = crate::testutil::Rng::new(40);
        let sats = random_sky(&mut rng, 40, &[System::Gps, System::Galileo], 1e-5);
        assert_eq!(
            run(&sats, &ge_ism(1e-4)),
            Err(AraimError::CapacityExceeded {
                have: 40,
                capacity: 32
            })
        );
    }

    #[test]
    fn duplicate_prn() {
        let mut sats = appendix_d_sats();
        sats[4].id = sats[1].id;
        assert_eq!(
            run(&sats, &ge_ism(1e-4)),
            Err(AraimError::DuplicateSatellite {
                system: System::Gps,
                prn: 2,
                first: 1,
                second: 4
            })
        );
    }

    #[test]
    fn too_few_and_rank_deficient() {
        let sats = appendix_d_sats();
        assert_eq!(
            run(&sats[..3], &Ism::with(&[System::Gps], 1e-4)),
            Err(AraimError::TooFewSatellites { have: 3, need: 4 })
        );
        // Four identical rows: singular.
        let mut same = [sats[0]; 5];
        for (i, s) in same.iter_mut().enumerate() {
            s.id.prn = i as u8 + 1;
        }
        assert!(matches!(
            run(&same, &Ism::with(&[System::Gps], 1e-4)),
            Err(AraimError::RankDeficient { .. })
        ));
    }

    /// Mode capacity overflow: unavailable with the count, never truncated.
    #[test]
    fn mode_capacity_overflow_is_unavailable() {
        let mut engine = Araim::<f64, 16, 8>::new();
        let out = engine
            .process(&AraimConfig::default(), &ge_ism(1e-4), &appendix_d_sats())
            .unwrap();
        assert_eq!(
            out.unavailable,
            Some(Unavailable::ModeCapacity {
                needed: 12,
                capacity: 8
            })
        );
        assert!(out.modes.is_empty());
    }

    /// A biased satellite fails its mode's test.
    #[test]
    fn a_large_bias_is_detected() {
        let mut sats = appendix_d_sats();
        sats[2].residual_m = 30.0;
        let mut engine = Araim::<f64, 16, 64>::new();
        let out = engine
            .process(&AraimConfig::default(), &ge_ism(1e-4), &sats)
            .unwrap();
        assert!(!out.detection_passed);
        assert!(!out.modes[2].passed);
    }
}

/// The same satellites in f32 (the device's precision), rounded once.
fn narrowed(sats: &[AraimSat<f64>]) -> std::vec::Vec<AraimSat<f32>> {
    sats.iter()
        .map(|s| AraimSat {
            id: s.id,
            g_enu: s.g_enu.map(|x| x as f32),
            c_int_m2: s.c_int_m2 as f32,
            c_acc_m2: s.c_acc_m2 as f32,
            b_nom_m: s.b_nom_m as f32,
            p_sat: s.p_sat,
            residual_m: s.residual_m as f32,
        })
        .collect()
}

/// f32 against f64 on App. D and a 20-satellite random sky.
#[test]
fn f32_agrees_with_f64() {
    /// Relative agreement of the f32 engine (dimensionless): the f32
    /// normal equations of a condition number ~1e2 lose about 1e-5.
    const REL_TOL: f64 = 2e-4;
    let mut rng = crate::testutil::Rng::new(32);
    let skies = [
        appendix_d_sats().to_vec(),
        random_sky(&mut rng, 20, &[System::Gps, System::Galileo], 1e-5),
    ];
    for sats in skies.iter() {
        let mut e64 = std::boxed::Box::new(Araim::<f64, 32, 256>::new());
        let mut e32 = std::boxed::Box::new(Araim::<f32, 32, 256>::new());
        let s32 = narrowed(sats);
        let ism = ge_ism(1e-4);
        let a = e64.process(&AraimConfig::default(), &ism, sats).unwrap();
        let b = e32.process(&AraimConfig::default(), &ism, &s32).unwrap();
        let close = |x: f64, y: f64| (x - y).abs() <= REL_TOL * x.abs().max(1.0);
        assert_eq!(a.modes.len(), b.modes.len());
        assert!(close(a.pl_exact.vpl_m, b.pl_exact.vpl_m));
        assert!(close(a.pl_exact.hpl_m, b.pl_exact.hpl_m));
        assert!(close(a.emt_m, b.emt_m as f64));
        assert!(close(a.sigma_v_acc_m, b.sigma_v_acc_m as f64));
        for (m, n) in a.modes.iter().zip(b.modes.iter()) {
            for q in 0..3 {
                assert!(close(m.stats.sigma_m[q], n.stats.sigma_m[q] as f64));
                assert!(close(m.stats.sigma_ss_m[q], n.stats.sigma_ss_m[q] as f64));
                assert!(close(m.stats.bias_m[q], n.stats.bias_m[q] as f64));
            }
        }
    }
}

/// f32 against f64 on stressed skies (8-19 satellites, the second
/// constellation only 2-3 satellites, so that some modes are nearly
/// unmonitorable): the f32 engine may declare a mode unmonitorable that
/// f64 still monitors (its removed rows' pivot between f64's and f32's
/// rank tolerance, 1e-9 and 1.2e-4: the mode's prior then goes to the
/// unmonitored part, never silently dropped), never the reverse; where
/// both monitor a mode its sigma_ss agrees within [`REL_TOL_STRESSED`]
/// (measured worst 0.4 %, on modes with sigma of 20-65 m, either sign);
/// and the f32 unmonitored probability is never below f64's.
#[test]
fn f32_on_stressed_skies_is_conservative_where_it_differs() {
    /// Relative agreement of sigma_ss on near-critical modes
    /// (dimensionless): f32's rounding grows as eps / pivot.
    const REL_TOL_STRESSED: f64 = 1e-2;
    /// Absolute floor for sigma_ss of a few micrometres (m).
    const ABS_TOL_M: f64 = 1e-4;
    let mut rng = crate::testutil::Rng::new(77);
    let (mut compared, mut f32_only_unmonitorable) = (0usize, 0usize);
    for trial in 0..300 {
        let n = 8 + trial % 12;
        let mut sats = random_sky(&mut rng, n, &[System::Gps, System::Galileo], 1e-4);
        let galileo = 2 + trial % 2;
        for (i, s) in sats.iter_mut().enumerate() {
            s.id.system = if i < galileo {
                System::Galileo
            } else {
                System::Gps
            };
        }
        let s32 = narrowed(&sats);
        let mut e64 = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        let mut e32 = std::boxed::Box::new(Araim::<f32, 32, 1024>::new());
        let ism = ge_ism(1e-4);
        let a = e64.process(&AraimConfig::default(), &ism, &sats).unwrap();
        let b = e32.process(&AraimConfig::default(), &ism, &s32).unwrap();
        assert_eq!(a.modes.len(), b.modes.len(), "trial {trial}");
        assert!(
            b.p_unmon >= a.p_unmon,
            "trial {trial}: {} < {}",
            b.p_unmon,
            a.p_unmon
        );
        for (m, k) in a.modes.iter().zip(b.modes.iter()) {
            assert_eq!(m.events, k.events, "trial {trial}");
            match (m.status, k.status) {
                (ModeStatus::Monitored, ModeStatus::Monitored) => {
                    compared += 1;
                    for q in 0..3 {
                        let (x, y) = (m.stats.sigma_ss_m[q], f64::from(k.stats.sigma_ss_m[q]));
                        assert!(
                            (x - y).abs() <= REL_TOL_STRESSED * x + ABS_TOL_M,
                            "trial {trial} axis {q}: f64 {x} f32 {y} ({:?})",
                            m.events
                        );
                    }
                }
                (ModeStatus::Monitored, ModeStatus::Unmonitorable { pivot, .. }) => {
                    f32_only_unmonitorable += 1;
                    assert!(pivot < 1.2e-4, "trial {trial}: pivot {pivot}");
                }
                (ModeStatus::Unmonitorable { .. }, ModeStatus::Monitored) => {
                    panic!(
                        "trial {trial}: f32 monitors a mode f64 cannot: {:?}",
                        m.events
                    )
                }
                _ => {}
            }
        }
    }
    std::println!("{compared} modes compared; {f32_only_unmonitorable} unmonitorable in f32 only");
    assert!(compared > 10_000);
}

mod fde_tests {
    use super::*;

    fn run(sats: &[AraimSat<f64>], ism: &Ism) -> (FdeDecision, AraimOutput<f64, 1024>) {
        let cfg = AraimConfig::default();
        let mut main = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        let mut scratch = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        main.process(&cfg, ism, sats).unwrap();
        let d = main.fde(&cfg, ism, sats, &mut scratch).unwrap();
        (d, scratch.output().clone())
    }

    fn sky20() -> std::vec::Vec<AraimSat<f64>> {
        let mut rng = crate::testutil::Rng::new(2020);
        let mut sats = random_sky(&mut rng, 20, &[System::Gps, System::Galileo], 1e-5);
        for s in sats.iter_mut() {
            s.residual_m = 0.0;
        }
        sats
    }

    #[test]
    fn clean_epoch_needs_no_exclusion() {
        let (d, _) = run(&sky20(), &ge_ism(1e-4));
        assert_eq!(d, FdeDecision::NoFault);
    }

    /// A 30 m step on one satellite: that satellite (or a set containing
    /// it) is excluded, and the subset passes its own tests.
    #[test]
    fn a_step_on_one_satellite_is_excluded() {
        let mut sats = sky20();
        let mut excluded_it = 0;
        for target in 0..sats.len() {
            for s in sats.iter_mut() {
                s.residual_m = 0.0;
            }
            sats[target].residual_m = 30.0;
            let (d, sub) = run(&sats, &ge_ism(1e-4));
            match d {
                FdeDecision::Excluded { sats: removed, .. } => {
                    assert!(removed & (1 << target) != 0, "target {target}: {d:?}");
                    assert!(sub.detection_passed);
                    if removed == 1 << target {
                        excluded_it += 1;
                    }
                }
                // Weakly observed satellites may pass undetected, or be
                // ambiguous; never a wrong exclusion.
                FdeDecision::NoFault | FdeDecision::Alarm(_) => {}
            }
        }
        assert!(excluded_it >= 10, "only {excluded_it} of 20 excluded");
    }

    /// `after_excluding` (availability with exclusion, issue 36) gives
    /// exactly the output the FDE leaves after excluding the same mode:
    /// on every 30 m step of sky20 that ends in an exclusion, the two
    /// outputs are equal (PLs, EMT, sigma_v,acc, availability). On the
    /// clean epoch it gives the same subset's output whatever the
    /// residuals: the fault-free residuals change no PL.
    #[test]
    fn after_excluding_is_the_fdes_excluded_subset() {
        let cfg = AraimConfig::default();
        let ism = ge_ism(1e-4);
        let mut main = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        let mut scratch = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        let mut other = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        let clean = sky20();
        let mut compared = 0;
        for target in 0..clean.len() {
            let mut sats = clean.clone();
            sats[target].residual_m = 30.0;
            main.process(&cfg, &ism, &sats).unwrap();
            let FdeDecision::Excluded { mode, .. } =
                main.fde(&cfg, &ism, &sats, &mut scratch).unwrap()
            else {
                continue;
            };
            let got = main
                .after_excluding(&cfg, &ism, &sats, mode, &mut other)
                .unwrap()
                .expect("a monitored mode");
            let want = scratch.output();
            assert_eq!(got.pl_add, want.pl_add, "target {target}");
            assert_eq!(got.pl_exact, want.pl_exact, "target {target}");
            assert_eq!(got.emt_m.to_bits(), want.emt_m.to_bits());
            assert_eq!(got.sigma_v_acc_m.to_bits(), want.sigma_v_acc_m.to_bits());
            assert_eq!(got.unavailable, want.unavailable);
            // The same exclusion on the clean epoch: the same PLs.
            main.process(&cfg, &ism, &clean).unwrap();
            let on_clean = main
                .after_excluding(&cfg, &ism, &clean, mode, &mut other)
                .unwrap()
                .expect("a monitored mode");
            assert_eq!(on_clean.pl_add, want.pl_add, "target {target}");
            compared += 1;
        }
        assert!(compared >= 10, "only {compared} exclusions");
        // Not a mode: None.
        main.process(&cfg, &ism, &clean).unwrap();
        assert!(main
            .after_excluding(&cfg, &ism, &clean, 5000, &mut other)
            .unwrap()
            .is_none());
    }

    /// A Galileo-wide fault: every Galileo range biased by a different
    /// amount (10-30 m, by PRN). A common bias would be absorbed by the
    /// Galileo clock, and a bias g_i . d by the position (then excluding
    /// either constellation is consistent: ambiguous, as the engine says).
    /// The Galileo constellation is excluded.
    #[test]
    fn a_constellation_bias_excludes_the_constellation() {
        let mut sats = sky20();
        for s in sats.iter_mut() {
            if s.id.system == System::Galileo {
                s.residual_m = 10.0 + 20.0 * ((s.id.prn as f64 * 0.37).fract());
            }
        }
        let (d, sub) = run(&sats, &ge_ism(1e-4));
        match d {
            FdeDecision::Excluded { consts, .. } => {
                assert_eq!(consts, 1 << System::Galileo.index(), "{d:?}");
                assert!(sub.detection_passed);
            }
            other => panic!("{other:?}"),
        }
    }

    /// The PLs after an exclusion (fde.rs, docs/ARAIM.md "Exclusion
    /// risk") against the dense reference: the subset, its modes
    /// re-enumerated by the reference itself, every mode a fresh dense
    /// WLS, the PL by dense bisection with 1 / N_ex of the budget, N_ex
    /// counted here as the single-event modes of the all-in-view list
    /// whose dense subset is solvable. Also: the exclusion's PLs are never
    /// below the subset's detection-only PLs.
    #[test]
    fn post_exclusion_pls_match_dense_reference_with_the_exclusion_budget() {
        let cfg = AraimConfig::default();
        let ism = ge_ism(1e-4);
        let mut checked = 0;
        for target in 0..20 {
            let mut sats = sky20();
            sats[target].residual_m = 30.0;
            let mut main = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
            let mut scratch = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
            let all = main.process(&cfg, &ism, &sats).unwrap().clone();
            let d = main.fde(&cfg, &ism, &sats, &mut scratch).unwrap();
            let FdeDecision::Excluded { sats: removed, .. } = d else {
                continue;
            };
            let n_ex = all
                .modes
                .iter()
                .filter(|m| m.events.sats.count_ones() + m.events.consts.count_ones() == 1)
                .filter(|m| {
                    let mut r = m.events.sats;
                    for (i, s) in sats.iter().enumerate() {
                        if m.events.consts & (1 << s.id.system.index()) != 0 {
                            r |= 1 << i;
                        }
                    }
                    super::brute_force::dense_subset(&sats, &ism, r).is_some()
                })
                .count();
            assert_eq!(n_ex, 22, "20 satellites + 2 constellations");
            let subset: std::vec::Vec<AraimSat<f64>> = sats
                .iter()
                .enumerate()
                .filter(|(i, _)| removed & (1 << i) == 0)
                .map(|(_, s)| *s)
                .collect();
            let mut sub_ism = Ism::default();
            for s in &subset {
                sub_ism.p_const[s.id.system.index()] = ism.p_const[s.id.system.index()];
            }
            let post = scratch.output().clone();
            assert!((scratch.integrity_budget_share() - 1.0 / n_ex as f64).abs() < 1e-15);
            super::brute_force::check_output(&subset, &sub_ism, &cfg, &post, 1.0 / n_ex as f64);
            let own = scratch.process(&cfg, &sub_ism, &subset).unwrap();
            assert!(post.pl_exact.vpl_m > own.pl_exact.vpl_m);
            assert!(post.pl_exact.hpl_m > own.pl_exact.hpl_m);
            checked += 1;
        }
        assert!(checked >= 10, "{checked}");
    }

    /// The FDE's tests-only check (early exit at a certain failure, no
    /// PLs) gives the same verdict as a full `process` for every
    /// single-satellite candidate of 20 faulted epochs.
    #[test]
    fn tests_only_check_agrees_with_full_processing() {
        let cfg = AraimConfig::default();
        let ism = ge_ism(1e-4);
        let mut a = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        let mut b = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        let mut early = 0;
        for target in 0..20 {
            let mut sats = sky20();
            sats[target].residual_m = 30.0;
            for drop in 0..20 {
                let sub: std::vec::Vec<AraimSat<f64>> = sats
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| *i != drop)
                    .map(|(_, s)| *s)
                    .collect();
                let full = a.process(&cfg, &ism, &sub).unwrap();
                let quick = b.process_tests_only(&cfg, &ism, &sub).unwrap();
                assert_eq!(full.detection_passed, quick.detection_passed);
                assert!(quick.unavailable.is_some());
                early += (quick.modes.len() < full.modes.len()) as usize;
            }
        }
        assert!(early > 100, "{early}");
    }
}

/// FDE with multi-event candidates (fde.rs, stage 2) against a dense
/// brute force: every candidate subset gets a fresh dense WLS of each of
/// its own re-enumerated fault modes (all event combinations up to its own
/// N_fault,max, the constellation/own-satellite merge), its own K_fa and
/// thresholds; the decision rule is applied to the brute-force verdicts.
mod fde_multi {
    extern crate std;
    use super::brute_force::{dense_subset, q_inv};
    use super::*;
    use nalgebra::DVector;
    use std::vec::Vec;

    /// The brute force's FDE outcome (removed-satellite masks).
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum Dense {
        NoFault,
        Excluded(u64),
        NoCandidate,
        Ambiguous,
    }

    /// A mode of an independent enumeration: its removed satellites and
    /// whether it holds one event.
    struct Mode {
        removed: u64,
        single: bool,
    }

    /// Every combination of 1..=r events of `sats` (satellites, then the
    /// constellations in use), without a constellation together with one
    /// of its own satellites (merged: same subset), r the smallest count
    /// with P(more than r events) <= P_THRES (exact Poisson-binomial
    /// counts); None when r would exceed 4.
    fn enumerate(sats: &[AraimSat<f64>], ism: &Ism, p_thres: f64) -> Option<Vec<Mode>> {
        let consts: Vec<usize> = (0..5)
            .filter(|&j| ism.p_const[j].is_some())
            .filter(|&j| sats.iter().any(|s| s.id.system.index() == j))
            .collect();
        let mut probs: Vec<f64> = sats.iter().map(|s| s.p_sat).collect();
        probs.extend(consts.iter().map(|&j| ism.p_const[j].unwrap()));
        let n_ev = probs.len();
        let mut exact = std::vec![0.0f64; n_ev + 1];
        exact[0] = 1.0;
        for &p in &probs {
            for j in (0..=n_ev).rev() {
                exact[j] = exact[j] * (1.0 - p) + if j > 0 { exact[j - 1] * p } else { 0.0 };
            }
        }
        let r = (0..=4).find(|&r| exact[r + 1..].iter().sum::<f64>() <= p_thres)?;
        let mut modes = Vec::new();
        for combo in 1u64..(1u64 << n_ev) {
            let k = combo.count_ones() as usize;
            if k > r {
                continue;
            }
            let mut removed = combo & ((1u64 << sats.len()) - 1);
            let mut clash = false;
            for (c, &j) in consts.iter().enumerate() {
                if combo & (1u64 << (sats.len() + c)) != 0 {
                    for (i, s) in sats.iter().enumerate() {
                        if s.id.system.index() == j {
                            clash |= removed & (1 << i) != 0 && combo & (1 << i) != 0;
                            removed |= 1 << i;
                        }
                    }
                }
            }
            if !clash {
                modes.push(Mode {
                    removed,
                    single: k == 1,
                });
            }
        }
        Some(modes)
    }

    /// The subset of `sats` without `removed`, with its ISM.
    fn subset(sats: &[AraimSat<f64>], ism: &Ism, removed: u64) -> (Vec<AraimSat<f64>>, Ism) {
        let sub: Vec<AraimSat<f64>> = sats
            .iter()
            .enumerate()
            .filter(|(i, _)| removed & (1 << i) == 0)
            .map(|(_, s)| *s)
            .collect();
        let mut sub_ism = Ism::default();
        for s in &sub {
            sub_ism.p_const[s.id.system.index()] = ism.p_const[s.id.system.index()];
        }
        (sub, sub_ism)
    }

    /// Whether the epoch passes all its own tests (dense, mode by mode).
    fn passes(sats: &[AraimSat<f64>], ism: &Ism, cfg: &AraimConfig) -> bool {
        let Some(d0) = dense_subset(sats, ism, 0) else {
            return false;
        };
        let Some(modes) = enumerate(sats, ism, cfg.p_thres) else {
            return false;
        };
        let dense: Vec<_> = modes
            .iter()
            .filter_map(|m| dense_subset(sats, ism, m.removed))
            .collect();
        if dense.is_empty() {
            return false;
        }
        let nm = dense.len() as f64;
        let k = [
            q_inv(cfg.pfa_hor / (4.0 * nm)),
            q_inv(cfg.pfa_hor / (4.0 * nm)),
            q_inv(cfg.pfa_vert / (2.0 * nm)),
        ];
        let y = DVector::from_iterator(sats.len(), sats.iter().map(|s| s.residual_m));
        dense.iter().all(|dk| {
            let diff = &dk.s - &d0.s;
            let sep = &diff * &y;
            (0..3).all(|q| {
                let ss = (0..sats.len())
                    .map(|i| diff[(q, i)].powi(2) * sats[i].c_acc_m2)
                    .sum::<f64>()
                    .sqrt();
                sep[q].abs() <= k[q] * ss
            })
        })
    }

    /// The brute-force FDE, and N_ex (the monitorable candidates).
    fn dense_fde(sats: &[AraimSat<f64>], ism: &Ism, cfg: &AraimConfig) -> (Dense, usize, usize) {
        if passes(sats, ism, cfg) {
            return (Dense::NoFault, 0, 0);
        }
        let modes: Vec<Mode> = enumerate(sats, ism, cfg.p_thres)
            .unwrap()
            .into_iter()
            .filter(|m| dense_subset(sats, ism, m.removed).is_some())
            .collect();
        let mut pairs = 0;
        for stage in [true, false] {
            let found: Vec<u64> = modes
                .iter()
                .filter(|m| m.single == stage)
                .map(|m| m.removed)
                .filter(|&r| {
                    let (sub, sub_ism) = subset(sats, ism, r);
                    passes(&sub, &sub_ism, cfg)
                })
                .collect();
            if !stage {
                pairs = found.iter().filter(|r| r.count_ones() == 2).count();
            }
            if found.is_empty() {
                continue;
            }
            let d = match found.iter().find(|&&c| found.iter().all(|&o| o & c == c)) {
                Some(&c) => Dense::Excluded(c),
                None => Dense::Ambiguous,
            };
            return (d, modes.len(), pairs);
        }
        (Dense::NoCandidate, modes.len(), pairs)
    }

    /// Runs the engine's FDE; checks it against the brute force (decision
    /// and N_ex). Returns the brute force's decision and its number of
    /// consistent removed sets of two satellites in stage 2.
    fn check(sats: &[AraimSat<f64>], ism: &Ism) -> (Dense, usize) {
        let cfg = AraimConfig::default();
        let mut main = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        let mut scratch = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        main.process(&cfg, ism, sats).unwrap();
        let d = main.fde(&cfg, ism, sats, &mut scratch).unwrap();
        let (want, n_ex, pairs) = dense_fde(sats, ism, &cfg);
        let got = match d {
            FdeDecision::NoFault => Dense::NoFault,
            FdeDecision::Excluded { sats: removed, .. } => {
                let share = scratch.integrity_budget_share();
                assert!((share - 1.0 / n_ex as f64).abs() < 1e-15, "N_ex {n_ex}");
                assert!(scratch.output().detection_passed);
                Dense::Excluded(removed)
            }
            FdeDecision::Alarm(FdeAlarm::NoCandidate) => Dense::NoCandidate,
            FdeDecision::Alarm(FdeAlarm::Ambiguous { .. }) => Dense::Ambiguous,
            FdeDecision::Alarm(FdeAlarm::BudgetExceeded { .. }) => {
                panic!("unlimited FDE out of budget: {d:?}")
            }
        };
        assert_eq!(got, want, "{d:?}");
        (want, pairs)
    }

    fn sky14(seed: u64) -> Vec<AraimSat<f64>> {
        let mut rng = crate::testutil::Rng::new(seed);
        let mut sats = random_sky(&mut rng, 14, &[System::Gps, System::Galileo], 1e-4);
        for s in sats.iter_mut() {
            s.residual_m = 0.0;
        }
        sats
    }

    /// Two simultaneous 40 m faults, one GPS and one Galileo satellite, on
    /// a sky whose modes include the pairs (P_sat 1e-4): no single event
    /// is consistent, the brute force finds exactly one consistent
    /// satellite pair, and the engine excludes exactly that pair (the
    /// pair + constellation candidates that also pass contain it).
    #[test]
    fn two_faults_exclude_the_one_consistent_pair() {
        let sats0 = sky14(77);
        let ism = ge_ism(1e-4);
        let gps: Vec<usize> = (0..14)
            .filter(|&i| sats0[i].id.system == System::Gps)
            .collect();
        let gal: Vec<usize> = (0..14)
            .filter(|&i| sats0[i].id.system != System::Gps)
            .collect();
        let mut pair_exclusions = 0;
        let mut cases = 0;
        for (&a, &b) in gps.iter().zip(gal.iter()) {
            let mut sats = sats0.clone();
            sats[a].residual_m = 40.0;
            sats[b].residual_m = -40.0;
            let (d, pairs) = check(&sats, &ism);
            cases += 1;
            if d == Dense::Excluded((1 << a) | (1 << b)) {
                assert_eq!(pairs, 1, "{a} {b}");
                pair_exclusions += 1;
            }
        }
        std::eprintln!("{pair_exclusions} pair exclusions of {cases}");
        assert!(pair_exclusions >= 3, "{pair_exclusions} of {cases}");
    }

    /// Random skies (8-14 satellites, G+E, pairs monitored), noise and one
    /// to three faults of 10-60 m: the engine's FDE equals the brute force
    /// on every epoch, and every outcome occurs: no fault, a single and a
    /// pair exclusion, an ambiguity between candidates that do not nest,
    /// and no consistent candidate.
    #[test]
    fn random_faults_match_brute_force_fde() {
        let mut rng = crate::testutil::Rng::new(1212);
        let ism = ge_ism(1e-4);
        let mut seen = [0usize; 5];
        for trial in 0..60 {
            let n = 8 + trial % 7;
            let mut sats = random_sky(&mut rng, n, &[System::Gps, System::Galileo], 1e-4);
            let faults = 1 + trial % 3;
            for _ in 0..faults {
                let i = (rng.uniform() * n as f64) as usize % n;
                let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                sats[i].residual_m += sign * (10.0 + 50.0 * rng.uniform());
            }
            let (d, _) = check(&sats, &ism);
            let slot = match d {
                Dense::NoFault => 0,
                Dense::Excluded(r) if r.count_ones() == 1 => 1,
                Dense::Excluded(_) => 2,
                Dense::Ambiguous => 3,
                Dense::NoCandidate => 4,
            };
            seen[slot] += 1;
        }
        std::eprintln!("no fault, single, multi, ambiguous, no candidate: {seen:?}");
        assert!(seen.iter().all(|&c| c > 0), "{seen:?}");
    }

    /// The candidates the unlimited search processes, counted by the brute
    /// force: the monitorable single-event modes, plus the multi-event
    /// ones when no single event is consistent (0 when the epoch passes).
    fn dense_candidates(sats: &[AraimSat<f64>], ism: &Ism, cfg: &AraimConfig) -> usize {
        if passes(sats, ism, cfg) {
            return 0;
        }
        let modes: Vec<Mode> = enumerate(sats, ism, cfg.p_thres)
            .unwrap()
            .into_iter()
            .filter(|m| dense_subset(sats, ism, m.removed).is_some())
            .collect();
        let singles: Vec<&Mode> = modes.iter().filter(|m| m.single).collect();
        let stage1 = singles.iter().any(|m| {
            let (sub, sub_ism) = subset(sats, ism, m.removed);
            passes(&sub, &sub_ism, cfg)
        });
        if stage1 {
            singles.len()
        } else {
            modes.len()
        }
    }

    /// The budget-limited FDE (`fde_within`) on the random epochs of
    /// `random_faults_match_brute_force_fde`, at budgets around the
    /// brute force's candidate count: `BudgetExceeded` exactly when the
    /// unlimited search needs more candidates than the budget (its
    /// `candidates` above the budget and at most the need), otherwise
    /// the unlimited outcome with the same subset output (PLs bit for
    /// bit).
    #[test]
    fn budget_limited_fde_is_the_unlimited_one_or_budget_exceeded() {
        use crate::araim::fde::FdeBudget;
        let mut rng = crate::testutil::Rng::new(1212);
        let ism = ge_ism(1e-4);
        let cfg = AraimConfig::default();
        let mut main = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        let mut scratch = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        let mut scratch_b = std::boxed::Box::new(Araim::<f64, 32, 1024>::new());
        let (mut exceeded, mut kept, mut stage2_needed) = (0, 0, 0);
        for trial in 0..60 {
            let n = 8 + trial % 7;
            let mut sats = random_sky(&mut rng, n, &[System::Gps, System::Galileo], 1e-4);
            let faults = 1 + trial % 3;
            for _ in 0..faults {
                let i = (rng.uniform() * n as f64) as usize % n;
                let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                sats[i].residual_m += sign * (10.0 + 50.0 * rng.uniform());
            }
            let need = dense_candidates(&sats, &ism, &cfg);
            main.process(&cfg, &ism, &sats).unwrap();
            let free = main.fde(&cfg, &ism, &sats, &mut scratch).unwrap();
            let singles = main
                .output()
                .modes
                .iter()
                .filter(|m| {
                    m.status == crate::araim::ModeStatus::Monitored
                        && m.events.sats.count_ones() + m.events.consts.count_ones() == 1
                })
                .count();
            if need > singles {
                stage2_needed += 1;
            }
            for budget in [0, 1, singles, need.saturating_sub(1), need, need + 1, 5000] {
                let limited = main
                    .fde_within(
                        &cfg,
                        &ism,
                        &sats,
                        &mut scratch_b,
                        FdeBudget {
                            max_candidates: budget,
                        },
                    )
                    .unwrap();
                if need > budget {
                    match limited {
                        FdeDecision::Alarm(FdeAlarm::BudgetExceeded {
                            candidates,
                            budget: b,
                        }) => {
                            assert_eq!(b, budget);
                            assert!(candidates > budget && candidates <= need, "{candidates}");
                        }
                        other => panic!("trial {trial} budget {budget} need {need}: {other:?}"),
                    }
                    exceeded += 1;
                } else {
                    assert_eq!(limited, free, "trial {trial} budget {budget} need {need}");
                    if let FdeDecision::Excluded { .. } = free {
                        assert_eq!(scratch_b.output().pl_exact, scratch.output().pl_exact);
                        assert_eq!(scratch_b.output().pl_add, scratch.output().pl_add);
                    }
                    kept += 1;
                }
            }
        }
        std::eprintln!("exceeded {exceeded}, kept {kept}, stage 2 needed {stage2_needed}");
        assert!(exceeded > 0 && kept > 0 && stage2_needed > 0);
    }
}

/// Issue 35 "Inputs": the ARAIM monitor refuses an epoch time outside the
/// GPS era (`measurement::EPOCH_TIME_S`, both epoch forms) and a satellite
/// number outside its system's range (PRN 0, 255, G33), with the snapshot
/// monitor's typed errors; the same sky at a valid time is taken.
///
/// Verifies: SAFE-INPUTS, WIRE-PrnOutOfRange
#[test]
fn monitor_refuses_absurd_times_and_satellite_numbers() {
    use super::{FdeLimits, Ism, Monitor, MonitorError, SatIsm};
    use crate::measurement::{Epoch, LinearObservation, SatId, System, EPOCH_TIME_S};
    use crate::{Config, Phase, RaimError};
    let mut obs = [LinearObservation::default(); 10];
    let mut entries = [SatIsm::default(); 10];
    for (i, r) in appendix_d::ROWS.iter().enumerate() {
        let system = if i < 5 { System::Gps } else { System::Galileo };
        let id = SatId::new(system, (i % 5 + 1) as u8);
        obs[i] = LinearObservation {
            id,
            los_enu: r.g.map(|v| -v),
            residual_m: 0.0,
            sigma_m: None,
        };
        entries[i] = SatIsm {
            id,
            sigma_ura_m: 0.75,
            sigma_ure_m: 0.5,
            b_nom_m: 0.5,
            p_sat: 1e-5,
        };
    }
    let cfg = super::AraimConfig::default();
    let solver = Config::preset(Phase::Npa);
    let ism = Ism::with(&[System::Gps, System::Galileo], 1e-4);
    let mut monitor = std::boxed::Box::new(Monitor::<f64, 16, 600>::new());
    let mut run = |t: f64, obs: &[LinearObservation], entries: &[SatIsm]| {
        monitor.epoch(
            &solver,
            &cfg,
            &ism,
            entries,
            &Epoch::linear(t, obs),
            FdeLimits::UNLIMITED,
        )
    };
    assert!(run(100.0, &obs, &entries).is_ok());
    for t in [1e300, -1e300, -1.0] {
        assert_eq!(
            run(t, &obs, &entries).err(),
            Some(MonitorError::Raim(RaimError::OutOfRange {
                field: "time_s",
                value: t,
                min: EPOCH_TIME_S.min,
                max: EPOCH_TIME_S.max
            }))
        );
    }
    for prn in [0u8, 33, 255] {
        let (mut o, mut e) = (obs, entries);
        o[2].id.prn = prn;
        e[2].id.prn = prn;
        assert_eq!(
            run(100.0, &o, &e).err(),
            Some(MonitorError::Raim(RaimError::PrnOutOfRange {
                index: 2,
                system: System::Gps,
                prn,
                max: 32
            }))
        );
    }
}

/// The monitor's entries for satellites whose variances are already known
/// (`Monitor::given`, the host's availability tools') and its availability
/// with exclusion (`Monitor::after_excluding`) are the engine's own: on
/// the ADD Appendix D sky (SPEC §9.1), `given` gives the engine's
/// all-in-view output bit for bit and holds the satellites as given;
/// after excluding each single-satellite mode it gives the engine's
/// `after_excluding` of that mode; a mode that does not exist is `None`;
/// more satellites than the monitor holds is the capacity error, and the
/// monitor then holds none. The monitor's refusal texts are the engine's
/// and the core's.
///
/// Verifies: SPEC-9.1, SAFE-INPUTS
#[test]
fn monitor_given_and_after_excluding_are_the_engines() {
    use super::{FdeLimits, Monitor, MonitorError};
    let cfg = AraimConfig::default();
    let ism = ge_ism(1e-4);
    let sats = appendix_d_sats();
    let mut monitor = std::boxed::Box::new(Monitor::<f64, 16, 600>::new());
    let mut engine = std::boxed::Box::new(Araim::<f64, 16, 600>::new());
    let mut other = std::boxed::Box::new(Araim::<f64, 16, 600>::new());
    monitor
        .given(&cfg, &ism, &sats, FdeLimits::UNLIMITED)
        .unwrap();
    engine.process(&cfg, &ism, &sats).unwrap();
    let (got, want) = (monitor.all_in_view(), engine.output());
    assert_eq!(got.pl_add, want.pl_add);
    assert_eq!(got.pl_exact, want.pl_exact);
    assert_eq!(got.emt_m.to_bits(), want.emt_m.to_bits());
    assert_eq!(got.unavailable, want.unavailable);
    assert_eq!(monitor.satellites(), &sats[..]);
    let mut modes = 0;
    for k in 0..want.modes.len() {
        let want_k = engine
            .after_excluding(&cfg, &ism, &sats, k, &mut other)
            .unwrap()
            .map(|o| (o.pl_add, o.pl_exact, o.unavailable));
        let got_k = monitor
            .after_excluding(&cfg, &ism, k)
            .unwrap()
            .map(|o| (o.pl_add, o.pl_exact, o.unavailable));
        assert_eq!(got_k, want_k, "mode {k}");
        modes += usize::from(got_k.is_some());
    }
    assert!(modes >= 10, "{modes}");
    assert!(monitor.after_excluding(&cfg, &ism, 5000).unwrap().is_none());
    let many = [sats[0]; 17];
    let e = monitor
        .given(&cfg, &ism, &many, FdeLimits::UNLIMITED)
        .unwrap_err();
    assert_eq!(
        e,
        MonitorError::Araim(AraimError::CapacityExceeded {
            have: 17,
            capacity: 16
        })
    );
    assert!(monitor.satellites().is_empty());
    assert_eq!(
        std::format!("{e}"),
        std::format!(
            "{}",
            AraimError::CapacityExceeded {
                have: 17,
                capacity: 16
            }
        )
    );
    let e = MonitorError::NotInIsm {
        id: SatId::new(System::Gps, 3),
        index: 1,
    };
    assert_eq!(
        std::format!("{e}"),
        "satellite G03 at index 1 has no ISM entry"
    );
    let r = crate::RaimError::InvalidDof { dof: 0, max: 60 };
    assert_eq!(
        std::format!("{}", MonitorError::Raim(r)),
        std::format!("{r}")
    );
}
