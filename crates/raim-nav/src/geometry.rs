//! Receiver-satellite geometry: the Earth-rotation (Sagnac) correction and
//! azimuth/elevation in the local frame (WGS-84, via raim-core's frames).

use crate::ephemeris::OMEGA_E_GPS_RAD_S;
use crate::m;
use nalgebra::Matrix3;
use raim_core::frames::{ecef_to_geodetic, enu_rotation, rotate, Geodetic};

/// Rotate a satellite position computed in the ECEF frame of the transmit
/// instant into the ECEF frame of the reception instant, `transit_s` later:
/// the Earth turned by omega_e * transit_s about Z meanwhile (IS-GPS-200
/// 20.3.3.4.3.4; ~30 m of position for a 70 ms transit).
pub fn rotate_earth(position_m: [f64; 3], transit_s: f64) -> [f64; 3] {
    let (s, c) = sin_cos_tiny(OMEGA_E_GPS_RAD_S * transit_s);
    let [x, y, z] = position_m;
    [c * x + s * y, -s * x + c * y, z]
}

/// Below this angle, [`sin_cos_tiny`] is x - x^3/6 and 1 - x^2/2, rad:
/// the Earth's rotation over 0.27 s, twice a GEO satellite's transit.
pub(crate) const TINY_ANGLE_RAD: f64 = 2e-5;

/// sin x and cos x: for |x| <= [`TINY_ANGLE_RAD`] their Taylor series to
/// x^3 and x^2, whose first terms left out (x^5/120, x^4/24) are below
/// 1.3e-21 of the result (the rounding of the result is 1.1e-16), else
/// the library's. The Earth-rotation angle of a signal's transit is such
/// an angle: a library sine and cosine cost ten times more in soft-float
/// f64 on the M4 (BENCHMARKS.md "Firmware: receiver stream").
pub(crate) fn sin_cos_tiny(x: f64) -> (f64, f64) {
    if x.abs() <= TINY_ANGLE_RAD {
        let z = x * x;
        (x - x * z * (1.0 / 6.0), 1.0 - z * 0.5)
    } else {
        m::sin_cos(x)
    }
}

/// Euclidean distance, m.
pub fn distance_m(a: [f64; 3], b: [f64; 3]) -> f64 {
    let [dx, dy, dz] = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    m::sqrt(dx * dx + dy * dy + dz * dz)
}

/// Azimuth (clockwise from north) and elevation of `sat_m` seen from
/// `rx_m`, radians, with the receiver's geodetic coordinates.
pub fn az_el(rx_m: [f64; 3], sat_m: [f64; 3]) -> (f64, f64, Geodetic) {
    az_el_from(rx_m, ecef_to_geodetic(rx_m), sat_m)
}

/// [`az_el`] with the receiver's geodetic position `g` =
/// `ecef_to_geodetic(rx_m)` given: computed once for all the satellites
/// of an epoch (ten f64 latitude iterations, soft-float on the M4).
pub fn az_el_from(rx_m: [f64; 3], g: Geodetic, sat_m: [f64; 3]) -> (f64, f64, Geodetic) {
    let (az, el) = az_el_rotated(rx_m, &enu_rotation(&g), sat_m);
    (az, el, g)
}

/// [`az_el`] with the receiver's ECEF-to-ENU rotation `r` =
/// `enu_rotation(&ecef_to_geodetic(rx_m))` given (four sines and cosines
/// of the receiver's latitude and longitude, once per epoch): azimuth and
/// elevation, radians.
pub fn az_el_rotated(rx_m: [f64; 3], r: &Matrix3<f64>, sat_m: [f64; 3]) -> (f64, f64) {
    let n = distance_m(sat_m, rx_m);
    let d = [
        (sat_m[0] - rx_m[0]) / n,
        (sat_m[1] - rx_m[1]) / n,
        (sat_m[2] - rx_m[2]) / n,
    ];
    let [e, nn, u] = rotate(r, d);
    (
        m::rem_euclid(m::atan2(e, nn), 2.0 * core::f64::consts::PI),
        libm::asin(u),
    )
}

/// The elevation of [`az_el_rotated`], to the bit, without the azimuth
/// (its arctangent and reduction to [0, 2 pi) are a fifth of a full
/// correction's soft-float cost on the M4).
pub fn elevation_rotated(rx_m: [f64; 3], r: &Matrix3<f64>, sat_m: [f64; 3]) -> f64 {
    let n = distance_m(sat_m, rx_m);
    let d = [
        (sat_m[0] - rx_m[0]) / n,
        (sat_m[1] - rx_m[1]) / n,
        (sat_m[2] - rx_m[2]) / n,
    ];
    let [_, _, u] = rotate(r, d);
    libm::asin(u)
}

#[cfg(test)]
mod tests {
    use super::*;
    use raim_core::frames::geodetic_to_ecef;

    /// A satellite 20,000 km straight up is at 90 deg; one due east on the
    /// equator's tangent plane is at azimuth 90 deg, elevation 0.
    #[test]
    fn az_el_closed_forms() {
        let g = Geodetic {
            lat_rad: 0.0,
            lon_rad: 0.0,
            height_m: 0.0,
        };
        let rx = geodetic_to_ecef(g);
        let (_, el, _) = az_el(rx, [rx[0] + 2e7, 0.0, 0.0]);
        assert!((el - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        let (az, el, _) = az_el(rx, [rx[0], 1e7, 0.0]);
        assert!((az - std::f64::consts::FRAC_PI_2).abs() < 1e-9 && el.abs() < 1e-9);
    }

    /// The transit angle's sine and cosine are the library's within its
    /// rounding (2 ulp) over transits up to 0.27 s and beyond (the
    /// library's), a rotated GPS position within 1e-8 m of the library
    /// rotation's.
    ///
    /// Verifies: RX-FORM-COST
    #[test]
    fn tiny_angles_are_the_librarys() {
        for k in 0..=3000 {
            let x = 3e-5 * f64::from(k) / 3000.0 * if k % 2 == 0 { 1.0 } else { -1.0 };
            let (s, c) = sin_cos_tiny(x);
            let (s0, c0) = libm::sincos(x);
            assert!((s - s0).abs() <= 2.0 * f64::EPSILON * s0.abs(), "{x}");
            assert!((c - c0).abs() <= 2.0 * f64::EPSILON, "{x}");
            let p = [2.0e7, -1.3e7, 1.1e7];
            let got = rotate_earth(p, x / OMEGA_E_GPS_RAD_S);
            let want = [c0 * p[0] + s0 * p[1], -s0 * p[0] + c0 * p[1], p[2]];
            assert!(distance_m(got, want) < 1e-8, "{x}");
        }
    }

    /// The rotation keeps the radius and moves a GPS satellite (26,560 km)
    /// by omega_e r tau = 7.29e-5 x 2.656e7 x 0.075 = 145 m along-track.
    #[test]
    fn earth_rotation_moves_by_omega_r_tau() {
        let p = [2.656e7, 0.0, 0.0];
        let q = rotate_earth(p, 0.075);
        assert!((distance_m(q, [0.0; 3]) - 2.656e7).abs() < 1e-6);
        let moved = distance_m(p, q);
        assert!(
            (moved - OMEGA_E_GPS_RAD_S * 2.656e7 * 0.075).abs() < 1e-3,
            "{moved}"
        );
        assert!(
            q[1] < 0.0,
            "the frame turns east, the satellite appears west"
        );
    }
}
