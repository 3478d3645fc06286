//! WGS-84 frames: ECEF to geodetic and the local East-North-Up rotation used
//! for protection levels (SPEC §6) and elevation-dependent sigmas (SPEC §1).

use nalgebra::{Matrix3, Vector3};

/// WGS-84 semi-major axis, m.
pub const WGS84_A_M: f64 = 6_378_137.0;
/// WGS-84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;

/// Geodetic latitude, longitude (rad) and ellipsoidal height (m).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Geodetic {
    /// Geodetic latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad (east positive).
    pub lon_rad: f64,
    /// Height above the WGS-84 ellipsoid, m.
    pub height_m: f64,
}

/// ECEF to geodetic by fixed-point iteration on latitude (converges to
/// < 1e-12 rad in 6 iterations for any point near the Earth's surface;
/// 10 are done). At the Earth's centre, where the latitude is undefined,
/// lon = 0 and the latitude and height are NaN (frames_cov_tests.rs).
pub fn ecef_to_geodetic(ecef_m: [f64; 3]) -> Geodetic {
    let [x, y, z] = ecef_m;
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let p = libm::sqrt(x * x + y * y);
    let lat_rad = libm::atan2(z, p * (1.0 - e2));
    iterate_latitude(ecef_m, lat_rad, 10, 0.0)
}

/// Latitude steps below this (rad, 0.6 mm on the ground) end
/// [`ecef_to_geodetic_from`]; each step contracts the error by ~e^2 = 6.7e-3,
/// so the latitude returned is within ~1e-12 rad of the fixed point.
pub const GEODETIC_STEP_TOL_RAD: f64 = 1e-10;

/// [`ecef_to_geodetic`] started from a nearby point's latitude `lat0_rad`
/// (Gauss-Newton's previous linearisation): the fixed point is reached in
/// 2-4 iterations instead of 10 (docs/CORE.md, "Do the work once").
pub fn ecef_to_geodetic_from(ecef_m: [f64; 3], lat0_rad: f64) -> Geodetic {
    iterate_latitude(ecef_m, lat0_rad, 10, GEODETIC_STEP_TOL_RAD)
}

/// Bowring's closed-form latitude (one step from the parametric latitude,
/// with its sine and cosine formed algebraically): within ~1e-10 rad of the
/// fixed point for heights below 10 km. A start for
/// [`ecef_to_geodetic_from`] that needs one or two iterations instead of
/// ten: 2 square roots and 1 atan2 instead of ~40 calls, which matters on
/// the M4F where each f64 call is a software routine.
pub fn bowring_latitude_rad(ecef_m: [f64; 3]) -> f64 {
    let [x, y, z] = ecef_m;
    let a = WGS84_A_M;
    let b = a * (1.0 - WGS84_F);
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let ep2 = e2 / (1.0 - e2);
    let p = libm::sqrt(x * x + y * y);
    let (za, pb) = (z * a, p * b);
    let q = libm::sqrt(za * za + pb * pb);
    if !(q > 0.0) {
        return 0.0;
    }
    let (st, ct) = (za / q, pb / q);
    libm::atan2(z + ep2 * b * st * st * st, p - e2 * a * ct * ct * ct)
}

fn iterate_latitude(ecef_m: [f64; 3], lat0_rad: f64, max_iter: u32, tol_rad: f64) -> Geodetic {
    let [x, y, z] = ecef_m;
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let p = libm::sqrt(x * x + y * y);
    let lon_rad = libm::atan2(y, x);
    let mut lat_rad = lat0_rad;
    let mut height_m = 0.0;
    for _ in 0..max_iter {
        let s = libm::sin(lat_rad);
        let c = libm::cos(lat_rad);
        let n = WGS84_A_M / libm::sqrt(1.0 - e2 * s * s);
        height_m = if libm::fabs(c) > 1e-9 {
            p / c - n
        } else {
            libm::fabs(z) - n * (1.0 - e2)
        };
        let next = libm::atan2(z, p * (1.0 - e2 * n / (n + height_m)));
        let step = libm::fabs(next - lat_rad);
        lat_rad = next;
        if step < tol_rad {
            break;
        }
    }
    // The height at the final latitude, in the form that stays well
    // conditioned at the poles (p / cos(lat) does not):
    // h = p cos(lat) + z sin(lat) - a sqrt(1 - e^2 sin^2 lat).
    let (s, c) = (libm::sin(lat_rad), libm::cos(lat_rad));
    if p > 0.0 || z != 0.0 {
        height_m = p * c + z * s - WGS84_A_M * libm::sqrt(1.0 - e2 * s * s);
    }
    Geodetic {
        lat_rad,
        lon_rad,
        height_m,
    }
}

/// Geodetic to ECEF.
pub fn geodetic_to_ecef(g: Geodetic) -> [f64; 3] {
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let (sl, cl) = (libm::sin(g.lat_rad), libm::cos(g.lat_rad));
    let n = WGS84_A_M / libm::sqrt(1.0 - e2 * sl * sl);
    [
        (n + g.height_m) * cl * libm::cos(g.lon_rad),
        (n + g.height_m) * cl * libm::sin(g.lon_rad),
        (n * (1.0 - e2) + g.height_m) * sl,
    ]
}

/// Rotation from ECEF to local ENU at a geodetic point: rows are the
/// East, North and Up unit vectors expressed in ECEF.
pub fn enu_rotation(g: &Geodetic) -> Matrix3<f64> {
    let (sl, cl) = (libm::sin(g.lat_rad), libm::cos(g.lat_rad));
    let (so, co) = (libm::sin(g.lon_rad), libm::cos(g.lon_rad));
    Matrix3::new(-so, co, 0.0, -sl * co, -sl * so, cl, cl * co, cl * so, sl)
}

/// Rotate an ECEF vector into ENU.
pub fn rotate<T: crate::real::Real>(r: &Matrix3<T>, v: [T; 3]) -> [T; 3] {
    (r * Vector3::from(v)).into()
}

/// Rotate an ENU vector back into ECEF (the transpose of the rotation).
pub fn unrotate(r: &Matrix3<f64>, v: [f64; 3]) -> [f64; 3] {
    (r.transpose() * Vector3::from(v)).into()
}

/// Elevation (rad) of an ENU unit vector.
pub fn elevation_rad(enu: [f64; 3]) -> f64 {
    elevation::<f64>(enu)
}

/// Below this ratio |up| / horizontal, [`elevation`] takes `atan` of the
/// ratio directly. `libm`'s `atan2(y, x)` for finite x > 0 and
/// |y / x| <= 2^26 (its f32 form's limit; f64's is 2^64) returns exactly
/// sign(y) atan(|y / x|), and `atan` is odd bit for bit, so below the limit
/// the shortcut is `atan2` bit for bit (test
/// `elevation_shortcut_equals_atan2_bit_for_bit`); 2^24 is an elevation
/// within 6e-8 rad of the zenith.
const ELEVATION_ATAN_MAX_RATIO: f64 = 16_777_216.0;

/// [`elevation_rad`] in the precision `T`: atan2(up, |horizontal|), by
/// `atan(up / horizontal)` where that is the same bits (the
/// `atan2` wrapper's special-case tests were ~3 % of a clean linearised
/// epoch); at the zenith, a non-finite or NaN input, `atan2` itself.
pub fn elevation<T: crate::real::Real>(enu: [T; 3]) -> T {
    let up = enu[2];
    let horizontal = (enu[0] * enu[0] + enu[1] * enu[1]).sqrt();
    if horizontal > T::zero()
        && horizontal < T::of(f64::INFINITY)
        && up.abs() <= horizontal * T::of(ELEVATION_ATAN_MAX_RATIO)
    {
        (up / horizontal).atan_m()
    } else {
        up.atan2_m(horizontal)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`elevation`]'s `atan` shortcut against `atan2` itself, bit for bit,
    /// in f64 and f32: 200,000 directions (unit and not, every octant,
    /// elevations from the nadir to the zenith including the ratio limit's
    /// neighbourhood) and the special inputs.
    #[test]
    fn elevation_shortcut_equals_atan2_bit_for_bit() {
        let check = |v: [f64; 3]| {
            let h = (v[0] * v[0] + v[1] * v[1]).sqrt();
            let want = libm::atan2(v[2], h);
            assert_eq!(elevation(v).to_bits(), want.to_bits(), "f64 {v:?}");
            let w = v.map(|x| x as f32);
            let hf = (w[0] * w[0] + w[1] * w[1]).sqrt();
            let wantf = libm::atan2f(w[2], hf);
            assert_eq!(elevation(w).to_bits(), wantf.to_bits(), "f32 {w:?}");
        };
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for i in 0..200_000 {
            let (a, b, c) = (next() * 2.0 - 1.0, next() * 2.0 - 1.0, next() * 2.0 - 1.0);
            // Every tenth: the horizontal part scaled down, to probe large
            // ratios up to and past the limit.
            let s = if i % 10 == 0 {
                2f64.powi(-(i % 40))
            } else {
                1.0
            };
            check([a * s, b * s, c]);
        }
        let lim = ELEVATION_ATAN_MAX_RATIO;
        for v in [
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, -0.0],
            [0.0, 1.0, lim],
            [0.0, 1.0, lim * (1.0 + f64::EPSILON)],
            [0.0, 1.0, -lim],
            [1e-30, 0.0, 1.0],
            [f64::NAN, 0.0, 1.0],
            [0.0, 0.0, f64::NAN],
            [f64::INFINITY, 0.0, 1.0],
            [1.0, 0.0, f64::INFINITY],
        ] {
            check(v);
        }
    }

    #[test]
    fn geodetic_round_trip() {
        // The 0759 station's header APPROX POSITION (shared/data, RINEX 2).
        let ecef = [-3_962_108.673, 3_381_309.574, 3_668_678.638];
        let g = ecef_to_geodetic(ecef);
        let back = geodetic_to_ecef(g);
        for i in 0..3 {
            assert!((back[i] - ecef[i]).abs() < 1e-6, "{back:?}");
        }
        // Published WGS-84 example: lat 0, lon 0, h 0 -> (a, 0, 0).
        let g0 = ecef_to_geodetic([WGS84_A_M, 0.0, 0.0]);
        assert!(g0.lat_rad.abs() < 1e-14 && g0.height_m.abs() < 1e-6);
        // North pole: z = b.
        let b = WGS84_A_M * (1.0 - WGS84_F);
        let gp = ecef_to_geodetic([0.0, 0.0, b]);
        assert!((gp.lat_rad - core::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!(gp.height_m.abs() < 1e-6, "{gp:?}");
    }

    /// Started from a latitude 1.6e-5 rad off (a point 100 m away), the
    /// early-stopping iteration agrees with the full one: latitude to
    /// 1e-12 rad, height to 1e-5 m.
    #[test]
    fn geodetic_from_a_nearby_latitude_matches_the_full_iteration() {
        const LAT_TOL_RAD: f64 = 1e-12;
        const HEIGHT_TOL_M: f64 = 1e-5;
        for ecef in [
            [-3_962_108.673, 3_381_309.574, 3_668_678.638],
            [3_513_638.0, 778_956.0, 5_248_216.0],
            [6_378_137.0 + 11_000.0, 10.0, -2_000.0],
            [1_000.0, 2_000.0, -6_356_000.0],
        ] {
            let full = ecef_to_geodetic(ecef);
            for off in [-1.6e-5, 0.0, 1.6e-5] {
                let near = ecef_to_geodetic_from(ecef, full.lat_rad + off);
                assert!(
                    (near.lat_rad - full.lat_rad).abs() < LAT_TOL_RAD,
                    "{near:?} {full:?}"
                );
                assert!(
                    (near.height_m - full.height_m).abs() < HEIGHT_TOL_M,
                    "{near:?} {full:?}"
                );
                assert_eq!(near.lon_rad, full.lon_rad);
            }
        }
    }

    #[test]
    fn enu_is_orthonormal_and_up_points_out() {
        let g = Geodetic {
            lat_rad: 0.6,
            lon_rad: 2.4,
            height_m: 0.0,
        };
        let r = enu_rotation(&g);
        assert!((r * r.transpose() - Matrix3::identity()).amax() < 1e-15);
        let v = [1.0, -2.0, 3.0];
        let back = unrotate(&r, rotate(&r, v));
        for k in 0..3 {
            assert!((back[k] - v[k]).abs() < 1e-15);
        }
        let p = geodetic_to_ecef(g);
        let up = rotate(&r, p);
        assert!(up[2] > 6.3e6 && up[0].abs() < 1e-6);
    }
}

#[cfg(test)]
#[path = "frames_cov_tests.rs"]
mod cov_tests;
