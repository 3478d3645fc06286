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
//!   These are [`Orbit::motion`]'s, computed with the position from one
//!   evaluation ([`Orbit::state_motion`], [`Orbit::transmit_state_motion`]);
//!   a stream epoch takes a satellite's motion, as its position, from its
//!   orbit arc (the cubic Hermite interpolant's derivative between exact
//!   nodes, within 6.2e-6 m/s of them: [`crate::arc`]).
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

use crate::ephemeris::{Kepler, Orbit, C_M_S, OMEGA_E_GPS_RAD_S};
use crate::geometry::rotate_earth;
use crate::glonass::pz90_to_wgs84;
use crate::m;

/// Unknowns of the velocity solution: three velocity components and the
/// receiver clock drift.
pub const UNKNOWNS: usize = 4;
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

/// A Keplerian satellite's velocity and clock drift at GPS time
/// `t_gps_s`: the time derivative of the same expressions as its position
/// ([`Orbit::motion`]; module doc). The receiver takes it with the
/// transmit state, from the same evaluation
/// ([`Orbit::transmit_state_motion`]).
pub fn kepler_motion(k: &Kepler, t_gps_s: f64) -> SatMotion {
    Orbit::new(k).motion(t_gps_s)
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
