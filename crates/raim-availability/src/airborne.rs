//! Airborne error curves that the engine passes to raim-core as an
//! observation's own sigma (`LinearObservation::sigma_m`), beside the
//! core's default GPS L1/L5 curves and its Galileo E1/E5a table
//! (docs/AVAILABILITY.md "The Galileo airborne curve").
//!
//! [`ed259a_maast_variance_m2`] is the dual-frequency model of MAAST for
//! ARAIM 2 (Stanford GPS Lab, `stanford-gps-lab/maast_for_araim_2`, 2024,
//! ADD v4.2): its `af_cnmp_259a.m` ("airborne pseudorange confidence per
//! DFMC SBAS MOPS ED259A", the same curve for GPS L1/L5 and Galileo
//! E1/E5a) and the dual-frequency ionospheric residual its
//! `usrprocess_araim.m` adds to it. That is the ED-259A curve as the
//! reference tool implements it, not a transcription of ED-259A itself
//! (not at hand); the tool's own comment says its code-noise formulas
//! "need to be double-checked".

/// One degree in radians.
const DEG_RAD: f64 = core::f64::consts::PI / 180.0;

/// The iono-free airborne multipath and noise variance (m^2) at `el_rad`,
/// as MAAST for ARAIM 2's `af_cnmp_259a` times its `GAMMA_L1_L5` (the
/// caller's scaling): 0.4^2 + (0.34 + 0.40 exp(-el / 14 deg))^2.
pub fn ed259a_maast_airborne_variance_m2(el_rad: f64) -> f64 {
    let el_deg = el_rad / DEG_RAD;
    let mp = 0.34 + 0.40 * libm::exp(-el_deg / 14.0);
    0.4 * 0.4 + mp * mp
}

/// The dual-frequency ionospheric residual sigma (m) MAAST for ARAIM 2
/// adds to the airborne term (`usrprocess_araim.m`, `sig_uire_df`):
/// 40 / (261 + el_deg^2) + 0.018.
pub fn ed259a_maast_iono_sigma_m(el_rad: f64) -> f64 {
    let el_deg = el_rad / DEG_RAD;
    40.0 / (261.0 + el_deg * el_deg) + 0.018
}

/// The nominal variance (m^2) of one satellite at `el_rad` under MAAST for
/// ARAIM 2's model: the DO-229 troposphere (raim-core's `tropo_sigma_m`,
/// the formula MAAST writes as `sig_trv`), plus
/// [`ed259a_maast_airborne_variance_m2`], plus
/// [`ed259a_maast_iono_sigma_m`]^2. C_int = sigma_URA^2 + this, C_acc =
/// sigma_URE^2 + this (raim-core adds the signal in space).
pub fn ed259a_maast_variance_m2(el_rad: f64) -> f64 {
    let tropo = raim_core::araim::error_model::tropo_sigma_m(libm::sin(el_rad));
    let iono = ed259a_maast_iono_sigma_m(el_rad);
    tropo * tropo + ed259a_maast_airborne_variance_m2(el_rad) + iono * iono
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The curve at 90 and 5 degrees against values worked out by hand
    /// from MAAST's formulas (exp(-90/14) = 0.0016148, exp(-5/14) =
    /// 0.69967): 0.27604 and 0.54424 m^2 of airborne variance, 0.022784
    /// and 0.15786 m of ionospheric residual.
    #[test]
    fn ed259a_maast_curve_by_hand() {
        let (z, lo) = (90.0 * DEG_RAD, 5.0 * DEG_RAD);
        assert!((ed259a_maast_airborne_variance_m2(z) - 0.276_04).abs() < 1e-5);
        assert!((ed259a_maast_airborne_variance_m2(lo) - 0.544_24).abs() < 1e-5);
        assert!((ed259a_maast_iono_sigma_m(z) - 0.022_784).abs() < 1e-6);
        assert!((ed259a_maast_iono_sigma_m(lo) - 0.157_86).abs() < 1e-5);
        let tropo_z = 0.12 * 1.001 / (0.002_001f64 + 1.0).sqrt();
        let want = tropo_z * tropo_z + 0.276_04 + 0.022_784f64.powi(2);
        assert!((ed259a_maast_variance_m2(z) - want).abs() < 1e-5);
    }
}
