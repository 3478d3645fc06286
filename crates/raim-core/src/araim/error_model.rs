//! The nominal error model (SPEC §9.1), and the one home of the DO-229
//! elevation curves that the snapshot sigma model (`sigma.rs`) uses too.
//!
//! ARAIM: C_int and C_acc of one satellite from its elevation, with the
//! DO-229 airborne troposphere and the ADD's airborne multipath and
//! receiver noise curves (GPS L1/L5; used for Galileo too, since the ADD's
//! Galileo curve is not at hand: SPEC §9.1 says so, and docs/ARAIM.md),
//! through the dual-frequency iono-free factor. MAAST's Galileo E1/E5a
//! table is here too ([`galileo_e1e5a_sigma_m`]), for a caller that
//! passes it as the observation's sigma (the availability engine, on
//! request: docs/AVAILABILITY.md "The Galileo airborne curve").
//!
//! Every transcendental goes through [`Real`]'s `libm` methods (`sin_m`,
//! `exp_m`, `asin_m`, ...), never the platform's: the host and the M4F
//! evaluate the curves bit for bit alike.

use crate::real::Real;

/// L1 carrier (MHz).
const F1_MHZ: f64 = 1575.42;
/// L5 carrier (MHz).
const F5_MHZ: f64 = 1176.45;
/// One degree in radians: the ADD writes its curves with theta in degrees.
const DEG_RAD: f64 = core::f64::consts::PI / 180.0;
/// DO-229 A.4.4.10.4: the Earth's radius and the ionospheric shell height
/// of the obliquity factor (km).
const EARTH_RADIUS_KM: f64 = 6378.1363;
const IONO_SHELL_KM: f64 = 350.0;

/// DO-229D A.4.2.4: the airborne tropospheric residual sigma (m) at an
/// elevation of sine `sin_el`, 0.12 m at the zenith:
/// 0.12 * 1.001 / sqrt(0.002001 + sin^2 el).
pub fn tropo_sigma_m<T: Real>(sin_el: T) -> T {
    T::of(0.12) * T::of(1.001) / (T::of(0.002_001) + sin_el * sin_el).sqrt()
}

/// DO-229D J.2.4: the airborne multipath sigma (m) at `el_deg` degrees,
/// 0.13 + 0.53 exp(-el / 10 deg).
pub fn multipath_sigma_m<T: Real>(el_deg: T) -> T {
    T::of(0.13) + T::of(0.53) * (-el_deg / T::of(10.0)).exp_m()
}

/// The ADD's airborne receiver-noise sigma (m) of one frequency at
/// `el_deg` degrees, 0.15 + 0.43 exp(-el / 6.9 deg).
pub fn noise_sigma_m<T: Real>(el_deg: T) -> T {
    T::of(0.15) + T::of(0.43) * (-el_deg / T::of(6.9)).exp_m()
}

/// DO-229D A.4.4.10.4: the thin-shell ionospheric obliquity factor at
/// `el_rad`, 1 / sqrt(1 - (R_e cos el / (R_e + h_I))^2).
pub fn iono_obliquity<T: Real>(el_rad: T) -> T {
    let re_ratio = T::of(EARTH_RADIUS_KM) / (T::of(EARTH_RADIUS_KM) + T::of(IONO_SHELL_KM));
    let c = re_ratio * el_rad.cos_m();
    T::one() / (T::one() - c * c).sqrt()
}

/// The square of the iono-free noise amplification,
/// (f1^4 + f5^4) / (f1^2 - f5^2)^2 (its root is about 2.59).
pub fn iono_free_factor_sq() -> f64 {
    let (a, b) = (F1_MHZ * F1_MHZ, F5_MHZ * F5_MHZ);
    (a * a + b * b) / ((a - b) * (a - b))
}

/// The elevation (rad) of a geometry row or a line of sight:
/// sin theta = |up| / |row|.
pub fn elevation_from_g<T: Real>(g_enu: &[T; 3]) -> T {
    let [e, n, u] = *g_enu;
    let norm = (e * e + n * n + u * u).sqrt();
    (u.abs() / norm).asin_m()
}

/// The per-frequency airborne variance sigma_multipath^2 + sigma_noise^2
/// (m^2) at `el_rad`.
pub fn airborne_variance_m2<T: Real>(el_rad: T) -> T {
    let el_deg = el_rad / T::of(DEG_RAD);
    let mp = multipath_sigma_m(el_deg);
    let noise = noise_sigma_m(el_deg);
    mp * mp + noise * noise
}

/// The elevation-dependent variance shared by C_int and C_acc (m^2):
/// sigma_tropo^2 + sigma_user^2, sigma_user^2 the airborne variance
/// through the L1/L5 iono-free combination.
pub fn nominal_variance_m2<T: Real>(el_rad: T) -> T {
    let tropo = tropo_sigma_m(el_rad.sin_m());
    tropo * tropo + T::of(iono_free_factor_sq()) * airborne_variance_m2(el_rad)
}

/// (C_int, C_acc) in m^2 for one satellite: sigma_URA^2 (resp.
/// sigma_URE^2) plus the nominal variance at elevation `el_rad`.
pub fn variances_m2<T: Real>(el_rad: T, sigma_ura_m: T, sigma_ure_m: T) -> (T, T) {
    let v = nominal_variance_m2(el_rad);
    (sigma_ura_m * sigma_ura_m + v, sigma_ure_m * sigma_ure_m + v)
}

/// The Galileo E1/E5a dual-frequency airborne sigma (multipath and noise
/// of the iono-free combination, m) at 5, 10, ..., 90 degrees of
/// elevation: the table of the ARAIM tool cross-check scenario
/// (Stanford, "ToolCrossCheckScenarioDefinitionV1.4a", 2011) that MAAST's
/// ARAIM uses for Galileo (`af_cnmp_galileo`, as carried by the ADD v4.2
/// implementation 4datascience/ARAIM-Fault-Detection,
/// `araim_matlab/lib/atmosphere/iono_gal.m`; the same values in the
/// appendix example of Blanch et al., "Advanced RAIM user algorithm
/// description", ION GNSS 2012). Already the iono-free sigma: no
/// [`iono_free_factor_sq`] applies.
pub const GALILEO_E1E5A_SIGMA_M: [f64; 18] = [
    0.4529, 0.3553, 0.3063, 0.2638, 0.2593, 0.2555, 0.2504, 0.2438, 0.2396, 0.2359, 0.2339, 0.2302,
    0.2295, 0.2278, 0.2297, 0.2310, 0.2274, 0.2277,
];

/// The Galileo E1/E5a airborne sigma (m) at `el_rad`: the table
/// [`GALILEO_E1E5A_SIGMA_M`] interpolated linearly in degrees (as MAAST
/// does); below 5 degrees the 5-10 degree segment continued (the table
/// stops at 5; the continuation grows as the elevation falls, 0.5505 m at
/// 0), above 90 the 90-degree value. NaN gives NaN.
pub fn galileo_e1e5a_sigma_m(el_rad: f64) -> f64 {
    let t = &GALILEO_E1E5A_SIGMA_M;
    let x = el_rad / DEG_RAD / 5.0 - 1.0; // 0 at 5 deg, 17 at 90 deg
    if x.is_nan() {
        return f64::NAN;
    }
    let last = (t.len() - 1) as f64;
    if x >= last {
        return t.last().copied().unwrap_or(f64::NAN);
    }
    // x < 17: the segment index is in 0..=16 (0 below 5 degrees).
    let i = if x <= 0.0 { 0 } else { x as usize };
    match (t.get(i), t.get(i + 1)) {
        (Some(&a), Some(&b)) => a + (x - i as f64) * (b - a),
        _ => f64::NAN,
    }
}

/// The nominal variance (m^2) of a Galileo E1/E5a satellite at `el_rad`:
/// sigma_tropo^2 (DO-229, as for GPS) + [`galileo_e1e5a_sigma_m`]^2.
pub fn galileo_e1e5a_variance_m2(el_rad: f64) -> f64 {
    let tropo = tropo_sigma_m(el_rad.sin_m());
    let air = galileo_e1e5a_sigma_m(el_rad);
    tropo * tropo + air * air
}

/// One satellite's nominal curves: how its elevation-dependent variance
/// (the part of C_int and C_acc besides the signal in space) is formed.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Curves {
    /// The square of the noise amplification of the satellite's iono-free
    /// combination, applied to the per-frequency airborne variance: the
    /// ADD's L1/L5, [`iono_free_factor_sq`] (about 2.59^2), by default;
    /// (f_a^4 + f_b^4) / (f_a^2 - f_b^2)^2 for another pair of bands.
    pub airborne_factor_sq: f64,
    /// A residual ionosphere for single-frequency ranging: its vertical
    /// sigma (m), times [`iono_obliquity`]; 0 for iono-free ranging.
    pub iono_vertical_m: f64,
}

impl Default for Curves {
    /// The ADD's model: L1/L5 iono-free, no ionospheric term.
    fn default() -> Self {
        Curves {
            airborne_factor_sq: iono_free_factor_sq(),
            iono_vertical_m: 0.0,
        }
    }
}

impl Curves {
    /// The nominal variance (m^2) at `el_rad`:
    /// sigma_tropo^2 + airborne_factor_sq (sigma_mp^2 + sigma_noise^2)
    /// + (iono_vertical_m F_pp)^2, in f64.
    pub fn variance_m2(&self, el_rad: f64) -> f64 {
        let tropo = tropo_sigma_m(el_rad.sin_m());
        let v = tropo * tropo + self.airborne_factor_sq * airborne_variance_m2(el_rad);
        if self.iono_vertical_m == 0.0 {
            return v;
        }
        let iono = self.iono_vertical_m * iono_obliquity(el_rad);
        v + iono * iono
    }
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

    /// The Galileo E1/E5a table (its source in the constant's doc): the
    /// published values at the nodes, linear between them, the first
    /// segment continued below 5 degrees, flat above 90; and it is below
    /// the GPS L1/L5 curve the core uses for Galileo by default (at 5
    /// degrees 0.4529 m against 1.49 m, at 90 degrees 0.2277 m against
    /// 0.514 m).
    #[test]
    fn galileo_e1e5a_table() {
        let d = core::f64::consts::PI / 180.0;
        for (el, want) in [
            (5.0, 0.4529),
            (30.0, 0.2555),
            (60.0, 0.2302),
            (70.0, 0.2278),
            (90.0, 0.2277),
        ] {
            assert!((galileo_e1e5a_sigma_m(el * d) - want).abs() < 1e-12, "{el}");
        }
        assert!((galileo_e1e5a_sigma_m(7.5 * d) - (0.4529 + 0.3553) / 2.0).abs() < 1e-12);
        assert!((galileo_e1e5a_sigma_m(0.0) - 0.5505).abs() < 1e-12);
        assert!((galileo_e1e5a_sigma_m(95.0 * d) - 0.2277).abs() < 1e-12);
        assert!(galileo_e1e5a_sigma_m(f64::NAN).is_nan());
        let el = 30.0 * d;
        let tropo = 0.12 * 1.001 / (0.002_001 + 0.25f64).sqrt();
        assert!((galileo_e1e5a_variance_m2(el) - (tropo * tropo + 0.2555 * 0.2555)).abs() < 1e-12);
        for el_deg in [5.0, 90.0] {
            let gps = (iono_free_factor_sq() * airborne_variance_m2(el_deg * d)).sqrt();
            assert!(galileo_e1e5a_sigma_m(el_deg * d) < gps / 2.0);
        }
    }

    #[test]
    fn iono_free_factor_is_about_2_59() {
        assert!((iono_free_factor_sq().sqrt() - 2.5883).abs() < 1e-3);
    }

    /// The default curves are the ADD's model itself, bit for bit, at
    /// every elevation from 2 to 90 degrees; the iono term adds
    /// (s F_pp)^2, F_pp from 1 at the zenith to about 3 at the horizon.
    #[test]
    fn curves_are_the_add_model_plus_the_iono_term() {
        for k in 0..=88 {
            let el = (2.0 + k as f64).to_radians();
            let add = Curves::default().variance_m2(el);
            assert_eq!(add.to_bits(), nominal_variance_m2(el).to_bits(), "{k}");
            let iono = Curves {
                iono_vertical_m: 0.5,
                ..Curves::default()
            };
            let f = iono_obliquity(el);
            assert!((iono.variance_m2(el) - add - 0.25 * f * f).abs() <= 1e-12 * add);
        }
        assert!((iono_obliquity(core::f64::consts::FRAC_PI_2) - 1.0).abs() < 1e-12);
        // 1 / sqrt(1 - (6378.1363 / 6728.1363)^2) = 3.1413.
        assert!((iono_obliquity(0.0f64) - 3.1413).abs() < 1e-3);
    }

    /// The snapshot sigma model's DO-229 terms alone (no URA, iono or
    /// noise) against the curves written out.
    #[test]
    fn matches_do229_terms_at_zenith_and_low_elevation() {
        let m = crate::sigma::SigmaModel {
            ura_m: 0.0,
            iono_vertical_m: 0.0,
            noise_m: 0.0,
            ..crate::sigma::SigmaModel::default()
        };
        // Zenith: tropo 0.12*1.001/sqrt(1.002001) = 0.120000 m; multipath
        // 0.13 + 0.53 e^-9 = 0.130066 m.
        let z = m.sigma_m(core::f64::consts::FRAC_PI_2);
        let expect = libm::sqrt(0.12f64.powi(2) + (0.13 + 0.53 * (-9.0f64).exp()).powi(2));
        assert!((z - expect).abs() < 1e-4, "{z} vs {expect}");
        // 5 deg: tropo 0.12*1.001/sqrt(0.002001+sin^2 5deg) = 1.2498 m,
        // multipath 0.13+0.53e^-0.5 = 0.4515 m.
        let low = m.sigma_m(5.0f64.to_radians());
        let t = 0.12 * 1.001 / (0.002001 + 5.0f64.to_radians().sin().powi(2)).sqrt();
        let mp = 0.13 + 0.53 * (-0.5f64).exp();
        assert!((low - (t * t + mp * mp).sqrt()).abs() < 1e-12);
        assert!(low > z);
    }
}
