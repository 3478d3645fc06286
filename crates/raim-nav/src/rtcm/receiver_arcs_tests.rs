//! The stream receiver's GLONASS arcs when they are all taken (issue 37,
//! structural coverage): a device that runs for hours sees more GLONASS
//! ephemerides than it keeps arcs (a new set every 30 min a satellite),
//! so an arc that no satellite of the epoch uses gives way, and with
//! every arc used in the epoch the orbit is integrated from t_b. Each
//! state is checked against the ICD integration from t_b
//! (`GlonassEphemeris::state`), which the arcs reproduce to the bit.

use std::vec::Vec;

use super::{GlonassArcs, GLONASS_ARCS};
use crate::glonass::{GlonassEphemeris, GlonassIcdFields};

/// One more distinct GLONASS set than the arcs hold: slots 1..=27 in
/// turn, each set its own t_b (a minute apart) and position.
fn sets(t0: f64) -> Vec<GlonassEphemeris> {
    (0..=GLONASS_ARCS)
        .map(|k| {
            let f = GlonassIcdFields {
                slot: (k % 27) as u8 + 1,
                frequency_channel: 1,
                tb_gps_s: t0 + 60.0 * k as f64,
                x_km: 10_000.0 + k as f64,
                y_km: -15_000.0,
                z_km: 6_000.0,
                vx_km_s: 1.5,
                vy_km_s: 0.8,
                vz_km_s: -3.4,
                ax_km_s2: 0.0,
                ay_km_s2: 0.0,
                az_km_s2: 0.0,
                tau_n_s: 1e-5,
                gamma_n: 0.0,
                unhealthy: false,
            };
            GlonassEphemeris::from_icd(&f).unwrap()
        })
        .collect()
}

/// The arcs' state of `g` at `t` is the ICD integration's, to the bit.
fn check(arcs: &mut GlonassArcs, g: &GlonassEphemeris, t: f64) {
    let (got, _velocity_m_s) = arcs.state(g, t);
    let want = g.state(t);
    for i in 0..3 {
        assert_eq!(
            got.position_m[i].to_bits(),
            want.position_m[i].to_bits(),
            "{i}"
        );
    }
    assert_eq!(got.clock_s.to_bits(), want.clock_s.to_bits());
}

/// With every arc used in the epoch, one more set is integrated from
/// t_b; in the next epoch it takes the place of an arc that epoch does
/// not use, and the set whose arc it took is integrated anew.
#[test]
fn glonass_arcs_give_way_when_all_are_taken() {
    let t0 = 1e9;
    let all = sets(t0);
    let (last, kept) = all.split_last().unwrap();
    let mut arcs = GlonassArcs::new();
    let t = t0 + 900.0;
    for g in kept {
        check(&mut arcs, g, t);
    }
    check(&mut arcs, last, t);
    assert_eq!(arcs.arcs.len(), GLONASS_ARCS);
    assert!(!arcs.arcs.iter().any(|(a, _)| a.ephemeris() == last));

    arcs.next_epoch();
    check(&mut arcs, last, t + 1.0);
    assert!(arcs.arcs.iter().any(|(a, _)| a.ephemeris() == last));
    assert!(!arcs.arcs.iter().any(|(a, _)| a.ephemeris() == &kept[0]));
    check(&mut arcs, &kept[0], t + 1.0);
    assert!(arcs.arcs.iter().any(|(a, _)| a.ephemeris() == &kept[0]));
    for g in &kept[2..] {
        check(&mut arcs, g, t + 2.0);
    }
    assert_eq!(arcs.arcs.len(), GLONASS_ARCS);
}
