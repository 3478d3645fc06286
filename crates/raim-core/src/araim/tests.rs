//! ARAIM tests: the ADD v3.0 Appendix D vector (SPEC §9.1), a dense
//! brute-force reference, the enumeration against all subsets, bad input
//! and f32 against f64.

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

fn appendix_d_sats() -> [AraimSat<f64>; 10] {
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

    fn run() -> AraimOutput<f64, 64> {
        let mut engine = Araim::<f64, 16, 64>::new();
        let sats = appendix_d_sats();
        engine
            .process(&AraimConfig::default(), &ge_ism(1e-4), &sats)
            .unwrap()
            .clone()
    }

    #[test]
    fn twelve_modes_and_k_fa() {
        let out = run();
        assert_eq!(out.modes.len(), 12);
        assert_eq!(out.n_monitored, 12);
        assert_eq!(out.max_faults, 1);
        assert!((out.k_fa[2] - 5.1083).abs() < 1e-4, "K_fa,3 {}", out.k_fa[2]);
        // The 10 single-satellite modes then the 2 constellation modes.
        for (i, m) in out.modes.iter().enumerate().take(10) {
            assert_eq!(m.events.sats, 1 << i);
            assert_eq!(m.events.consts, 0);
            assert_eq!(m.events.prior, 1e-5);
        }
        assert_eq!(out.modes[10].events.consts, 1);
        assert_eq!(out.modes[11].events.consts, 2);
    }

    #[test]
    fn constellation_modes_match_published_intermediates() {
        let out = run();
        // (sigma_3, sigma_ss,3, b_3): GPS-constellation mode, then Galileo.
        let published = [(2.5760, 1.5307, 2.8935), (2.5577, 1.5292, 2.0875)];
        for (m, (sigma, sigma_ss, b)) in out.modes[10..].iter().zip(published) {
            assert!((m.stats.sigma_m[2] - sigma).abs() <= TOL_INTERMEDIATE_M, "{m:?}");
            assert!((m.stats.sigma_ss_m[2] - sigma_ss).abs() <= TOL_INTERMEDIATE_M, "{m:?}");
            assert!((m.stats.bias_m[2] - b).abs() <= TOL_INTERMEDIATE_M, "{m:?}");
        }
    }

    #[test]
    fn vpl_emt_sigma_acc_match_published() {
        let out = run();
        assert!((out.pl_exact.vpl_m - 19.217).abs() <= 1e-3, "{}", out.pl_exact.vpl_m);
        assert!((out.pl_add.vpl_m - 19.2).abs() <= TOL_PRINTED_M, "{}", out.pl_add.vpl_m);
        assert!((out.pl_exact.vpl_m - 19.2).abs() <= TOL_PRINTED_M);
        assert!((out.emt_m - 7.8).abs() <= TOL_PRINTED_M, "EMT {}", out.emt_m);
        assert!((out.sigma_v_acc_m - 1.47).abs() <= TOL_PRINTED_M, "{}", out.sigma_v_acc_m);
        assert!(out.available(), "{:?}", out.unavailable);
        assert!(out.detection_passed);
    }

    #[test]
    fn hpl_exact_root_and_add_bracket_output() {
        let out = run();
        let root = out.pl_exact.hpl_m;
        assert!((root - 14.416).abs() <= TOL_HPL_ROOT_M, "HPL root {root}");
        assert!((out.pl_exact.hpl_axes_m[0] - 9.523).abs() <= TOL_HPL_ROOT_M);
        assert!((out.pl_exact.hpl_axes_m[1] - 10.823).abs() <= TOL_HPL_ROOT_M);
        let add = out.pl_add.hpl_m;
        assert!(root <= add && add <= root + 0.1, "ADD output {add}, root {root}");
        // Per axis the bracket's upper end is within TOL_PL above the root.
        for q in 0..2 {
            let (e, a) = (out.pl_exact.hpl_axes_m[q], out.pl_add.hpl_axes_m[q]);
            assert!(e <= a && a <= e + 0.05 + 1e-9, "axis {q}: {a} vs {e}");
        }
    }
}
