//! Broadcast ephemeris to satellite ECEF position and clock offset
//! (IS-GPS-200 Table 20-IV and 20.3.3.3.3.1, Galileo OS SIS ICD §5.1.1 and
//! §5.1.4, BeiDou B1I ICD §5.2.4.12 with the GEO rotation).
//!
//! The `rinex` crate (light configuration) gives the broadcast parameters;
//! the orbit and clock are evaluated here so that the heavy `nav` feature
//! (anise, 250 crates) is not needed. The Kepler iteration is capped.

use raim_core::System;

use crate::m;

/// Speed of light, m/s (IS-GPS-200 20.3.4.3).
pub const C_M_S: f64 = 299_792_458.0;
/// WGS-84 Earth rotation rate used by GPS and Galileo, rad/s.
pub const OMEGA_E_GPS_RAD_S: f64 = 7.292_115_146_7e-5;
/// CGCS2000 Earth rotation rate (BeiDou ICD), rad/s.
pub const OMEGA_E_BDS_RAD_S: f64 = 7.292_115e-5;
/// GPS WGS-84 gravitational constant, m^3/s^2 (IS-GPS-200 20.3.3.3.3.1).
pub const MU_GPS_M3_S2: f64 = 3.986_005e14;
/// Galileo (GTRF) and BeiDou (CGCS2000) gravitational constant, m^3/s^2.
pub const MU_GAL_BDS_M3_S2: f64 = 3.986_004_418e14;
/// Seconds in a week.
pub const WEEK_S: f64 = 604_800.0;
/// BeiDou time is GPS time minus 14 s (BDS ICD §5.2.4.1; constant, no leap seconds).
pub const BDT_MINUS_GPST_S: f64 = -14.0;
/// Kepler equation: stop when the eccentric anomaly changes by less than this, rad.
const KEPLER_TOLERANCE_RAD: f64 = 1e-14;
/// Kepler equation: iteration cap (e < 0.03 converges in < 10).
const KEPLER_MAX_ITERATIONS: usize = 30;

/// One broadcast ephemeris (Keplerian elements, harmonic corrections and the
/// clock polynomial), times converted to the GPS time scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kepler {
    pub system: System,
    pub prn: u8,
    /// Time of clock, GPS seconds since 1980-01-06 (continuous).
    pub toc_gps_s: f64,
    /// Time of ephemeris, seconds of the system's week (GPS/GST week or BDT week).
    pub toe_sow_s: f64,
    pub af0_s: f64,
    pub af1_s_s: f64,
    pub af2_s_s2: f64,
    pub sqrt_a_m05: f64,
    pub e: f64,
    pub i0_rad: f64,
    pub omega0_rad: f64,
    pub omega_rad: f64,
    pub m0_rad: f64,
    pub delta_n_rad_s: f64,
    pub omega_dot_rad_s: f64,
    pub idot_rad_s: f64,
    pub cuc_rad: f64,
    pub cus_rad: f64,
    pub crc_m: f64,
    pub crs_m: f64,
    pub cic_rad: f64,
    pub cis_rad: f64,
    /// Group delay to apply for the single-frequency code used, s: GPS TGD
    /// (L1 C/A), Galileo BGD(E1,E5b) for I/NAV, BeiDou TGD1 (B1I). 0 if absent.
    pub group_delay_s: f64,
    /// Galileo I/NAV only: BGD(E1,E5a), s (the record carries both BGDs),
    /// for the E1/E5a iono-free combination with the I/NAV clock
    /// (`ranging::iono_free`); 0 otherwise or if absent.
    pub group_delay_e5a_s: f64,
    /// Raw health word from the nav file (0 = healthy for GPS, Galileo, BeiDou).
    pub health: u32,
    /// Issue of data, for diagnostics.
    pub iod: u32,
}

/// Satellite state at one transmit time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SatState {
    /// ECEF position at the transmit time, in the ECEF frame of that instant, m.
    pub position_m: [f64; 3],
    /// Satellite clock offset (polynomial + relativistic eccentricity term), s.
    /// The group delay is not included.
    pub clock_s: f64,
}

impl Kepler {
    /// BeiDou GEO satellites (BDS-2 C01-C05, BDS-3 C59-C63) use the ICD's
    /// extra -5 degree rotation (BDS ICD §5.2.4.12, the "GEO" branch).
    pub fn is_beidou_geo(&self) -> bool {
        self.system == System::Beidou && (self.prn <= 5 || (59..=63).contains(&self.prn))
    }

    fn mu_omega(&self) -> (f64, f64) {
        match self.system {
            System::Gps | System::Qzss => (MU_GPS_M3_S2, OMEGA_E_GPS_RAD_S),
            System::Galileo => (MU_GAL_BDS_M3_S2, OMEGA_E_GPS_RAD_S),
            System::Beidou => (MU_GAL_BDS_M3_S2, OMEGA_E_BDS_RAD_S),
            // GLONASS broadcasts state vectors, not Keplerian elements; the
            // loader never builds a Kepler for it. WGS-84 values as a fallback.
            System::Glonass => (MU_GPS_M3_S2, OMEGA_E_GPS_RAD_S),
        }
    }

    /// Seconds of the satellite system's week at GPS time `t_gps_s`.
    fn system_sow(&self, t_gps_s: f64) -> f64 {
        let t = match self.system {
            System::Beidou => t_gps_s + BDT_MINUS_GPST_S,
            _ => t_gps_s,
        };
        m::rem_euclid(t, WEEK_S)
    }

    /// t - toe in seconds, with the week crossover of IS-GPS-200 20.3.3.3.3.1.
    pub fn tk_s(&self, t_gps_s: f64) -> f64 {
        let mut tk = self.system_sow(t_gps_s) - self.toe_sow_s;
        if tk > WEEK_S / 2.0 {
            tk -= WEEK_S;
        } else if tk < -WEEK_S / 2.0 {
            tk += WEEK_S;
        }
        tk
    }

    /// Satellite clock polynomial a0 + a1 dt + a2 dt^2 at GPS time `t_gps_s`
    /// (IS-GPS-200 20.3.3.3.3.1), without the relativistic term. Valid
    /// before toc too (the `rinex` crate returns None there).
    pub fn clock_polynomial_s(&self, t_gps_s: f64) -> f64 {
        let dt = t_gps_s - self.toc_gps_s;
        self.af0_s + self.af1_s_s * dt + self.af2_s_s2 * dt * dt
    }

    /// Position (ECEF of the transmit instant) and clock at GPS time `t_gps_s`.
    pub fn state(&self, t_gps_s: f64) -> SatState {
        let (mu, omega_e) = self.mu_omega();
        let a = self.sqrt_a_m05 * self.sqrt_a_m05;
        let n0 = m::sqrt(mu / (a * a * a));
        let tk = self.tk_s(t_gps_s);
        let n = n0 + self.delta_n_rad_s;
        let mk = self.m0_rad + n * tk;
        let e = self.e;
        let mut ek = mk;
        for _ in 0..KEPLER_MAX_ITERATIONS {
            let next = mk + e * m::sin(ek);
            let done = (next - ek).abs() < KEPLER_TOLERANCE_RAD;
            ek = next;
            if done {
                break;
            }
        }
        let (sin_e, cos_e) = m::sin_cos(ek);
        let nu = m::atan2(m::sqrt(1.0 - e * e) * sin_e, cos_e - e);
        let phi = nu + self.omega_rad;
        let (s2, c2) = m::sin_cos(2.0 * phi);
        let u = phi + self.cus_rad * s2 + self.cuc_rad * c2;
        let r = a * (1.0 - e * cos_e) + self.crs_m * s2 + self.crc_m * c2;
        let i = self.i0_rad + self.idot_rad_s * tk + self.cis_rad * s2 + self.cic_rad * c2;
        let (x_orb, y_orb) = (r * m::cos(u), r * m::sin(u));
        let (sin_i, cos_i) = m::sin_cos(i);
        let toe = self.toe_sow_s;
        let position_m = if self.is_beidou_geo() {
            // BDS ICD: GEO elements are in an inertial-like frame; rotate by
            // -5 deg about X, then by omega_e tk about Z.
            let omega = self.omega0_rad + self.omega_dot_rad_s * tk - omega_e * toe;
            let (so, co) = m::sin_cos(omega);
            let xg = x_orb * co - y_orb * cos_i * so;
            let yg = x_orb * so + y_orb * cos_i * co;
            let zg = y_orb * sin_i;
            let (sf, cf) = m::sin_cos(-5.0f64.to_radians());
            // Rx(-5 deg)
            let (x1, y1, z1) = (xg, cf * yg + sf * zg, -sf * yg + cf * zg);
            let (sz, cz) = m::sin_cos(omega_e * tk);
            // Rz(omega_e tk)
            [cz * x1 + sz * y1, -sz * x1 + cz * y1, z1]
        } else {
            let omega = self.omega0_rad + (self.omega_dot_rad_s - omega_e) * tk - omega_e * toe;
            let (so, co) = m::sin_cos(omega);
            [
                x_orb * co - y_orb * cos_i * so,
                x_orb * so + y_orb * cos_i * co,
                y_orb * sin_i,
            ]
        };
        // Relativistic eccentricity term F e sqrt(A) sin(E), F = -2 sqrt(mu)/c^2.
        let f = -2.0 * m::sqrt(mu) / (C_M_S * C_M_S);
        let clock_s = self.clock_polynomial_s(t_gps_s) + f * e * self.sqrt_a_m05 * sin_e;
        SatState {
            position_m,
            clock_s,
        }
    }
}

/// A circular, equatorial orbit with every correction zero: a closed form
/// (tests here and in `ranging`).
#[cfg(test)]
pub(crate) fn circular(system: System, prn: u8) -> Kepler {
    Kepler {
        system,
        prn,
        toc_gps_s: 1000.0 * WEEK_S,
        toe_sow_s: 0.0,
        af0_s: 1e-4,
        af1_s_s: 1e-11,
        af2_s_s2: 0.0,
        sqrt_a_m05: 5153.6,
        e: 0.0,
        i0_rad: 0.0,
        omega0_rad: 0.0,
        omega_rad: 0.0,
        m0_rad: 0.0,
        delta_n_rad_s: 0.0,
        omega_dot_rad_s: 0.0,
        idot_rad_s: 0.0,
        cuc_rad: 0.0,
        cus_rad: 0.0,
        crc_m: 0.0,
        crs_m: 0.0,
        cic_rad: 0.0,
        cis_rad: 0.0,
        group_delay_s: 0.0,
        group_delay_e5a_s: 0.0,
        health: 0,
        iod: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Closed-form positions of a circular equatorial orbit: at t = toe the
    /// satellite is on the X axis at radius A; after tk it has moved by the
    /// inertial angle (n - omega_e) tk in the ECEF frame. Tolerance: float
    /// rounding on 2.66e7 m.
    #[test]
    fn circular_equatorial_orbit_matches_closed_form() {
        const TOL_M: f64 = 1e-6;
        let k = circular(System::Gps, 1);
        let a = 5153.6f64 * 5153.6;
        let s = k.state(1000.0 * WEEK_S);
        assert!((s.position_m[0] - a).abs() < TOL_M && s.position_m[1].abs() < TOL_M);
        let tk = 3600.0;
        let s = k.state(1000.0 * WEEK_S + tk);
        let n = (MU_GPS_M3_S2 / (a * a * a)).sqrt();
        let ang = (n - OMEGA_E_GPS_RAD_S) * tk;
        assert!((s.position_m[0] - a * ang.cos()).abs() < TOL_M);
        assert!((s.position_m[1] - a * ang.sin()).abs() < TOL_M);
        assert!(s.position_m[2].abs() < TOL_M);
        // The clock polynomial: af0 + af1 dt, before and after toc alike.
        assert!((s.clock_s - (1e-4 + 1e-11 * tk)).abs() < 1e-18);
        let before = k.clock_polynomial_s(1000.0 * WEEK_S - 100.0);
        assert!((before - (1e-4 - 1e-9)).abs() < 1e-18);
    }

    /// The week crossover: toe late in the week, t early in the next.
    #[test]
    fn tk_wraps_across_the_week() {
        let mut k = circular(System::Gps, 1);
        k.toe_sow_s = WEEK_S - 600.0;
        assert!((k.tk_s(1001.0 * WEEK_S + 600.0) - 1200.0).abs() < 1e-9);
        // BeiDou: BDT = GPST - 14 s.
        let mut b = circular(System::Beidou, 20);
        b.toe_sow_s = 100.0;
        assert!((b.tk_s(1000.0 * WEEK_S + 114.0)).abs() < 1e-9);
    }

    /// Kepler's equation with e = 0.3 (far beyond any GNSS orbit) converges
    /// within the cap: M = E - e sin E holds to 1e-12 rad.
    #[test]
    fn kepler_equation_converges_for_large_eccentricity() {
        let mut k = circular(System::Galileo, 11);
        k.e = 0.3;
        k.m0_rad = 1.0;
        let s = k.state(1000.0 * WEEK_S);
        let r = (s.position_m.iter().map(|v| v * v).sum::<f64>()).sqrt();
        let a = 5153.6f64 * 5153.6;
        // r = a (1 - e cos E) with E solving E - 0.3 sin E = 1.
        let mut e_anom = 1.0f64;
        for _ in 0..200 {
            e_anom = 1.0 + 0.3 * e_anom.sin();
        }
        assert!((r - a * (1.0 - 0.3 * e_anom.cos())).abs() < 1e-4);
    }
}

#[cfg(test)]
#[path = "ephemeris_cov_tests.rs"]
mod ephemeris_cov_tests;
