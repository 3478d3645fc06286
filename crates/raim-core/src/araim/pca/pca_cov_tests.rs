//! The PCA monitor's window edge cases: a window of one epoch never
//! tests (a covariance needs two epochs), and keeping every component
//! (`variance_share` 1) leaves no redundant direction to test.

extern crate std;
use std::vec::Vec;

use super::*;
use crate::araim::AraimSat;
use crate::measurement::{SatId, System};

/// A uniform number in [-0.5, 0.5) from (t, i) (xorshift64*), so that the
/// per-satellite noise has a full-rank covariance.
fn noise(t: usize, i: usize) -> f64 {
    let mut x = (t as u64 * 1_000_003 + i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    x ^= x >> 12;
    x ^= x << 25;
    x ^= x >> 27;
    ((x.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64) / (1u64 << 53) as f64 - 0.5
}

/// Twelve satellites (6 GPS, 6 Galileo) with a common clock walk and
/// independent per-satellite noise as residuals at epoch `t`.
fn epoch(t: usize) -> Vec<AraimSat<f64>> {
    (0..12)
        .map(|i| {
            let system = if i < 6 { System::Gps } else { System::Galileo };
            let az = (i as f64 * 137.5f64).to_radians();
            let el = (15.0 + (i as f64 * 23.0) % 70.0).to_radians();
            let clock = 2.0 * (t as f64 * 0.7).sin();
            AraimSat {
                id: SatId {
                    system,
                    prn: (i + 1) as u8,
                },
                g_enu: AraimSat::g_from_az_el(az, el),
                c_int_m2: 1.0,
                c_acc_m2: 1.0,
                b_nom_m: 0.0,
                p_sat: 1e-5,
                residual_m: clock + noise(t, i),
            }
        })
        .collect()
}

#[test]
fn a_one_epoch_window_never_tests() {
    let mut pca = Pca::<f64, 16, 1>::new();
    let cfg = PcaConfig::default();
    for t in 0..4 {
        let out = pca.process(&cfg, 30.0 * t as f64, &epoch(t)).unwrap();
        let complete = if t == 0 { 0 } else { 12 };
        assert_eq!(
            out,
            PcaOutcome::WarmingUp {
                epochs: t.min(1),
                complete
            },
            "epoch {t}"
        );
    }
}

#[test]
fn keeping_every_component_tests_nothing() {
    const W: usize = 20;
    let mut pca = std::boxed::Box::new(Pca::<f64, 16, W>::new());
    let cfg = PcaConfig {
        variance_share: 1.0,
        ..PcaConfig::default()
    };
    let mut tested = 0;
    for t in 0..W + 3 {
        if let PcaOutcome::Tested(r) = pca.process(&cfg, 30.0 * t as f64, &epoch(t)).unwrap() {
            tested += 1;
            assert_eq!(r.k, r.n_complete, "epoch {t}");
            assert_eq!((r.ratio, r.fault), (0.0, false), "epoch {t}");
        }
    }
    assert_eq!(tested, 3);
}
