//! The ADD v3.0 Appendix D vector (`host-tests/vectors/add_v3_appendix_d.json`,
//! the epoch format of docs/FORMATS.md with the ARAIM fields) through
//! raim-core's ARAIM engine, against the published numbers it carries.

use raim_core::araim::{Araim, AraimConfig, AraimSat, Ism};
use raim_core::{SatId, System};
use serde_json::Value;

fn f(v: &Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("missing {key}"))
}

/// Verifies: SPEC-9.1
#[test]
fn add_v3_appendix_d_vector() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/vectors/add_v3_appendix_d.json"
    ))
    .unwrap();
    let epoch: Value = serde_json::from_str(&text).unwrap();
    let sats: Vec<AraimSat<f64>> = epoch["sats"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            let sys = s["sys"].as_str().unwrap().chars().next().unwrap();
            let g: Vec<f64> = s["g_enu"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            AraimSat {
                id: SatId {
                    system: System::from_letter(sys).unwrap(),
                    prn: s["prn"].as_u64().unwrap() as u8,
                },
                g_enu: [g[0], g[1], g[2]],
                c_int_m2: f(s, "c_int_m2"),
                c_acc_m2: f(s, "c_acc_m2"),
                b_nom_m: f(s, "b_nom_m"),
                p_sat: f(s, "p_sat"),
                residual_m: f(s, "residual_m"),
            }
        })
        .collect();
    let mut ism = Ism::default();
    for (letter, p) in epoch["ism"]["p_const"].as_object().unwrap() {
        let system = System::from_letter(letter.chars().next().unwrap()).unwrap();
        ism.p_const[system.index()] = p.as_f64();
    }
    let c = &epoch["araim_config"];
    let cfg = AraimConfig {
        phmi_vert: f(c, "phmi_vert"),
        phmi_hor: f(c, "phmi_hor"),
        pfa_vert: f(c, "pfa_vert"),
        pfa_hor: f(c, "pfa_hor"),
        p_thres: f(c, "p_thres"),
        p_emt: f(c, "p_emt"),
        val_m: f(c, "val_m"),
        hal_m: f(c, "hal_m"),
        tol_pl_m: f(c, "tol_pl_m"),
        ..AraimConfig::default()
    };
    let mut engine = Box::new(Araim::<f64, 32, 256>::new());
    let out = engine.process(&cfg, &ism, &sats).unwrap();
    let e = &epoch["expected"];
    let tol = &e["tolerances"];
    let (ti, tp) = (f(tol, "intermediate_m"), f(tol, "printed_m"));
    assert_eq!(out.modes.len() as u64, e["modes"].as_u64().unwrap());
    assert!((out.k_fa[2] - f(e, "k_fa_vert")).abs() <= 1e-4);
    for (mode, key) in out.modes[10..]
        .iter()
        .zip(["gps_constellation_mode", "galileo_constellation_mode"])
    {
        let p = &e[key];
        assert!((mode.stats.sigma_m[2] - f(p, "sigma_3_m")).abs() <= ti);
        assert!((mode.stats.sigma_ss_m[2] - f(p, "sigma_ss_3_m")).abs() <= ti);
        assert!((mode.stats.bias_m[2] - f(p, "b_3_m")).abs() <= ti);
    }
    assert!((out.pl_add.vpl_m - f(e, "vpl_m")).abs() <= tp);
    assert!((out.emt_m - f(e, "emt_m")).abs() <= tp);
    assert!((out.sigma_v_acc_m - f(e, "sigma_v_acc_m")).abs() <= tp);
    let root = out.pl_exact.hpl_m;
    assert!((root - f(e, "hpl_root_m")).abs() <= f(tol, "hpl_root_m"));
    assert!(root <= out.pl_add.hpl_m && out.pl_add.hpl_m <= root + f(tol, "hpl_add_above_root_m"));
    // The printed 14.5 is the ADD output rounded to 0.1 m.
    assert!((out.pl_add.hpl_m - f(e, "hpl_m")).abs() <= tp + 0.01);
}
