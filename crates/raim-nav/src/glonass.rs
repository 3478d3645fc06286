//! GLONASS FDMA broadcast ephemerides: state vectors integrated by
//! 4th-order Runge-Kutta, the satellite clock, GLONASS time and the
//! PZ-90.11 to WGS-84 transformation (GLONASS ICD edition 5.1, 2008:
//! §3.3.1.2 time, §4.4 ephemeris and clock words, Appendix A.3.1.2 the
//! orbit re-calculation; the frame transformation of EPSG:7960).
//!
//! - **Orbit.** The broadcast state (position, velocity, luni-solar
//!   acceleration) at t_b is in the Earth-fixed PZ-90.11 frame. The ICD's
//!   equations of motion in that rotating frame (central body, J2, the
//!   centrifugal and Coriolis terms, the broadcast luni-solar acceleration
//!   held constant) are integrated from t_b to t by RK4 with a fixed step
//!   ([`RK4_STEP_S`]), the last step shortened to land on t:
//!
//!   ```text
//!   dvx/dt = -mu x/r^3 - 3/2 J2 mu ae^2 x/r^5 (1 - 5 z^2/r^2) + w^2 x + 2 w vy + ax
//!   dvy/dt = -mu y/r^3 - 3/2 J2 mu ae^2 y/r^5 (1 - 5 z^2/r^2) + w^2 y - 2 w vx + ay
//!   dvz/dt = -mu z/r^3 - 3/2 J2 mu ae^2 z/r^5 (3 - 5 z^2/r^2) + az
//!   ```
//! - **Clock.** dt_sv(t) = -tau_n + gamma_n (t - t_b) (ICD §4.4; RINEX
//!   stores -tau_n as the clock bias and +gamma_n as the drift). tau_n
//!   already contains the relativistic effects, so no eccentricity term is
//!   added, and it refers to L1 (no group delay for single-frequency L1).
//! - **Time.** GLONASS time is UTC(SU) + 3 h and follows the leap seconds.
//!   Every time here is carried as continuous GPS seconds since
//!   1980-01-06; t_b (a time of the Moscow day) is placed on that scale with
//!   GPS - UTC from hifitime's leap-second table. The offset between
//!   GLONASS time and GPS time (tau_GPS, under a microsecond) is not
//!   applied: it is common to every GLONASS satellite, so the solution's
//!   GLONASS clock column absorbs it (SPEC §1, one clock per system).
//! - **Frame.** PZ-90.11 to ITRF2008 by the 7-parameter coordinate-frame
//!   rotation of EPSG:7960 (translations -3, -1, 0 mm; rotations 0.019,
//!   -0.042, 0.002 mas; no scale), then ITRF2008 = WGS-84 (G1762), which
//!   NGA aligned to ITRF2008 at the centimetre level. The whole
//!   transformation moves a GLONASS satellite by less than 1 cm.

use raim_core::System;

use crate::ephemeris::SatState;
use crate::error::NavError;
use crate::m;

/// PZ-90.11 gravitational constant, m^3/s^2 (ICD 5.1 Table 3.2).
pub const MU_PZ90_M3_S2: f64 = 3.986_004_418e14;
/// PZ-90 equatorial radius, m (ICD 5.1 Table 3.2).
pub const A_E_PZ90_M: f64 = 6_378_136.0;
/// Second zonal harmonic J2 of PZ-90 (ICD 5.1: J_0^2 = 1082625.75e-9).
pub const J2_PZ90: f64 = 1_082_625.75e-9;
/// Earth rotation rate of PZ-90, rad/s (ICD 5.1 Table 3.2).
pub const OMEGA_E_PZ90_RAD_S: f64 = 7.292_115e-5;
/// GLONASS time minus UTC(SU), s (ICD 5.1 §3.3.3: Moscow time, UTC + 3 h).
pub const GLONASS_MINUS_UTC_S: f64 = 10_800.0;
/// Seconds in a day.
const DAY_S: f64 = 86_400.0;
/// TAI - GPS time, s (constant since 1980-01-06).
/// Runge-Kutta step, s. The ICD's accuracy needs no less: halving it
/// moves a 15-minute propagation by under 1 mm (test
/// `rk4_step_is_converged`).
pub const RK4_STEP_S: f64 = 60.0;
/// Longest integration accepted, s: the ICD's 15-minute interval with
/// margin for a missing message (the loader's age limit is 30 min).
pub const MAX_PROPAGATION_S: f64 = 3_600.0;

/// Global average broadcast signal-in-space range error of GPS (LNAV), m
/// (Montenbruck, Steigenberger, Hauschild 2015, "Broadcast versus precise
/// ephemerides: a multi-GNSS perspective", GPS Solutions 19:321-333,
/// 12 months of 2013/2014).
pub const SISRE_GPS_M: f64 = 0.7;
/// The same study's GLONASS value, m.
pub const SISRE_GLONASS_M: f64 = 1.9;

/// A GLONASS URA from a GPS one, scaled by the published SISRE ratio
/// (1.9 m / 0.7 m): the GLONASS broadcast orbits and clocks are that much
/// less accurate, and a sigma model sized for GPS would under-weight the
/// residuals of GLONASS satellites (SPEC §3: sigma_URA per satellite).
pub fn glonass_ura_m(gps_ura_m: f64) -> f64 {
    gps_ura_m * SISRE_GLONASS_M / SISRE_GPS_M
}

/// L1 FDMA nominal carrier, Hz (ICD 5.1 §3.3.1.4).
pub const F_L1_BASE_HZ: f64 = 1_602.0e6;
/// L1 channel spacing, Hz.
pub const F_L1_STEP_HZ: f64 = 562.5e3;
/// L2 FDMA nominal carrier, Hz.
pub const F_L2_BASE_HZ: f64 = 1_246.0e6;
/// L2 channel spacing, Hz.
pub const F_L2_STEP_HZ: f64 = 437.5e3;

/// PZ-90.11 to ITRF2008, EPSG:7960 (coordinate-frame rotation): translations, m.
const PZ90_ITRF_T_M: [f64; 3] = [-0.003, -0.001, 0.0];
/// PZ-90.11 to ITRF2008, EPSG:7960: rotations, milliarcseconds.
const PZ90_ITRF_R_MAS: [f64; 3] = [0.019, -0.042, 0.002];
/// Milliarcseconds to radians.
const MAS_TO_RAD: f64 = core::f64::consts::PI / (180.0 * 3600.0 * 1000.0);

/// L1 carrier of frequency channel `k`, Hz: 1602 MHz + k x 562.5 kHz.
pub fn l1_hz(k: i8) -> f64 {
    F_L1_BASE_HZ + f64::from(k) * F_L1_STEP_HZ
}

/// L2 carrier of frequency channel `k`, Hz: 1246 MHz + k x 437.5 kHz.
pub fn l2_hz(k: i8) -> f64 {
    F_L2_BASE_HZ + f64::from(k) * F_L2_STEP_HZ
}

/// GPS time minus UTC at GPS time `t_gps_s`, s (the leap seconds since
/// 1980: TAI - UTC from hifitime's table, minus 19 s).
pub fn gps_minus_utc_s(t_gps_s: f64) -> f64 {
    crate::time::gps_minus_utc_s(t_gps_s)
}

/// GLONASS time (UTC(SU) + 3 h) as continuous seconds on the GPS origin:
/// t_gps - (GPS - UTC) + 3 h.
pub fn glonass_from_gps_s(t_gps_s: f64) -> f64 {
    glonass_from_gps_with_s(t_gps_s, gps_minus_utc_s(t_gps_s))
}

/// [`glonass_from_gps_s`] with GPS - UTC = `gps_minus_utc_s` (the count in
/// force: a stream's, or the table's before its expiry).
pub fn glonass_from_gps_with_s(t_gps_s: f64, gps_minus_utc_s: f64) -> f64 {
    t_gps_s - gps_minus_utc_s + GLONASS_MINUS_UTC_S
}

/// Seconds of the GLONASS (Moscow) day at GPS time `t_gps_s`.
pub fn glonass_time_of_day_s(t_gps_s: f64) -> f64 {
    glonass_time_of_day_with_s(t_gps_s, gps_minus_utc_s(t_gps_s))
}

/// [`glonass_time_of_day_s`] with GPS - UTC = `gps_minus_utc_s`.
pub fn glonass_time_of_day_with_s(t_gps_s: f64, gps_minus_utc_s: f64) -> f64 {
    m::rem_euclid(glonass_from_gps_with_s(t_gps_s, gps_minus_utc_s), DAY_S)
}

/// A time of the GLONASS day (t_b of an ephemeris, in [0, 86400) s) as
/// GPS seconds: the day is the one that puts it within 12 h of
/// `near_gps_s` (the receiver time of the message that carried it).
pub fn glonass_time_of_day_to_gps_s(tod_s: f64, near_gps_s: f64) -> f64 {
    glonass_time_of_day_to_gps_with_s(tod_s, near_gps_s, gps_minus_utc_s(near_gps_s))
}

/// [`glonass_time_of_day_to_gps_s`] with GPS - UTC = `gps_minus_utc_s` (the
/// count at `near_gps_s`).
pub fn glonass_time_of_day_to_gps_with_s(tod_s: f64, near_gps_s: f64, gps_minus_utc_s: f64) -> f64 {
    let near_glo = glonass_from_gps_with_s(near_gps_s, gps_minus_utc_s);
    let day_start = m::floor(near_glo / DAY_S) * DAY_S;
    let mut t_glo = day_start + tod_s;
    if t_glo - near_glo > DAY_S / 2.0 {
        t_glo -= DAY_S;
    } else if near_glo - t_glo > DAY_S / 2.0 {
        t_glo += DAY_S;
    }
    t_glo + gps_minus_utc_s - GLONASS_MINUS_UTC_S
}

/// PZ-90.11 to WGS-84 (G1762) through ITRF2008 (EPSG:7960 coordinate-frame
/// rotation; WGS-84 (G1762) = ITRF2008 at the centimetre level):
/// X' = T + R X with R = [[1, rz, -ry], [-rz, 1, rx], [ry, -rx, 1]].
pub fn pz90_to_wgs84(p_m: [f64; 3]) -> [f64; 3] {
    let [rx, ry, rz] = PZ90_ITRF_R_MAS.map(|v| v * MAS_TO_RAD);
    let [x, y, z] = p_m;
    [
        PZ90_ITRF_T_M[0] + x + rz * y - ry * z,
        PZ90_ITRF_T_M[1] - rz * x + y + rx * z,
        PZ90_ITRF_T_M[2] + ry * x - rx * y + z,
    ]
}

/// One GLONASS FDMA broadcast ephemeris (immediate data of strings 1-4),
/// SI units, PZ-90.11, times on the GPS scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlonassEphemeris {
    /// Orbital slot number n (1-24, the RINEX "PRN").
    pub slot: u8,
    /// FDMA frequency channel k (-7..=6).
    pub frequency_channel: i8,
    /// Reference time t_b, GPS seconds since 1980-01-06 (continuous).
    pub tb_gps_s: f64,
    /// Position at t_b, PZ-90.11, m.
    pub position_m: [f64; 3],
    /// Velocity at t_b, PZ-90.11 (Earth-fixed), m/s.
    pub velocity_m_s: [f64; 3],
    /// Luni-solar acceleration at t_b, PZ-90.11, m/s^2.
    pub lunisolar_m_s2: [f64; 3],
    /// tau_n: satellite time minus GLONASS time at t_b, s.
    pub tau_n_s: f64,
    /// gamma_n: relative carrier frequency deviation (s/s).
    pub gamma_n: f64,
    /// Health: 0 = healthy (B_n bit 3 clear; RINEX health 0).
    pub health: u32,
}

/// The ICD's fields of one ephemeris as a receiver decodes them (strings
/// 1-4, or RTCM 1020), in the ICD's units: km, km/s, km/s^2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlonassIcdFields {
    /// Slot n, 1..=24 (up to 27 for spares).
    pub slot: u8,
    /// Frequency channel k, -7..=6.
    pub frequency_channel: i8,
    /// t_b resolved to GPS seconds ([`glonass_time_of_day_to_gps_s`] turns
    /// the ICD's t_b x 15 min of the Moscow day into this).
    pub tb_gps_s: f64,
    pub x_km: f64,
    pub y_km: f64,
    pub z_km: f64,
    pub vx_km_s: f64,
    pub vy_km_s: f64,
    pub vz_km_s: f64,
    pub ax_km_s2: f64,
    pub ay_km_s2: f64,
    pub az_km_s2: f64,
    pub tau_n_s: f64,
    pub gamma_n: f64,
    /// B_n bit 3 (the "unhealthy" flag), or any non-zero health word.
    pub unhealthy: bool,
}

/// Plausible bounds of the broadcast fields (the ICD's field ranges: |x|
/// <= 2.7e4 km, |v| <= 4.3 km/s, |tau_n| <= 2e-3 s, |gamma_n| <= 2^-30).
/// The luni-solar acceleration is bounded by its 5-bit sign-magnitude
/// field, 15 x 2^-30 km/s^2: the ICD's printed range (6.2e-9 km/s^2) is
/// exceeded by real broadcasts (7 x 2^-30 = 6.5e-9 km/s^2 on slot 14 in
/// the GMSD7 stream of 2012-10-14), and the Moon and Sun together reach
/// about that at GLONASS altitude.
const MAX_POSITION_KM: f64 = 27_000.0;
const MAX_VELOCITY_KM_S: f64 = 4.3;
const MAX_ACCEL_KM_S2: f64 = 15.0 / 1_073_741_824.0;
const MAX_TAU_N_S: f64 = 2.0e-3;
const MAX_GAMMA_N: f64 = 9.32e-10;

fn check(field: &'static str, value: f64, max: f64) -> Result<f64, NavError> {
    if value.is_finite() && value.abs() <= max {
        Ok(value)
    } else {
        Err(NavError::OutOfRange {
            field,
            value,
            min: -max,
            max,
        })
    }
}

impl GlonassEphemeris {
    /// Build from the ICD fields, checking each against its ICD range.
    pub fn from_icd(f: &GlonassIcdFields) -> Result<Self, NavError> {
        if !(1..=27).contains(&f.slot) {
            return Err(NavError::OutOfRange {
                field: "slot",
                value: f64::from(f.slot),
                min: 1.0,
                max: 27.0,
            });
        }
        if !(-7..=6).contains(&f.frequency_channel) {
            return Err(NavError::OutOfRange {
                field: "frequency_channel",
                value: f64::from(f.frequency_channel),
                min: -7.0,
                max: 6.0,
            });
        }
        if !f.tb_gps_s.is_finite() {
            return Err(NavError::OutOfRange {
                field: "tb_gps_s",
                value: f.tb_gps_s,
                min: 0.0,
                max: f64::MAX,
            });
        }
        let km = 1_000.0;
        Ok(GlonassEphemeris {
            slot: f.slot,
            frequency_channel: f.frequency_channel,
            tb_gps_s: f.tb_gps_s,
            position_m: [
                check("x_km", f.x_km, MAX_POSITION_KM)? * km,
                check("y_km", f.y_km, MAX_POSITION_KM)? * km,
                check("z_km", f.z_km, MAX_POSITION_KM)? * km,
            ],
            velocity_m_s: [
                check("vx_km_s", f.vx_km_s, MAX_VELOCITY_KM_S)? * km,
                check("vy_km_s", f.vy_km_s, MAX_VELOCITY_KM_S)? * km,
                check("vz_km_s", f.vz_km_s, MAX_VELOCITY_KM_S)? * km,
            ],
            lunisolar_m_s2: [
                check("ax_km_s2", f.ax_km_s2, MAX_ACCEL_KM_S2)? * km,
                check("ay_km_s2", f.ay_km_s2, MAX_ACCEL_KM_S2)? * km,
                check("az_km_s2", f.az_km_s2, MAX_ACCEL_KM_S2)? * km,
            ],
            tau_n_s: check("tau_n_s", f.tau_n_s, MAX_TAU_N_S)?,
            gamma_n: check("gamma_n", f.gamma_n, MAX_GAMMA_N)?,
            health: u32::from(f.unhealthy),
        })
    }

    /// The system (always GLONASS), for code shared with `Kepler`.
    pub const fn system(&self) -> System {
        System::Glonass
    }

    /// t - t_b, s.
    pub fn age_s(&self, t_gps_s: f64) -> f64 {
        t_gps_s - self.tb_gps_s
    }

    /// Satellite clock offset dt_sv = -tau_n + gamma_n (t - t_b), s.
    pub fn clock_s(&self, t_gps_s: f64) -> f64 {
        -self.tau_n_s + self.gamma_n * self.age_s(t_gps_s)
    }

    /// Position and velocity in PZ-90.11 at GPS time `t_gps_s`, by RK4
    /// from t_b (ICD 5.1 A.3.1.2). The interval is clamped to
    /// +-[`MAX_PROPAGATION_S`] (the loader never selects an older message).
    pub fn propagate_pz90(&self, t_gps_s: f64) -> ([f64; 3], [f64; 3]) {
        let mut remaining = self
            .age_s(t_gps_s)
            .clamp(-MAX_PROPAGATION_S, MAX_PROPAGATION_S);
        let mut s = initial_state(self);
        let acc = self.lunisolar_m_s2;
        while remaining.abs() > 1e-9 {
            let h = remaining.clamp(-RK4_STEP_S, RK4_STEP_S);
            s = rk4_step(&s, h, &acc);
            remaining -= h;
        }
        ([s[0], s[1], s[2]], [s[3], s[4], s[5]])
    }

    /// Position (WGS-84, Earth-fixed frame of the instant `t_gps_s`) and
    /// clock: the shape of [`crate::ephemeris::Kepler::state`].
    pub fn state(&self, t_gps_s: f64) -> SatState {
        let (p, _) = self.propagate_pz90(t_gps_s);
        SatState {
            position_m: pz90_to_wgs84(p),
            clock_s: self.clock_s(t_gps_s),
        }
    }
}

/// One GLONASS orbit integrated once and evaluated at many times: the
/// state at the latest node of the ICD's RK4 grid reached so far (t_b +
/// k x [`RK4_STEP_S`], on one side of t_b), from which a time t is
/// reached by the remaining whole steps and the one shortened step.
///
/// [`GlonassEphemeris::propagate_pz90`] takes exactly these steps from
/// t_b (whole steps of +-[`RK4_STEP_S`], then `t - t_b - k x 60 s`, which
/// is exact in f64), so a time evaluated here gives its result to the bit
/// (test `arc_equals_the_icd_integration`, and host-tests `rtcm_receiver`
/// on the 1020s of GMSD7 and the GLONASS records of ESBC), while a
/// receiver at 1 Hz pays one shortened step per satellite and epoch and a
/// whole step once a minute, instead of up to 15 steps (30 at the 30 min
/// age limit) per evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlonassArc {
    /// The ephemeris integrated.
    eph: GlonassEphemeris,
    /// Direction of the node from t_b: +1 after, -1 before (0 at t_b).
    dir: i8,
    /// Whole steps from t_b to the node.
    steps: u32,
    /// [x, y, z, vx, vy, vz] at the node, PZ-90.11, m and m/s.
    state: [f64; 6],
}

impl GlonassArc {
    /// The arc of `eph`, at its reference time.
    pub fn new(eph: &GlonassEphemeris) -> Self {
        GlonassArc {
            eph: *eph,
            dir: 0,
            steps: 0,
            state: initial_state(eph),
        }
    }

    /// The ephemeris this arc integrates.
    pub fn ephemeris(&self) -> &GlonassEphemeris {
        &self.eph
    }

    /// Position and velocity in PZ-90.11 at GPS time `t_gps_s`: the same
    /// bits as [`GlonassEphemeris::propagate_pz90`], from the node reached
    /// so far when `t_gps_s` is at or beyond it on the same side of t_b
    /// (else from t_b again); the node moves to the last whole step before
    /// `t_gps_s`.
    pub fn propagate_pz90(&mut self, t_gps_s: f64) -> ([f64; 3], [f64; 3]) {
        let age = self
            .eph
            .age_s(t_gps_s)
            .clamp(-MAX_PROPAGATION_S, MAX_PROPAGATION_S);
        if age.is_nan() {
            let s = initial_state(&self.eph);
            return ([s[0], s[1], s[2]], [s[3], s[4], s[5]]);
        }
        let dir: i8 = if age < 0.0 { -1 } else { 1 };
        let span = age.abs();
        // Whole steps: the largest k with span - 60 k >= 0 (the division
        // may round across an integer, so checked both ways).
        let mut steps = m::floor(span / RK4_STEP_S) as u32;
        while steps > 0 && span - f64::from(steps) * RK4_STEP_S < 0.0 {
            steps -= 1;
        }
        while span - f64::from(steps + 1) * RK4_STEP_S >= 0.0 {
            steps += 1;
        }
        if self.steps > steps || (self.steps > 0 && self.dir != dir) {
            self.dir = 0;
            self.steps = 0;
            self.state = initial_state(&self.eph);
        }
        let h = f64::from(dir) * RK4_STEP_S;
        while self.steps < steps {
            self.state = rk4_step(&self.state, h, &self.eph.lunisolar_m_s2);
            self.steps += 1;
            self.dir = dir;
        }
        // The remainder, exact: age - k x 60 s (propagate_pz90 subtracts
        // the same whole steps one by one, each exactly).
        let rest = age - h * f64::from(steps);
        let s = if rest.abs() > 1e-9 {
            rk4_step(&self.state, rest, &self.eph.lunisolar_m_s2)
        } else {
            self.state
        };
        ([s[0], s[1], s[2]], [s[3], s[4], s[5]])
    }

    /// Position (WGS-84) and clock at `t_gps_s`: the same bits as
    /// [`GlonassEphemeris::state`].
    pub fn state(&mut self, t_gps_s: f64) -> SatState {
        let (p, _) = self.propagate_pz90(t_gps_s);
        SatState {
            position_m: pz90_to_wgs84(p),
            clock_s: self.eph.clock_s(t_gps_s),
        }
    }
}

/// [x, y, z, vx, vy, vz] of the broadcast state at t_b.
fn initial_state(e: &GlonassEphemeris) -> [f64; 6] {
    [
        e.position_m[0],
        e.position_m[1],
        e.position_m[2],
        e.velocity_m_s[0],
        e.velocity_m_s[1],
        e.velocity_m_s[2],
    ]
}

/// The ICD's equations of motion in the rotating PZ-90 frame: the time
/// derivative of [x, y, z, vx, vy, vz].
fn derivative(s: &[f64; 6], acc: &[f64; 3]) -> [f64; 6] {
    let [x, y, z, vx, vy, vz] = *s;
    let r2 = x * x + y * y + z * z;
    let r = m::sqrt(r2);
    let r3 = r2 * r;
    let mu_r3 = MU_PZ90_M3_S2 / r3;
    // 3/2 J2 mu a_e^2 / r^5
    let j = 1.5 * J2_PZ90 * MU_PZ90_M3_S2 * A_E_PZ90_M * A_E_PZ90_M / (r2 * r3);
    let z2 = 5.0 * z * z / r2;
    let w2 = OMEGA_E_PZ90_RAD_S * OMEGA_E_PZ90_RAD_S;
    let w = OMEGA_E_PZ90_RAD_S;
    [
        vx,
        vy,
        vz,
        -mu_r3 * x - j * x * (1.0 - z2) + w2 * x + 2.0 * w * vy + acc[0],
        -mu_r3 * y - j * y * (1.0 - z2) + w2 * y - 2.0 * w * vx + acc[1],
        -mu_r3 * z - j * z * (3.0 - z2) + acc[2],
    ]
}

/// One classical 4th-order Runge-Kutta step of `h` seconds.
fn rk4_step(s: &[f64; 6], h: f64, acc: &[f64; 3]) -> [f64; 6] {
    let add = |a: &[f64; 6], k: &[f64; 6], f: f64| -> [f64; 6] {
        let mut out = *a;
        for (o, k) in out.iter_mut().zip(k) {
            *o += k * f;
        }
        out
    };
    let k1 = derivative(s, acc);
    let k2 = derivative(&add(s, &k1, h / 2.0), acc);
    let k3 = derivative(&add(s, &k2, h / 2.0), acc);
    let k4 = derivative(&add(s, &k3, h), acc);
    let mut out = *s;
    for ((((o, a), b), c), d) in out.iter_mut().zip(&k1).zip(&k2).zip(&k3).zip(&k4) {
        *o += h / 6.0 * (a + 2.0 * b + 2.0 * c + d);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn norm(a: [f64; 3], b: [f64; 3]) -> f64 {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    }

    fn eph(pos_km: [f64; 3], vel_km_s: [f64; 3], acc_km_s2: [f64; 3]) -> GlonassEphemeris {
        GlonassEphemeris::from_icd(&GlonassIcdFields {
            slot: 1,
            frequency_channel: 1,
            tb_gps_s: 1_000_000.0,
            x_km: pos_km[0],
            y_km: pos_km[1],
            z_km: pos_km[2],
            vx_km_s: vel_km_s[0],
            vy_km_s: vel_km_s[1],
            vz_km_s: vel_km_s[2],
            ax_km_s2: acc_km_s2[0],
            ay_km_s2: acc_km_s2[1],
            az_km_s2: acc_km_s2[2],
            tau_n_s: 1e-4,
            gamma_n: 1e-12,
            unhealthy: false,
        })
        .unwrap()
    }

    /// The worked example of the GLONASS ICD (edition 5.1, 2008, Appendix
    /// A.3.1.2): the state at t_b = 06:15 propagated to 06:30 (900 s)
    /// against the ICD's printed position. The ICD computes its reference
    /// with its precise algorithm (luni-solar terms evaluated from the
    /// Sun and Moon ephemerides, not the broadcast constants, which the
    /// example leaves at zero), so the simplified algorithm here is
    /// expected to agree to about a metre; tolerance 2 m.
    ///
    /// Verifies: SPEC-13
    #[test]
    fn icd_5_1_worked_example() {
        const TOL_M: f64 = 2.0;
        let e = eph(
            [-14_081.752701, 18_358.958252, 10_861.302124],
            [-1.02576358, 1.08672147, -3.15732343],
            [0.0; 3],
        );
        let (p, _) = e.propagate_pz90(e.tb_gps_s + 900.0);
        let want = [-14_836.563872e3, 19_249.935476e3, 7_924.017196e3];
        let d = norm(p, want);
        eprintln!("ICD 5.1 example: {d:.3} m from the ICD's position");
        assert!(d < TOL_M, "{d} m: {p:?}");
    }

    /// The worked example of the GLONASS CDMA general ICD (edition 1.0,
    /// 2016, Appendix J): t_e = 11700 s, propagated to 12300 s (600 s),
    /// with broadcast luni-solar accelerations. Same caveat as above;
    /// tolerance 2 m on position, 5 mm/s on velocity.
    #[test]
    fn icd_cdma_worked_example() {
        const TOL_M: f64 = 2.0;
        const TOL_M_S: f64 = 5e-3;
        let e = eph(
            [7_003.008789, -12_206.626953, 21_280.765625],
            [0.7835417, 2.8042530, 1.3525150],
            [0.0, 1.7e-9, -5.41e-9],
        );
        let (p, v) = e.propagate_pz90(e.tb_gps_s + 600.0);
        let want_p = [7_523.174853e3, -10_506.962176e3, 21_999.239866e3];
        let want_v = [0.95012609e3, 2.85568710e3, 1.04068137e3];
        let (dp, dv) = (norm(p, want_p), norm(v, want_v));
        eprintln!("CDMA ICD example: {dp:.3} m, {dv:.5} m/s from the ICD's state");
        assert!(dp < TOL_M, "{dp} m: {p:?}");
        assert!(dv < TOL_M_S, "{dv} m/s: {v:?}");
    }

    /// RK4 at the chosen step against a 5 s step over the full 15-minute
    /// half-interval: under 1 mm apart.
    ///
    /// Verifies: SPEC-13
    #[test]
    fn rk4_step_is_converged() {
        const TOL_M: f64 = 1e-3;
        let e = eph(
            [7_003.008789, -12_206.626953, 21_280.765625],
            [0.7835417, 2.8042530, 1.3525150],
            [0.0, 1.7e-9, -5.41e-9],
        );
        let t = e.tb_gps_s - 900.0;
        let (p, _) = e.propagate_pz90(t);
        let mut s = [
            e.position_m[0],
            e.position_m[1],
            e.position_m[2],
            e.velocity_m_s[0],
            e.velocity_m_s[1],
            e.velocity_m_s[2],
        ];
        for _ in 0..180 {
            s = rk4_step(&s, -5.0, &e.lunisolar_m_s2);
        }
        let d = norm(p, [s[0], s[1], s[2]]);
        eprintln!("RK4 {RK4_STEP_S} s vs 5 s over 900 s: {:.6} m", d);
        assert!(d < TOL_M, "{d} m");
        // Forward then back returns to the broadcast state (1 mm).
        let (p_fwd, v_fwd) = e.propagate_pz90(e.tb_gps_s + 900.0);
        let back = GlonassEphemeris {
            tb_gps_s: e.tb_gps_s + 900.0,
            position_m: p_fwd,
            velocity_m_s: v_fwd,
            ..e
        };
        let (p0, _) = back.propagate_pz90(e.tb_gps_s);
        assert!(norm(p0, e.position_m) < TOL_M);
    }

    /// The arc gives [`GlonassEphemeris::propagate_pz90`]'s result to the
    /// bit, whatever the order of the times asked: 1 Hz forward and
    /// backward across t_b over the whole +-1 h, times on the grid's nodes
    /// and a nanosecond either side, jumps back to an earlier node, to the
    /// other side of t_b and beyond the clamp.
    ///
    /// Verifies: RX-GLONASS-ARC
    #[test]
    fn arc_equals_the_icd_integration() {
        let e = eph(
            [7_003.008789, -12_206.626953, 21_280.765625],
            [0.7835417, 2.8042530, 1.3525150],
            [0.0, 1.7e-9, -5.41e-9],
        );
        let mut times: Vec<f64> = Vec::new();
        // A 1 Hz receiver from t_b - 30 min to t_b + 30 min, with transit
        // times of about 70 ms.
        for k in -1800..=1800 {
            times.push(e.tb_gps_s + f64::from(k) - 0.071_234_567);
        }
        for k in [0.0, 60.0, 120.0, -60.0, 900.0, -900.0, 3_600.0, -3_600.0] {
            times.extend([k, k + 1e-9, k - 1e-9, k + 1e-6, k - 1e-6].map(|d| e.tb_gps_s + d));
        }
        times.extend(
            [
                5_000.0, -5_000.0, 1_799.5, 30.0, -0.5, 1_200.25, 1_199.75, 59.999_999, 0.0,
            ]
            .map(|d| e.tb_gps_s + d),
        );
        let mut arc = GlonassArc::new(&e);
        for (i, &t) in times.iter().enumerate() {
            let want = e.propagate_pz90(t);
            let got = arc.propagate_pz90(t);
            assert_eq!(
                got.0.map(f64::to_bits),
                want.0.map(f64::to_bits),
                "time {i}"
            );
            assert_eq!(
                got.1.map(f64::to_bits),
                want.1.map(f64::to_bits),
                "time {i}"
            );
            assert_eq!(arc.state(t), e.state(t), "time {i}");
        }
        // NaN: the broadcast state, as the ICD integration gives it.
        let nan = arc.propagate_pz90(f64::NAN);
        assert_eq!(nan.0, e.position_m);
    }

    /// The clock model and its sign convention: dt = -tau_n + gamma_n dt.
    #[test]
    fn clock_is_minus_tau_plus_gamma() {
        let e = eph([20_000.0, 0.0, 10_000.0], [0.0, 3.0, 0.0], [0.0; 3]);
        assert!((e.clock_s(e.tb_gps_s) + 1e-4).abs() < 1e-18);
        assert!((e.clock_s(e.tb_gps_s + 600.0) - (-1e-4 + 600e-12)).abs() < 1e-18);
    }

    /// PZ-90.11 to WGS-84 moves a GLONASS orbit (25,500 km) by under 1 cm,
    /// and by the EPSG:7960 translation at the origin.
    #[test]
    fn frame_transformation_is_centimetric() {
        const TOL_M: f64 = 0.01;
        let p = [15_000e3, -12_000e3, 16_000e3];
        assert!(norm(pz90_to_wgs84(p), p) < TOL_M);
        assert!(norm(pz90_to_wgs84(p), p) > 1e-4);
        assert!(norm(pz90_to_wgs84([0.0; 3]), [-0.003, -0.001, 0.0]) < 1e-12);
    }

    /// GLONASS time: 2020-06-25 00:00:00 GPST is 2020-06-24 23:59:42 UTC
    /// (18 leap seconds), 02:59:42 Moscow time; t_b = 02:45:00 Moscow is
    /// 2020-06-24 23:45:18 GPST, and a t_b just after Moscow midnight
    /// resolves to the next GLONASS day when the receiver is there.
    ///
    /// Verifies: RX-GLONASS-TIME
    #[test]
    fn glonass_time_and_leap_seconds() {
        let t = 2111.0 * 604_800.0 + 4.0 * DAY_S;
        assert_eq!(gps_minus_utc_s(t), 18.0);
        // 2005: 13 leap seconds.
        assert_eq!(gps_minus_utc_s(796_435_200.0), 13.0);
        assert!((glonass_time_of_day_s(t) - (2.0 * 3600.0 + 59.0 * 60.0 + 42.0)).abs() < 1e-6);
        let tb = glonass_time_of_day_to_gps_s(2.0 * 3600.0 + 45.0 * 60.0, t);
        assert!((tb - (t - 15.0 * 60.0 + 18.0)).abs() < 1e-6, "{}", tb - t);
        // Receiver at 20:50 GPST (23:49:42 Moscow); t_b = 00:15 Moscow
        // of the next day is 25 min later.
        let rx = t + 20.0 * 3600.0 + 50.0 * 60.0;
        let tb = glonass_time_of_day_to_gps_s(15.0 * 60.0, rx);
        assert!((tb - rx - (25.0 * 60.0 + 18.0)).abs() < 1e-6, "{}", tb - rx);
    }

    /// Out-of-range ICD fields are typed errors naming the field.
    #[test]
    fn bad_fields_are_refused() {
        let good = GlonassIcdFields {
            slot: 3,
            frequency_channel: 5,
            tb_gps_s: 0.0,
            x_km: 1.0,
            y_km: 1.0,
            z_km: 1.0,
            vx_km_s: 0.0,
            vy_km_s: 0.0,
            vz_km_s: 0.0,
            ax_km_s2: 0.0,
            ay_km_s2: 0.0,
            az_km_s2: 0.0,
            tau_n_s: 0.0,
            gamma_n: 0.0,
            unhealthy: false,
        };
        assert!(GlonassEphemeris::from_icd(&good).is_ok());
        for (bad, name) in [
            (
                GlonassIcdFields {
                    frequency_channel: 9,
                    ..good
                },
                "frequency_channel",
            ),
            (GlonassIcdFields { slot: 0, ..good }, "slot"),
            (
                GlonassIcdFields {
                    x_km: f64::NAN,
                    ..good
                },
                "x_km",
            ),
            (
                GlonassIcdFields {
                    tau_n_s: 1.0,
                    ..good
                },
                "tau_n_s",
            ),
        ] {
            match GlonassEphemeris::from_icd(&bad) {
                Err(NavError::OutOfRange { field, .. }) => assert_eq!(field, name),
                other => panic!("{name}: {other:?}"),
            }
        }
    }

    /// Channel frequencies: k = 0 at the nominal carriers, L2/L1 = 7/9
    /// for every k (so the iono-free factor does not depend on k).
    #[test]
    fn channel_frequencies() {
        assert_eq!(l1_hz(0), 1_602.0e6);
        assert_eq!(l1_hz(-7), 1_598.062_5e6);
        assert_eq!(l2_hz(6), 1_248.625e6);
        for k in -7..=6 {
            assert!((l2_hz(k) / l1_hz(k) - 7.0 / 9.0).abs() < 1e-15);
        }
    }
}
