//! The ADD's nominal error model (SPEC §9.1): C_int and C_acc of one
//! satellite from its elevation, with the DO-229 airborne troposphere,
//! the airborne multipath and receiver noise curves (GPS L1/L5; used for
//! Galileo too, since the ADD's Galileo curve is not at hand: SPEC §9.1
//! says so, and docs/ARAIM.md), and the dual-frequency iono-free factor.

use crate::real::Real;

/// L1 carrier (MHz).
const F1_MHZ: f64 = 1575.42;
/// L5 carrier (MHz).
const F5_MHZ: f64 = 1176.45;
/// One degree in radians: the curves are written with theta in degrees.
const DEG_RAD: f64 = core::f64::consts::PI / 180.0;

/// The square of the iono-free noise amplification,
/// (f1^4 + f5^4) / (f1^2 - f5^2)^2 (its root is about 2.59).
pub fn iono_free_factor_sq() -> f64 {
    let (a, b) = (F1_MHZ * F1_MHZ, F5_MHZ * F5_MHZ);
    (a * a + b * b) / ((a - b) * (a - b))
}

/// The elevation (rad) of a geometry row: sin theta = |up| / |row|.
pub fn elevation_from_g<T: Real>(g_enu: &[T; 3]) -> T {
    let [e, n, u] = *g_enu;
    let norm = (e * e + n * n + u * u).sqrt();
    (u.abs() / norm).asin()
}

/// The elevation-dependent variance shared by C_int and C_acc (m^2):
/// sigma_tropo^2 + sigma_user^2.
pub fn nominal_variance_m2<T: Real>(el_rad: T) -> T {
    let s = el_rad.sin();
    let tropo = T::of(0.12 * 1.001) / (T::of(0.002001) + s * s).sqrt();
    let el_deg = el_rad / T::of(DEG_RAD);
    let mp = T::of(0.13) + T::of(0.53) * (-el_deg / T::of(10.0)).exp();
    let noise = T::of(0.15) + T::of(0.43) * (-el_deg / T::of(6.9)).exp();
    tropo * tropo + T::of(iono_free_factor_sq()) * (mp * mp + noise * noise)
}

/// (C_int, C_acc) in m^2 for one satellite: sigma_URA^2 (resp.
/// sigma_URE^2) plus the nominal variance at elevation `el_rad`.
pub fn variances_m2<T: Real>(el_rad: T, sigma_ura_m: T, sigma_ure_m: T) -> (T, T) {
    let v = nominal_variance_m2(el_rad);
    (sigma_ura_m * sigma_ura_m + v, sigma_ure_m * sigma_ure_m + v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::araim::tests::appendix_d;

    /// C_acc,ii, m^2: the ADD prints four decimals.
    const TOL_M2: f64 = 1e-4;

    /// SPEC §9.1: with the elevation from each G row and the GPS curves for
    /// Galileo too, the model reproduces all ten published C_acc values,
    /// and C_int - C_acc = 0.75^2 - 0.5^2 for every satellite.
    #[test]
    fn reproduces_appendix_d_c_acc() {
        for (i, row) in appendix_d::ROWS.iter().enumerate() {
            let el = elevation_from_g(&row.g);
            let (c_int, c_acc) = variances_m2(el, 0.75, 0.5);
            assert!(
                (c_acc - row.c_acc).abs() <= TOL_M2,
                "sat {i}: C_acc {c_acc} vs published {}",
                row.c_acc
            );
            assert!(
                (c_int - row.c_int).abs() <= TOL_M2,
                "sat {i}: C_int {c_int}"
            );
        }
    }

    #[test]
    fn iono_free_factor_is_about_2_59() {
        assert!((iono_free_factor_sq().sqrt() - 2.5883).abs() < 1e-3);
    }
}
