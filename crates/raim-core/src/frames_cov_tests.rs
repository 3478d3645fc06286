//! The conversions at the Earth's centre and on the polar axis.

use super::*;

/// At the centre: Bowring's latitude has no direction and returns 0 (as
/// for NaN input); the geodetic latitude and height are undefined there
/// (every meridian's normal passes through the centre), and the iterative
/// conversion says so with NaN rather than a number.
#[test]
fn the_centre_and_nan() {
    assert_eq!(bowring_latitude_rad([0.0; 3]), 0.0);
    assert_eq!(bowring_latitude_rad([f64::NAN, 0.0, 1.0]), 0.0);
    let g = ecef_to_geodetic([0.0; 3]);
    assert!(g.lat_rad.is_nan() && g.height_m.is_nan(), "{g:?}");
}

/// On the polar axis (p = 0, z > 0): latitude pi/2 and the height above
/// the pole, z - b with b = a (1 - f).
#[test]
fn the_polar_axis() {
    let b = WGS84_A_M * (1.0 - WGS84_F);
    let g = ecef_to_geodetic([0.0, 0.0, b + 250.0]);
    assert!((g.lat_rad - core::f64::consts::FRAC_PI_2).abs() < 1e-12);
    assert!((g.height_m - 250.0).abs() < 1e-6, "{g:?}");
}
