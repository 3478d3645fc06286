//! The geodetic update's fallback on a step west across the antimeridian,
//! and the stall rule's four conditions.

extern crate std;

use super::*;
use crate::frames::ecef_to_geodetic;

/// 1e-8 rad east of -pi, then 0.9 m west: the first-order longitude
/// leaves (-pi, pi] below -pi, so the update falls back to the iterative
/// conversion and agrees with the plain one (1e-11 rad, 1e-4 m), the
/// longitude wrapped to near +pi.
#[test]
fn geodetic_update_west_across_the_antimeridian() {
    use crate::frames::geodetic_to_ecef;
    let pi = core::f64::consts::PI;
    let p = geodetic_to_ecef(Geodetic {
        lat_rad: -0.7,
        lon_rad: -pi + 1e-8,
        height_m: 80.0,
    });
    let l = Linearisation::at(p, None);
    let west = unrotate(&l.rotation, [-0.9, 0.0, 0.0]);
    let x = [p[0] + west[0], p[1] + west[1], p[2] + west[2]];
    let near = l.geodetic_of(x);
    let exact = ecef_to_geodetic(x);
    assert!((near.lat_rad - exact.lat_rad).abs() < 1e-11);
    assert!((near.lon_rad - exact.lon_rad).abs() < 1e-11);
    assert!((near.height_m - exact.height_m).abs() < 1e-4);
    assert!(near.lon_rad > pi - 1e-6, "{near:?}");
}

/// Stalled only in a precision coarser than f64, on two parity
/// iterations, with a step under STALL_MAX_M that no longer shrinks by
/// STALL_RATIO; in f64 never.
#[test]
fn stall_needs_all_four_conditions() {
    let small = 0.5 * STALL_MAX_M;
    assert!(stalled::<f32>(true, small, small));
    assert!(!stalled::<f64>(true, small, small));
    assert!(!stalled::<f32>(false, small, small));
    assert!(!stalled::<f32>(true, 2.0 * STALL_MAX_M, 2.0 * STALL_MAX_M));
    // Still shrinking: step < STALL_RATIO x the last one.
    assert!(!stalled::<f32>(true, 0.4 * small, small));
    // NaN last step: not shrinking, so stalled (it ends the iteration).
    assert!(stalled::<f32>(true, small, f64::NAN));
}
