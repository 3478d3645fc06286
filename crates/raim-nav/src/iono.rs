//! Klobuchar single-frequency ionospheric model (IS-GPS-200 20.3.3.5.2.5),
//! with the broadcast alpha/beta from the GPS navigation file header.
//! Other frequencies scale by (f_L1 / f)^2 (first-order ionosphere).

use crate::ephemeris::C_M_S;
use core::f64::consts::PI;

use crate::m;

/// GPS L1 / Galileo E1 carrier, Hz.
pub const F_L1_HZ: f64 = 1_575.42e6;
/// BeiDou B1I carrier, Hz.
pub const F_B1I_HZ: f64 = 1_561.098e6;

/// Broadcast Klobuchar coefficients: alpha in s, s/semicircle^n; beta in
/// s, s/semicircle^n.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Klobuchar {
    pub alpha: [f64; 4],
    pub beta: [f64; 4],
}

impl Klobuchar {
    /// L1 ionospheric delay, m, for a user at geodetic latitude/longitude
    /// (rad), a satellite at azimuth/elevation (rad), at GPS time of week `t_s`.
    pub fn delay_l1_m(
        &self,
        lat_rad: f64,
        lon_rad: f64,
        az_rad: f64,
        el_rad: f64,
        t_s: f64,
    ) -> f64 {
        // Work in semicircles, as the ICD does.
        let phi_u = lat_rad / PI;
        let lam_u = lon_rad / PI;
        let e = el_rad / PI;
        let psi = 0.0137 / (e + 0.11) - 0.022;
        let phi_i = (phi_u + psi * m::cos(az_rad)).clamp(-0.416, 0.416);
        let lam_i = lam_u + psi * m::sin(az_rad) / m::cos(phi_i * PI);
        let phi_m = phi_i + 0.064 * m::cos((lam_i - 1.617) * PI);
        let t = m::rem_euclid(4.32e4 * lam_i + t_s, 86_400.0);
        let d = 0.53 - e;
        let f = 1.0 + 16.0 * (d * d * d);
        let poly = |c: &[f64; 4]| c[0] + phi_m * (c[1] + phi_m * (c[2] + phi_m * c[3]));
        let amp = poly(&self.alpha).max(0.0);
        let per = poly(&self.beta).max(72_000.0);
        let x = 2.0 * PI * (t - 50_400.0) / per;
        let delay_s = if x.abs() < 1.57 {
            f * (5e-9 + amp * (1.0 - x * x / 2.0 + (x * x) * (x * x) / 24.0))
        } else {
            f * 5e-9
        };
        delay_s * C_M_S
    }
}

/// Scale an L1 ionospheric delay to carrier `f_hz` (first order, 1/f^2).
pub fn scale_to_frequency(delay_l1_m: f64, f_hz: f64) -> f64 {
    {
        let r = F_L1_HZ / f_hz;
        delay_l1_m * (r * r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tolerance on closed-form delays, m (float rounding only).
    const TOL_M: f64 = 1e-9;

    /// At night (|x| >= 1.57) the model is the constant 5 ns times the
    /// obliquity factor F = 1 + 16 (0.53 - E)^3; at zenith E = 0.5.
    #[test]
    fn night_floor_at_zenith_is_5_ns_times_obliquity() {
        let k = Klobuchar {
            alpha: [1e-8, 0.0, 0.0, 0.0],
            beta: [72_000.0, 0.0, 0.0, 0.0],
        };
        // Longitude 0, GPS time 0 h: local time 0 h, x = -2 pi 50400/72000.
        let d = k.delay_l1_m(0.0, 0.0, 0.0, PI / 2.0, 0.0);
        let f = 1.0 + 16.0 * 0.03f64.powi(3);
        assert!((d - f * 5e-9 * C_M_S).abs() < TOL_M, "{d}");
    }

    /// At 14:00 local time (x = 0) the delay is F (5 ns + AMP); with only
    /// alpha0 set, AMP = alpha0 wherever the pierce point is.
    #[test]
    fn afternoon_peak_is_floor_plus_amplitude() {
        let k = Klobuchar {
            alpha: [2e-8, 0.0, 0.0, 0.0],
            beta: [100_000.0, 0.0, 0.0, 0.0],
        };
        // Zenith: psi = 0.0137/0.61 - 0.022, pierce point shifted only in
        // latitude for az = 0; lam_i = lam_u = 0 so local t = t_gps.
        let d = k.delay_l1_m(0.0, 0.0, 0.0, PI / 2.0, 50_400.0);
        let f = 1.0 + 16.0 * 0.03f64.powi(3);
        assert!((d - f * (5e-9 + 2e-8) * C_M_S).abs() < TOL_M, "{d}");
        // Negative amplitude polynomials are clamped to zero.
        let neg = Klobuchar {
            alpha: [-2e-8, 0.0, 0.0, 0.0],
            ..k
        };
        let d = neg.delay_l1_m(0.0, 0.0, 0.0, PI / 2.0, 50_400.0);
        assert!((d - f * 5e-9 * C_M_S).abs() < TOL_M);
    }

    /// Low elevations get the obliquity factor: at 5 deg, F = 1 + 16 (0.53 -
    /// 0.02778)^3 = 3.0267.
    #[test]
    fn obliquity_factor_at_five_degrees() {
        let k = Klobuchar {
            alpha: [0.0; 4],
            beta: [72_000.0, 0.0, 0.0, 0.0],
        };
        let d = k.delay_l1_m(0.6, 0.2, 1.0, 5f64.to_radians(), 0.0);
        let e: f64 = 5.0 / 180.0;
        assert!((d - (1.0 + 16.0 * (0.53 - e).powi(3)) * 5e-9 * C_M_S).abs() < TOL_M);
        assert!((1.0 + 16.0 * (0.53 - e).powi(3) - 3.0267).abs() < 1e-4);
    }

    /// B1I is 1.8 % lower in frequency than L1: delay 1.84 % larger.
    #[test]
    fn frequency_scaling() {
        let s = scale_to_frequency(1.0, F_B1I_HZ);
        assert!((s - (1575.42f64 / 1561.098).powi(2)).abs() < 1e-12);
        assert!((s - 1.0184).abs() < 1e-4);
    }
}
