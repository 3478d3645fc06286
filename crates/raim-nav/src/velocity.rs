//! The receiver's velocity from Doppler: each satellite's broadcast
//! velocity and clock drift, the range-rate model, and a weighted
//! least-squares solution for the receiver's velocity and clock drift;
//! speed and course over ground from its local-level (ENU) components.
//! No heap, fixed size: four unknowns.
//!
//! **Satellite motion.**
//! - Keplerian orbits (GPS, Galileo, BeiDou, QZSS): the time derivative of
//!   IS-GPS-200 Table 20-IV's position (the eccentric anomaly's rate
//!   n / (1 - e cos E), the true anomaly's, the harmonic corrections' and
//!   the node's, Omega_dot - omega_e), the same equations in the Galileo
//!   OS SIS ICD §5.1.1 and the BeiDou ICD §5.2.4.12 (whose GEO satellites'
//!   extra rotations are differentiated too: Rz(omega_e t_k) turns at
//!   omega_e); the clock drift af1 + 2 af2 (t - toc) plus the relativistic
//!   term's rate F e sqrt(A) cos(E) dE/dt (IS-GPS-200 20.3.3.3.3.1).
//! - GLONASS: the velocity of the ICD's integrated state (ICD 5.1
//!   A.3.1.2, the rotating PZ-90.11 frame, i.e. Earth-fixed), through the
//!   rotation and scale of [`crate::glonass::pz90_to_wgs84`] (not its
//!   translation); the clock drift gamma_n.
//!
//! **The model** (in the Earth-fixed frame of the reception instant, as
//! the epoch's satellite positions, [`crate::ranging::correct_at`]): the
//! satellite's velocity at its transmit time is turned by the Earth's
//! rotation over the transit, as its position is
//! ([`crate::geometry::rotate_earth`]). Differentiating the inertial range
//! |S(t - tau) - X(t)| with u the unit vector from the receiver to the
//! satellite's turned position r_sat, the terms omega_e x r of both ends
//! cancel along u (their difference omega_e x (r_sat - r_rx) is normal to
//! u: the Sagnac term of the rate), and the light time's own rate
//! d tau / dt = rate / c scales the satellite's inertial velocity
//! w_sat = v_sat + omega_e x r_sat:
//!
//! rate = (u . v_sat - u . v_rx) / (1 + u . w_sat / c)
//!        + c (drift_rx - drift_sat).
//!
//! The factor is 1 - 3e-6 at most (2 mm/s on an 800 m/s rate). Left out:
//! the same factor on the satellite's clock drift (below 1e-8 m/s), the
//! receiver clock's rate on its own time scale (below 1e-4 m/s at a 30
//! m/s drift), and the ionosphere's and troposphere's rates (a few mm/s).
//!
//! **The solution.** x = [v_rx (ECEF, m/s), c drift_rx (m/s)] by
//! weighted least squares, rows [-u_i / k_i, 1] with k_i = 1 + u_i .
//! w_sat_i / c, measurements rate_i - u_i . v_sat_i / k_i + c
//! drift_sat_i, weights 1 / sigma_i^2 with sigma_i the
//! satellite's range sigma (its elevation dependence: a Doppler's noise
//! grows at low elevation as the range's does; the scale does not change
//! the estimate). One clock drift for every constellation: the
//! inter-system biases are constant over an epoch. The velocity carries
//! no integrity bound: it is written to NMEA only for an epoch whose
//! position is (decision `Ok` or `Excluded`), from the satellites that
//! position used.

use nalgebra::{Matrix4, Vector4};
use raim_core::frames::{ecef_to_geodetic, enu_rotation, rotate};
use raim_core::System;

use crate::ephemeris::{
    Kepler, C_M_S, MU_GAL_BDS_M3_S2, MU_GPS_M3_S2, OMEGA_E_BDS_RAD_S, OMEGA_E_GPS_RAD_S,
};
use crate::geometry::rotate_earth;
use crate::glonass::pz90_to_wgs84;
use crate::m;

/// Unknowns of the velocity solution: three velocity components and the
/// receiver clock drift.
pub const UNKNOWNS: usize = 4;
/// Kepler's equation for the velocity: a Newton step below this is the
/// last, rad (the velocity is a function of E through terms of order
/// n a ~ 4 km/s per radian: 1e-12 rad is 4e-9 m/s).
const KEPLER_LAST_STEP_RAD: f64 = 1e-12;
/// Kepler's equation: iteration cap (Newton's method from E = M converges
/// in under 6 steps for e < 0.3).
const KEPLER_MAX_ITERATIONS: usize = 30;

/// A satellite's velocity and clock drift at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SatMotion {
    /// Earth-fixed velocity (WGS-84, the frame of the same instant), m/s.
    pub velocity_m_s: [f64; 3],
    /// Clock drift, s/s.
    pub clock_drift_s_s: f64,
}

/// One satellite's Doppler measurement and motion, as the epoch's forming
/// keeps it for the velocity solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeRate {
    /// The measured phase-range rate, m/s (positive receding): the MSM's
    /// DF399 + DF404 of the signal the satellite is ranged with.
    pub rate_m_s: f64,
    /// The satellite's velocity at its transmit time, turned into the
    /// Earth-fixed frame of the reception instant (as its position), m/s.
    pub sat_velocity_m_s: [f64; 3],
    /// The satellite's clock drift, s/s.
    pub sat_clock_drift_s_s: f64,
}

/// One satellite of the velocity solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RateObservation {
    /// The satellite's position, Earth-fixed frame of the reception
    /// instant (the epoch's `RangeObservation::position_m`), m.
    pub sat_position_m: [f64; 3],
    pub rate: RangeRate,
    /// The satellite's range sigma (its weight is 1 / sigma^2), m.
    pub sigma_m: f64,
}

/// The receiver's velocity and clock drift.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReceiverVelocity {
    /// Earth-fixed velocity, m/s.
    pub ecef_m_s: [f64; 3],
    /// East, north, up velocity at the solution's position, m/s.
    pub enu_m_s: [f64; 3],
    /// c times the receiver clock drift, m/s.
    pub clock_drift_m_s: f64,
    /// Satellites in the solution.
    pub satellites: u32,
}

impl ReceiverVelocity {
    /// Speed over ground: the horizontal speed, m/s.
    pub fn speed_over_ground_m_s(&self) -> f64 {
        let [e, n, _] = self.enu_m_s;
        m::sqrt(e * e + n * n)
    }

    /// Course over ground: the direction of the horizontal velocity,
    /// clockwise from true north, in [0, 2 pi), rad (at a speed within the
    /// velocity's noise, the direction of the noise).
    pub fn course_over_ground_rad(&self) -> f64 {
        let [e, n, _] = self.enu_m_s;
        m::rem_euclid(m::atan2(e, n), 2.0 * core::f64::consts::PI)
    }
}

/// Why no velocity was solved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum VelocityError {
    /// Fewer satellites with a range rate than the unknowns.
    TooFewRates { have: u32, need: u32 },
    /// The geometry's normal matrix is not positive definite.
    Singular,
    /// A non-finite input or result (`field` names it).
    NotFinite { field: &'static str },
}

impl core::fmt::Display for VelocityError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            VelocityError::TooFewRates { have, need } => {
                write!(f, "{have} range rates, {need} needed for a velocity")
            }
            VelocityError::Singular => write!(f, "velocity geometry singular"),
            VelocityError::NotFinite { field } => write!(f, "velocity: {field} not finite"),
        }
    }
}

/// The gravitational constant and Earth rotation rate of a Keplerian
/// set's system (as [`Kepler::state`] takes them).
fn mu_omega(system: System) -> (f64, f64) {
    match system {
        System::Gps | System::Qzss | System::Glonass => (MU_GPS_M3_S2, OMEGA_E_GPS_RAD_S),
        System::Galileo => (MU_GAL_BDS_M3_S2, OMEGA_E_GPS_RAD_S),
        System::Beidou => (MU_GAL_BDS_M3_S2, OMEGA_E_BDS_RAD_S),
    }
}

/// Below this |d|, [`sin_cos_short`] takes its Taylor series; above, the
/// library's sine and cosine, rad (|E - M| <= e: GPS, BeiDou and most
/// Galileo orbits have e < 0.03).
const SHORT_ANGLE_RAD: f64 = 0.05;

/// sin d and cos d: their Taylor series to d^9 and d^8 for |d| <=
/// [`SHORT_ANGLE_RAD`] (the first term left out below 0.05^10 / 10! =
/// 2.7e-20 of the result), else the library's.
fn sin_cos_short(d: f64) -> (f64, f64) {
    if d.is_nan() || d.abs() > SHORT_ANGLE_RAD {
        return m::sin_cos(d);
    }
    let z = d * d;
    let s = d
        * (1.0
            - z * (1.0 / 6.0)
                * (1.0 - z * (1.0 / 20.0) * (1.0 - z * (1.0 / 42.0) * (1.0 - z * (1.0 / 72.0)))));
    let c = 1.0
        - z * (1.0 / 2.0)
            * (1.0 - z * (1.0 / 12.0) * (1.0 - z * (1.0 / 30.0) * (1.0 - z * (1.0 / 56.0))));
    (s, c)
}

/// The sine and cosine of the eccentric anomaly of mean anomaly `mk`,
/// eccentricity `e` (Kepler's equation M = E - e sin E): Newton's method
/// on d = E - M from d = e sin M, with sin(M + d) and cos(M + d) from M's
/// sine and cosine (one library call) and d's ([`sin_cos_short`]).
fn eccentric_anomaly_sin_cos(mk: f64, e: f64) -> (f64, f64) {
    let (sin_m, cos_m) = m::sin_cos(mk);
    let at = |d: f64| {
        let (sd, cd) = sin_cos_short(d);
        (sin_m * cd + cos_m * sd, cos_m * cd - sin_m * sd)
    };
    let mut d = e * sin_m;
    let (mut sin_e, mut cos_e) = at(d);
    for _ in 0..KEPLER_MAX_ITERATIONS {
        let step = (d - e * sin_e) / (1.0 - e * cos_e);
        d -= step;
        (sin_e, cos_e) = at(d);
        if step.is_nan() || step.abs() < KEPLER_LAST_STEP_RAD {
            break;
        }
    }
    (sin_e, cos_e)
}

/// A Keplerian satellite's velocity and clock drift at GPS time
/// `t_gps_s` (module doc: the time derivative of IS-GPS-200 Table 20-IV,
/// BeiDou GEO satellites through their extra rotations). The true
/// anomaly's and the argument of latitude's sines and cosines come from
/// E's and omega's by the angle-sum identities (no arctangent; the
/// harmonic correction of u, below 1e-4 rad, by its Taylor series), so
/// that a satellite takes four library sines and cosines.
pub fn kepler_motion(k: &Kepler, t_gps_s: f64) -> SatMotion {
    let (mu, omega_e) = mu_omega(k.system);
    let tk = k.tk_s(t_gps_s);
    let a = k.sqrt_a_m05 * k.sqrt_a_m05;
    let n = m::sqrt(mu / (a * a * a)) + k.delta_n_rad_s;
    let e = k.e;
    let (sin_e, cos_e) = eccentric_anomaly_sin_cos(k.m0_rad + n * tk, e);
    let one_m_ecos = 1.0 - e * cos_e;
    let e_dot = n / one_m_ecos;
    let root = m::sqrt(1.0 - e * e);
    // The true anomaly nu: sin and cos (IS-GPS-200 Table 20-IV).
    let (sin_nu, cos_nu) = (root * sin_e / one_m_ecos, (cos_e - e) / one_m_ecos);
    let nu_dot = e_dot * root / one_m_ecos;
    // phi = nu + omega.
    let (sin_w, cos_w) = m::sin_cos(k.omega_rad);
    let (sin_phi, cos_phi) = (
        sin_nu * cos_w + cos_nu * sin_w,
        cos_nu * cos_w - sin_nu * sin_w,
    );
    let (s2, c2) = (
        2.0 * sin_phi * cos_phi,
        cos_phi * cos_phi - sin_phi * sin_phi,
    );
    let du = k.cus_rad * s2 + k.cuc_rad * c2;
    let (sin_du, cos_du) = sin_cos_short(du);
    let (sin_u, cos_u) = (
        sin_phi * cos_du + cos_phi * sin_du,
        cos_phi * cos_du - sin_phi * sin_du,
    );
    let u_dot = nu_dot * (1.0 + 2.0 * (k.cus_rad * c2 - k.cuc_rad * s2));
    let r = a * one_m_ecos + k.crs_m * s2 + k.crc_m * c2;
    let r_dot = a * e * sin_e * e_dot + 2.0 * nu_dot * (k.crs_m * c2 - k.crc_m * s2);
    let i = k.i0_rad + k.idot_rad_s * tk + k.cis_rad * s2 + k.cic_rad * c2;
    let i_dot = k.idot_rad_s + 2.0 * nu_dot * (k.cis_rad * c2 - k.cic_rad * s2);
    let (xo, yo) = (r * cos_u, r * sin_u);
    let (xo_dot, yo_dot) = (
        r_dot * cos_u - r * u_dot * sin_u,
        r_dot * sin_u + r * u_dot * cos_u,
    );
    let (sin_i, cos_i) = m::sin_cos(i);
    // The orbital plane turned by the node Omega (rate omega_rate) and
    // the inclination i: position and velocity.
    let plane = |omega: f64, omega_rate: f64| {
        let (so, co) = m::sin_cos(omega);
        let p = [
            xo * co - yo * cos_i * so,
            xo * so + yo * cos_i * co,
            yo * sin_i,
        ];
        let v = [
            xo_dot * co - yo_dot * cos_i * so + yo * sin_i * i_dot * so - omega_rate * p[1],
            xo_dot * so + yo_dot * cos_i * co - yo * sin_i * i_dot * co + omega_rate * p[0],
            yo_dot * sin_i + yo * cos_i * i_dot,
        ];
        (p, v)
    };
    let toe = k.toe_sow_s;
    let velocity_m_s = if k.is_beidou_geo() {
        let (g, gv) = plane(
            k.omega0_rad + k.omega_dot_rad_s * tk - omega_e * toe,
            k.omega_dot_rad_s,
        );
        let (sf, cf) = m::sin_cos(-5.0f64.to_radians());
        let rx = |v: [f64; 3]| [v[0], cf * v[1] + sf * v[2], -sf * v[1] + cf * v[2]];
        let (q, qv) = (rx(g), rx(gv));
        let (sz, cz) = m::sin_cos(omega_e * tk);
        [
            cz * qv[0] + sz * qv[1] + omega_e * (-sz * q[0] + cz * q[1]),
            -sz * qv[0] + cz * qv[1] + omega_e * (-cz * q[0] - sz * q[1]),
            qv[2],
        ]
    } else {
        let rate = k.omega_dot_rad_s - omega_e;
        plane(k.omega0_rad + rate * tk - omega_e * toe, rate).1
    };
    let f = -2.0 * m::sqrt(mu) / (C_M_S * C_M_S);
    let dt = t_gps_s - k.toc_gps_s;
    let clock_drift_s_s = k.af1_s_s + 2.0 * k.af2_s_s2 * dt + f * e * k.sqrt_a_m05 * cos_e * e_dot;
    SatMotion {
        velocity_m_s,
        clock_drift_s_s,
    }
}

/// A GLONASS satellite's motion from its integrated PZ-90.11 velocity
/// `velocity_pz90_m_s` (`GlonassArc::propagate_pz90`'s) and its clock
/// drift gamma_n: the velocity through the rotation and scale of the
/// PZ-90.11 to WGS-84 transformation (its translation moves positions
/// only).
pub fn glonass_motion(velocity_pz90_m_s: [f64; 3], gamma_n: f64) -> SatMotion {
    let moved = pz90_to_wgs84(velocity_pz90_m_s);
    let origin = pz90_to_wgs84([0.0; 3]);
    SatMotion {
        velocity_m_s: [
            moved[0] - origin[0],
            moved[1] - origin[1],
            moved[2] - origin[2],
        ],
        clock_drift_s_s: gamma_n,
    }
}

/// The transmit time of a Keplerian satellite's signal from the time
/// `t_sv_gps_s` its clock sent it at, for the velocity: t_sv less the
/// clock polynomial (the relativistic term, below 1e-7 s, moves the
/// velocity by below 1e-6 m/s).
pub fn kepler_transmit_time_s(k: &Kepler, t_sv_gps_s: f64) -> f64 {
    t_sv_gps_s - k.clock_polynomial_s(t_sv_gps_s)
}

/// A satellite's [`RangeRate`] for the velocity solution: its measured
/// rate and its motion at the transmit time, the velocity turned into the
/// frame of the reception instant over the transit from its position
/// there (`sat_position_m`, already turned) to the receiver at `rx_m`.
pub fn range_rate(
    rate_m_s: f64,
    motion: &SatMotion,
    sat_position_m: [f64; 3],
    rx_m: [f64; 3],
) -> RangeRate {
    let transit_s = crate::geometry::distance_m(sat_position_m, rx_m) / C_M_S;
    RangeRate {
        rate_m_s,
        sat_velocity_m_s: rotate_earth(motion.velocity_m_s, transit_s),
        sat_clock_drift_s_s: motion.clock_drift_s_s,
    }
}

/// The receiver's velocity and clock drift at `rx_m` (the solved
/// position) from `sats` (module doc: the model and the weights).
pub fn solve(
    rx_m: [f64; 3],
    sats: &mut dyn Iterator<Item = RateObservation>,
) -> Result<ReceiverVelocity, VelocityError> {
    if !rx_m.iter().all(|v| v.is_finite()) {
        return Err(VelocityError::NotFinite { field: "position" });
    }
    let mut ata = Matrix4::<f64>::zeros();
    let mut aty = Vector4::<f64>::zeros();
    let mut n = 0u32;
    for s in sats {
        let p = s.sat_position_m;
        let d = [p[0] - rx_m[0], p[1] - rx_m[1], p[2] - rx_m[2]];
        let range = m::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        let u = [d[0] / range, d[1] / range, d[2] / range];
        let v = s.rate.sat_velocity_m_s;
        let u_v = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
        // u . (omega_e x r_sat), omega_e along Z.
        let u_spin = OMEGA_E_GPS_RAD_S * (u[1] * p[0] - u[0] * p[1]);
        let k = 1.0 + (u_v + u_spin) / C_M_S;
        let y = s.rate.rate_m_s - u_v / k + C_M_S * s.rate.sat_clock_drift_s_s;
        let w = 1.0 / (s.sigma_m * s.sigma_m);
        let h = Vector4::new(-u[0] / k, -u[1] / k, -u[2] / k, 1.0);
        if !(y.is_finite() && w.is_finite() && w > 0.0 && h.iter().all(|x| x.is_finite())) {
            return Err(VelocityError::NotFinite {
                field: "range rate",
            });
        }
        ata += h * h.transpose() * w;
        aty += h * (w * y);
        n += 1;
    }
    if n < UNKNOWNS as u32 {
        return Err(VelocityError::TooFewRates {
            have: n,
            need: UNKNOWNS as u32,
        });
    }
    let x = ata.cholesky().ok_or(VelocityError::Singular)?.solve(&aty);
    if !x.iter().all(|v| v.is_finite()) {
        return Err(VelocityError::NotFinite { field: "velocity" });
    }
    let ecef_m_s = [x.x, x.y, x.z];
    let enu_m_s = rotate(&enu_rotation(&ecef_to_geodetic(rx_m)), ecef_m_s);
    Ok(ReceiverVelocity {
        ecef_m_s,
        enu_m_s,
        clock_drift_m_s: x.w,
        satellites: n,
    })
}

#[cfg(test)]
#[path = "velocity_tests.rs"]
mod tests;
