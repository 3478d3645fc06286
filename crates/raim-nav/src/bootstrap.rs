//! The bootstrap position of an epoch: the receiver position at which the
//! corrections (Earth rotation, elevation, troposphere, mask) are
//! computed, solved from the clock- and rotation-corrected ranges of the
//! bootstrap pass ([`crate::ranging::correct`] with `full` false).
//!
//! It is the weighted least-squares position of raim-core's Gauss-Newton
//! solution (`raim_core::solve`, SPEC §1: unit weights near the Earth's
//! centre, then the default sigma model at each satellite's elevation,
//! re-evaluated when the position moves more than
//! `raim_core::solve::RELINEARISE_M`; one clock per system; stop when the
//! step is below the default configuration's `convergence_m`), computed
//! with raim-core's precision policy for the device (docs/CORE.md
//! "Precision"): the range and the residual in f64, the lines of sight,
//! weights and normal equations in f32, the M4F's hardware precision. The
//! position is only a linearisation point, and its fixed point is that of
//! the f64 solution to well under a millimetre (the f32 model's relative
//! error, 1e-7, times residuals of metres): the test
//! `stream_forming::the_lean_bootstrap_is_the_core_solution` holds it
//! within 1 mm on real epochs and the corrected ranges at it within
//! 1e-4 m. It costs a tenth of the core's solution, which forms the parity
//! space and the sigma model in f64 (soft-float on the M4; BENCHMARKS.md
//! "Firmware: receiver stream"), and it needs no storage of the epoch's
//! size.
//!
//! The host's readers and the device's receiver call this one function,
//! so they form the same bits.

use raim_core::frames::{elevation, WGS84_A_M, WGS84_F};
use raim_core::solve::RELINEARISE_M;
use raim_core::{Config, RangeObservation, System};

use crate::geometry::distance_m;

/// A solved position is trusted as the linearisation point for the
/// corrections only if it is within this of the Earth's surface, m.
pub const SURFACE_BAND_M: f64 = 100_000.0;

/// Below this radius the position is near the Earth's centre, where there
/// is no local level and the weights are unit (raim-core's rule), m.
const SURFACE_RADIUS_MIN_M: f64 = 5.0e6;

/// The weights are computed once a step is below this, m (unit weights
/// before, as raim-core's near the Earth's centre).
const WEIGHTS_AFTER_STEP_M: f64 = 1000.0;

/// Gauss-Newton iterations before giving up (raim-core's default).
const MAX_ITERATIONS: usize = 20;

/// Unknowns: three position coordinates and one clock per system.
const STATES: usize = 3 + System::ALL.len();

/// A range from its square, to 1e-14 relative: the hardware f32 square
/// root and one Newton step in f64 (`raim_core::real`'s `range_sqrt` for
/// f32; a soft-float f64 square root costs ten times more on the M4F).
fn range_m(r2: f64) -> f64 {
    let r0 = f64::from(libm::sqrtf(r2 as f32));
    if r0.is_finite() && r0 > 0.0 {
        0.5 * (r0 + r2 / r0)
    } else {
        libm::sqrt(r2)
    }
}

/// The rows of the ECEF-to-ENU rotation at `x_m` (`raim_core::frames::
/// enu_rotation`) in f32, the precision of the weights' lines of sight:
/// the longitude, and Bowring's closed-form geodetic latitude (within
/// 1e-9 rad at the surface, `raim_core::frames::bowring_latitude_rad`),
/// in f32 (1e-7 rad) instead of ten f64 latitude iterations.
fn enu_rows(x_m: [f64; 3]) -> [[f32; 3]; 3] {
    let [x, y, z] = x_m.map(|v| v as f32);
    let a = WGS84_A_M as f32;
    let f = WGS84_F as f32;
    let b = a * (1.0 - f);
    let e2 = f * (2.0 - f);
    let ep2 = e2 / (1.0 - e2);
    let p = libm::sqrtf(x * x + y * y);
    let theta = libm::atan2f(z * a, p * b);
    let (st, ct) = (libm::sinf(theta), libm::cosf(theta));
    let lat = libm::atan2f(z + ep2 * b * st * st * st, p - e2 * a * ct * ct * ct);
    let lon = libm::atan2f(y, x);
    let (sl, cl) = (libm::sinf(lat), libm::cosf(lat));
    let (so, co) = (libm::sinf(lon), libm::cosf(lon));
    [
        [-so, co, 0.0],
        [-sl * co, -sl * so, cl],
        [cl * co, cl * so, sl],
    ]
}

/// The least-squares position of `sats` (more than the unknowns: three
/// coordinates and a clock per system; at most `N`), starting at
/// `apriori` (else the Earth's centre); None if it does not converge, a satellite is within 1 m of the position, the normal
/// equations are singular, or the position is farther than
/// [`SURFACE_BAND_M`] from the surface.
pub fn bootstrap_position<const N: usize>(
    sats: &[RangeObservation],
    apriori: Option<[f64; 3]>,
) -> Option<[f64; 3]> {
    if sats.len() > N || sats.len() < 4 {
        return None;
    }
    let model = Config::default();
    // The clock column of each system present, in `System::ALL` order.
    let mut column = [None; System::ALL.len()];
    let mut clocks = 0;
    for (sys, col) in System::ALL.iter().zip(column.iter_mut()) {
        if sats.iter().any(|s| s.id.system == *sys) {
            *col = Some(3 + clocks);
            clocks += 1;
        }
    }
    let m = 3 + clocks;
    // One range more than the unknowns, as raim-core's solution requires
    // (a fit with no redundancy is refused there).
    if sats.len() <= m {
        return None;
    }
    let mut x = apriori.unwrap_or([0.0; 3]);
    let mut clock_m = [0.0f64; STATES];
    // The weights' linearisation point and rotation, once on the surface.
    let mut lin: Option<([f64; 3], [[f32; 3]; 3])> = None;
    // The model's sigma of each satellite at the linearisation point `lin`
    // (the weights of the satellites without a sigma of their own):
    // computed when `lin` is set, then kept while it holds.
    let mut model_sigma_m = [0.0f32; N];
    let mut last_step_m = f64::INFINITY;
    for _ in 0..MAX_ITERATIONS {
        let mut relinearised = false;
        // The weights wait for the position to settle (a step below
        // WEIGHTS_AFTER_STEP_M: Gauss-Newton's next error is then below a
        // few cm), so that they are computed once, at the point raim-core's
        // last linearisation is within RELINEARISE_M of.
        let on_surface = distance_m(x, [0.0; 3]) > SURFACE_RADIUS_MIN_M
            && (lin.is_some() || last_step_m < WEIGHTS_AFTER_STEP_M);
        if on_surface
            && lin.is_none_or(|(p, _)| {
                let moved_m = distance_m(p, x);
                moved_m.is_nan() || moved_m > RELINEARISE_M
            })
        {
            lin = Some((x, enu_rows(x)));
            relinearised = true;
        }
        let rot = if on_surface {
            lin.map(|(_, r)| r)
        } else {
            None
        };
        let mut a = [[0.0f32; STATES]; STATES];
        let mut b = [0.0f32; STATES];
        for (s, kept_sigma_m) in sats.iter().zip(model_sigma_m.iter_mut()) {
            let d = [
                s.position_m[0] - x[0],
                s.position_m[1] - x[1],
                s.position_m[2] - x[2],
            ];
            let range = range_m(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if range.is_nan() || range <= 1.0 {
                return None;
            }
            let col = column.get(s.id.system.index()).copied().flatten()?;
            let z = s.pseudorange_m - range - clock_m.get(col).copied().unwrap_or(0.0);
            let r32 = range as f32;
            let u = [d[0] as f32 / r32, d[1] as f32 / r32, d[2] as f32 / r32];
            let sigma_m = match (rot, s.sigma_m) {
                (None, v) => v.map_or(1.0, |v| v as f32),
                (Some(_), Some(v)) => v as f32,
                (Some(r), None) => {
                    if relinearised {
                        let enu = r.map(|row| row[0] * u[0] + row[1] * u[1] + row[2] * u[2]);
                        *kept_sigma_m = model.sigma_model.sigma(elevation(enu));
                    }
                    *kept_sigma_m
                }
            };
            if !(sigma_m > 0.0 && sigma_m < f32::INFINITY) {
                return None;
            }
            let w2 = 1.0 / (sigma_m * sigma_m);
            let mut h = [0.0f32; STATES];
            h[0] = -u[0];
            h[1] = -u[1];
            h[2] = -u[2];
            if let Some(c) = h.get_mut(col) {
                *c = 1.0;
            }
            let z = z as f32;
            for (i, (bi, row)) in b.iter_mut().zip(a.iter_mut()).enumerate() {
                let wh = w2 * h.get(i).copied().unwrap_or(0.0);
                *bi += wh * z;
                for (aij, hj) in row.iter_mut().zip(h.iter()).skip(i) {
                    *aij += wh * hj;
                }
            }
        }
        // An absent system's clock: dx = 0 for its column.
        for (i, row) in a.iter_mut().enumerate().skip(m) {
            if let Some(v) = row.get_mut(i) {
                *v = 1.0;
            }
        }
        let dx = solve_spd(&mut a, &b)?;
        let step = [f64::from(dx[0]), f64::from(dx[1]), f64::from(dx[2])];
        let step_m = distance_m(step, [0.0; 3]);
        if !step_m.is_finite() {
            return None;
        }
        x = [x[0] + step[0], x[1] + step[1], x[2] + step[2]];
        for (c, d) in clock_m.iter_mut().zip(dx.iter()).skip(3).take(clocks) {
            *c += f64::from(*d);
        }
        last_step_m = step_m;
        // Converged only with the weights in force.
        if step_m < model.convergence_m && rot.is_some() {
            let r = distance_m(x, [0.0; 3]);
            return ((r - WGS84_A_M).abs() < SURFACE_BAND_M).then_some(x);
        }
    }
    None
}

/// The entry (i, j) of `a` (0 outside it).
fn at(a: &[[f32; STATES]; STATES], i: usize, j: usize) -> f32 {
    a.get(i).and_then(|r| r.get(j)).copied().unwrap_or(0.0)
}

/// Solves `a x = b` for the symmetric positive definite matrix whose
/// upper triangle `a` holds (Cholesky, in place: a = r^T r with r upper
/// triangular); None if it is not positive definite.
fn solve_spd(a: &mut [[f32; STATES]; STATES], b: &[f32; STATES]) -> Option<[f32; STATES]> {
    for i in 0..STATES {
        let d = (0..i).fold(at(a, i, i), |d, k| d - at(a, k, i) * at(a, k, i));
        if d.is_nan() || d <= 0.0 {
            return None;
        }
        let rii = libm::sqrtf(d);
        for j in i..STATES {
            let v = if j == i {
                rii
            } else {
                (0..i).fold(at(a, i, j), |v, k| v - at(a, k, i) * at(a, k, j)) / rii
            };
            if let Some(c) = a.get_mut(i).and_then(|r| r.get_mut(j)) {
                *c = v;
            }
        }
    }
    // r^T y = b, then r x = y.
    let mut y = [0.0f32; STATES];
    for i in 0..STATES {
        let v = (0..i).fold(b.get(i).copied().unwrap_or(0.0), |v, k| {
            v - at(a, k, i) * y.get(k).copied().unwrap_or(0.0)
        });
        if let Some(c) = y.get_mut(i) {
            *c = v / at(a, i, i);
        }
    }
    let mut x = [0.0f32; STATES];
    for i in (0..STATES).rev() {
        let v = (i + 1..STATES).fold(y.get(i).copied().unwrap_or(0.0), |v, k| {
            v - at(a, i, k) * x.get(k).copied().unwrap_or(0.0)
        });
        if let Some(c) = x.get_mut(i) {
            *c = v / at(a, i, i);
        }
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use raim_core::SatId;

    /// The f32 rotation against raim-core's f64 one (its rows), at points
    /// on and above the surface over latitudes and longitudes: within
    /// 1e-6 per entry.
    #[test]
    fn f32_rotation_is_the_cores() {
        use raim_core::frames::{enu_rotation, geodetic_to_ecef, Geodetic};
        for lat_deg in [-89.0f64, -60.0, -12.0, 0.0, 33.0, 55.5, 89.0] {
            for lon_deg in [-179.0f64, -90.0, 0.0, 12.0, 100.0, 179.5] {
                for height_m in [0.0, 3000.0, 500_000.0] {
                    let g = Geodetic {
                        lat_rad: lat_deg.to_radians(),
                        lon_rad: lon_deg.to_radians(),
                        height_m,
                    };
                    let want = enu_rotation(&g);
                    let got = enu_rows(geodetic_to_ecef(g));
                    for i in 0..3 {
                        for j in 0..3 {
                            let d = (f64::from(got[i][j]) - want[(i, j)]).abs();
                            assert!(d < 1e-6, "{lat_deg} {lon_deg} {height_m}: {d}");
                        }
                    }
                }
            }
        }
    }

    /// The Cholesky solve against a system with a known solution.
    #[test]
    fn cholesky_solves_a_known_system() {
        // a = l l^T with l lower [[2,0,0],[1,3,0],[0.5,-1,1.5]].
        let full = [[4.0f32, 2.0, 1.0], [2.0, 10.0, -2.5], [1.0, -2.5, 3.5]];
        let want = [1.0f32, -2.0, 0.5];
        let mut a = [[0.0f32; STATES]; STATES];
        let mut b = [0.0f32; STATES];
        for i in 0..3 {
            for j in i..3 {
                a[i][j] = full[i][j];
            }
            b[i] = (0..3).map(|j| full[i][j] * want[j]).sum();
        }
        for (i, row) in a.iter_mut().enumerate().skip(3) {
            row[i] = 1.0;
        }
        let x = solve_spd(&mut a, &b).unwrap();
        for i in 0..3 {
            assert!((x[i] - want[i]).abs() < 1e-5, "{x:?}");
        }
        let mut singular = [[0.0f32; STATES]; STATES];
        singular[0][0] = 1.0;
        assert!(solve_spd(&mut singular, &[1.0; STATES]).is_none());
    }

    /// Exact ranges from a point on the surface with a clock of 30 km
    /// per system (GPS and GLONASS) are solved back to the point from the
    /// Earth's centre, to the convergence tolerance; fewer than four
    /// satellites, none.
    #[test]
    fn exact_ranges_give_the_point_back() {
        let rx = raim_core::frames::geodetic_to_ecef(raim_core::frames::Geodetic {
            lat_rad: 0.62,
            lon_rad: 2.4,
            height_m: 35.0,
        });
        let up = {
            let r = distance_m(rx, [0.0; 3]);
            [rx[0] / r, rx[1] / r, rx[2] / r]
        };
        let mut sats = std::vec::Vec::new();
        for (k, (e, n, sys)) in [
            (0.0, 0.0, System::Gps),
            (1.2e7, 0.3e7, System::Gps),
            (-1.0e7, 0.8e7, System::Gps),
            (0.2e7, -1.1e7, System::Gps),
            (0.9e7, 0.9e7, System::Glonass),
            (-0.7e7, -0.6e7, System::Glonass),
        ]
        .into_iter()
        .enumerate()
        {
            // A point 2e7 m above the receiver, pushed sideways.
            let east = [-up[1], up[0], 0.0];
            let r = distance_m(east, [0.0; 3]);
            let east = [east[0] / r, east[1] / r, 0.0];
            let north = [
                up[1] * east[2] - up[2] * east[1],
                up[2] * east[0] - up[0] * east[2],
                up[0] * east[1] - up[1] * east[0],
            ];
            let p = [0, 1, 2].map(|i| rx[i] + 2.0e7 * up[i] + e * east[i] + n * north[i]);
            let clock_m = if sys == System::Gps { 3.0e4 } else { -1.2e4 };
            sats.push(RangeObservation {
                id: SatId::new(sys, k as u8 + 1),
                pseudorange_m: distance_m(p, rx) + clock_m,
                position_m: p,
                sigma_m: None,
            });
        }
        let got = bootstrap_position::<32>(&sats, None).unwrap();
        assert!(distance_m(got, rx) < 1e-3, "{}", distance_m(got, rx));
        assert!(bootstrap_position::<32>(&sats[..3], None).is_none());
        assert!(bootstrap_position::<4>(&sats, None).is_none());
    }
}
