//! BeiDou orbits (issue 37, structural coverage): the BDS ICD's constants
//! for a MEO satellite, and the GEO branch (BDS ICD §5.2.4.12: the GEO
//! elements in a frame tilted by 5 degrees) against what a geostationary
//! orbit is, a point fixed in the Earth-fixed frame.

use super::*;

/// The BDS ICD's values, written out here (CGCS2000).
const MU_BDS_M3_S2: f64 = 3.986_004_418e14;
const OMEGA_E_BDS_RAD_S: f64 = 7.292_115e-5;

/// A BeiDou MEO satellite (C20) on the circular test orbit moves as the
/// closed form with the BDS gravitational constant and Earth rate, in
/// BeiDou time (BDT = GPST - 14 s, BDS ICD §5.2.3): 3600 s of GPS time
/// after its toe is 3586 s of BDT.
#[test]
fn a_beidou_meo_orbit_uses_the_bds_constants() {
    let k = circular(System::Beidou, 20);
    assert!(!k.is_beidou_geo());
    let a = k.sqrt_a_m05 * k.sqrt_a_m05;
    let s = k.state(1000.0 * WEEK_S + 3600.0);
    let tk = 3600.0 - 14.0;
    let n = (MU_BDS_M3_S2 / (a * a * a)).sqrt();
    let ang = (n - OMEGA_E_BDS_RAD_S) * tk;
    assert!((s.position_m[0] - a * ang.cos()).abs() < 1e-6, "{s:?}");
    assert!((s.position_m[1] - a * ang.sin()).abs() < 1e-6, "{s:?}");
}

/// GEO satellites are C01-C05 and C59-C63 (BDS-2 and BDS-3), no other
/// BeiDou number and no other system.
#[test]
fn beidou_geo_numbers() {
    for (system, prn, geo) in [
        (System::Beidou, 1, true),
        (System::Beidou, 5, true),
        (System::Beidou, 6, false),
        (System::Beidou, 58, false),
        (System::Beidou, 59, true),
        (System::Beidou, 63, true),
        (System::Beidou, 64, false),
        (System::Gps, 3, false),
    ] {
        assert_eq!(
            circular(system, prn).is_beidou_geo(),
            geo,
            "{system:?} {prn}"
        );
    }
}

/// A GEO satellite (C03) broadcast with inclination -5 degrees in the
/// ICD's tilted frame and the geostationary radius (mean motion = the
/// Earth rate) is equatorial and does not move in the Earth-fixed frame:
/// the same point at its toe and 6 h later, at the orbit's radius.
#[test]
fn a_beidou_geo_orbit_is_fixed_in_the_earth_frame() {
    let a = (MU_BDS_M3_S2 / (OMEGA_E_BDS_RAD_S * OMEGA_E_BDS_RAD_S)).cbrt();
    let k = Kepler {
        sqrt_a_m05: a.sqrt(),
        i0_rad: (-5.0f64).to_radians(),
        m0_rad: 0.7,
        ..circular(System::Beidou, 3)
    };
    assert!(k.is_beidou_geo());
    let t0 = 1000.0 * WEEK_S;
    let p0 = k.state(t0).position_m;
    let p1 = k.state(t0 + 6.0 * 3600.0).position_m;
    let r = (p0[0] * p0[0] + p0[1] * p0[1] + p0[2] * p0[2]).sqrt();
    assert!((r - a).abs() < 1e-6, "{r} {a}");
    assert!(p0[2].abs() < 1e-6, "{p0:?}");
    for i in 0..3 {
        assert!((p0[i] - p1[i]).abs() < 1e-4, "{p0:?} {p1:?}");
    }
    // At toe the satellite is at the argument of latitude m0 in the
    // equatorial plane.
    assert!((p0[1].atan2(p0[0]) - 0.7).abs() < 1e-9, "{p0:?}");
}
