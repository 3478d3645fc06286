//! The ARAIM benchmark inputs, shared by raim-core's `benches/araim.rs`
//! and the peer comparison in `peer-bench/` (included there by path), so
//! both engines see the same skies.

use raim_core::araim::{error_model, AraimSat};
use raim_core::{SatId, System};

/// SPEC §9.1: (G row ENU, C_int, C_acc), GPS 1-5 then Galileo 1-5.
pub const APPENDIX_D: [([f64; 3], f64, f64); 10] = [
    ([0.0225, 0.9951, -0.0966], 3.8865, 3.5740),
    ([0.6750, -0.6900, -0.2612], 1.4377, 1.1252),
    ([0.0723, -0.6601, -0.7477], 0.8604, 0.5479),
    ([-0.9398, 0.2553, -0.2269], 1.6383, 1.3258),
    ([-0.5907, -0.7539, -0.2877], 1.3229, 1.0104),
    ([-0.3236, -0.0354, -0.9455], 0.8434, 0.5309),
    ([-0.6748, 0.4356, -0.5957], 0.8963, 0.5838),
    ([0.0938, -0.7004, -0.7075], 0.8669, 0.5544),
    ([0.5571, 0.3088, -0.7709], 0.8573, 0.5448),
    ([0.6622, 0.6958, -0.2780], 1.3616, 1.0491),
];

pub fn appendix_d() -> Vec<AraimSat<f64>> {
    APPENDIX_D
        .iter()
        .enumerate()
        .map(|(i, &(g, c_int, c_acc))| AraimSat {
            id: SatId {
                system: if i < 5 { System::Gps } else { System::Galileo },
                prn: (i % 5 + 1) as u8,
            },
            g_enu: g,
            c_int_m2: c_int,
            c_acc_m2: c_acc,
            b_nom_m: 0.5,
            p_sat: 1e-5,
            residual_m: 0.0,
        })
        .collect()
}

/// `per` satellites of each of GPS and Galileo: azimuths on a golden-angle
/// spiral, elevations 10..85 deg, the ADD error model (sigma_URA 0.75 m,
/// sigma_URE 0.5 m), b_nom 0.5 m. The peer bench builds the same sky.
pub fn sky(per: usize, p_sat: f64) -> Vec<AraimSat<f64>> {
    let n = 2 * per;
    (0..n)
        .map(|i| {
            let az = (i as f64 * 137.507_764_f64).rem_euclid(360.0).to_radians();
            let el = (10.0 + 75.0 * ((i * 7) % n) as f64 / n as f64).to_radians();
            let (c_int, c_acc) = error_model::variances_m2(el, 0.75, 0.5);
            AraimSat {
                id: SatId {
                    system: if i < per {
                        System::Gps
                    } else {
                        System::Galileo
                    },
                    prn: (i % per + 1) as u8,
                },
                g_enu: AraimSat::g_from_az_el(az, el),
                c_int_m2: c_int,
                c_acc_m2: c_acc,
                b_nom_m: 0.5,
                p_sat,
                residual_m: 0.0,
            }
        })
        .collect()
}
