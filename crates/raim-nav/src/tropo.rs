//! Saastamoinen tropospheric delay (Saastamoinen 1972) with a standard
//! atmosphere: pressure and temperature from the height (ICAO), relative
//! humidity 70 %, mapped by 1/cos(zenith angle). This is the classic
//! single-point-positioning model (the one the RTKLIB facts in the shared
//! data README were measured with).

/// Relative humidity assumed by the standard atmosphere.
pub const RELATIVE_HUMIDITY: f64 = 0.7;

/// Slant tropospheric delay, m, for a receiver at latitude `lat_rad` and
/// ellipsoidal height `height_m`, satellite elevation `el_rad`. Returns 0
/// outside the model's domain (below the horizon, height < -100 m or
/// above 10 km), as the delay is then unmodelled rather than invented.
pub fn saastamoinen_m(lat_rad: f64, height_m: f64, el_rad: f64) -> f64 {
    SaastamoinenSite::at(lat_rad, height_m).slant_m(el_rad)
}

/// The receiver's part of [`saastamoinen_m`]: its zenith hydrostatic and
/// wet delays, which depend on the latitude and height alone, computed
/// once for all the satellites of an epoch (a power and an exponential in
/// soft-float f64 on the M4); [`Self::slant_m`] maps them to an elevation
/// with the bits of [`saastamoinen_m`] (the same operations in the same
/// order).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SaastamoinenSite {
    /// (hydrostatic, wet) zenith delays, m; None outside the model's
    /// height domain.
    zenith_m: Option<(f64, f64)>,
}

impl SaastamoinenSite {
    /// The site at latitude `lat_rad` and ellipsoidal height `height_m`.
    pub fn at(lat_rad: f64, height_m: f64) -> Self {
        if !(-100.0..=1e4).contains(&height_m) {
            return SaastamoinenSite { zenith_m: None };
        }
        let h = height_m.max(0.0);
        let pressure_hpa = 1013.25 * crate::m::pow(1.0 - 2.2557e-5 * h, 5.2568);
        let temp_k = 15.0 - 6.5e-3 * h + 273.16;
        let e_hpa =
            6.108 * RELATIVE_HUMIDITY * crate::m::exp((17.15 * temp_k - 4684.0) / (temp_k - 38.45));
        let hydro = 0.002_276_8 * pressure_hpa
            / (1.0 - 0.002_66 * crate::m::cos(2.0 * lat_rad) - 0.000_28 * h / 1e3);
        let wet = 0.002_277 * (1255.0 / temp_k + 0.05) * e_hpa;
        SaastamoinenSite {
            zenith_m: Some((hydro, wet)),
        }
    }

    /// The slant delay at elevation `el_rad`, m: 1/cos(zenith angle)
    /// mapping; 0 below the horizon or outside the height domain.
    pub fn slant_m(&self, el_rad: f64) -> f64 {
        let Some((hydro, wet)) = self.zenith_m else {
            return 0.0;
        };
        if el_rad <= 0.0 {
            return 0.0;
        }
        let cos_z = crate::m::sin(el_rad); // cos(pi/2 - el)
        hydro / cos_z + wet / cos_z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Zenith hydrostatic delay at sea level, latitude 45 deg (cos 2 lat =
    /// 0): 0.0022768 x 1013.25 hPa = 2.3070 m (Saastamoinen's closed form);
    /// the wet part at 15 C, 70 % humidity (e = 12.0 hPa) is 0.12 m.
    #[test]
    fn zenith_sea_level_closed_form() {
        let d = saastamoinen_m(45f64.to_radians(), 0.0, std::f64::consts::FRAC_PI_2);
        let temp_k: f64 = 288.16;
        let e = 6.108 * 0.7 * ((17.15 * temp_k - 4684.0) / (temp_k - 38.45)).exp();
        let wet = 0.002277 * (1255.0 / temp_k + 0.05) * e;
        assert!((d - (0.0022768 * 1013.25 + wet)).abs() < 1e-9);
        assert!((2.40..2.50).contains(&d), "{d}");
        assert!((e - 12.0).abs() < 0.05, "{e}");
    }

    /// The site's zenith delays mapped to an elevation are the one-call
    /// formula's bits: Saastamoinen's delay written out here in one
    /// expression (the form before the split), against
    /// `SaastamoinenSite::at(..).slant_m(el)` over latitudes, heights
    /// across the domain's edges and elevations from below the horizon to
    /// the zenith.
    ///
    /// Verifies: RX-FORM-COST
    #[test]
    fn the_site_split_gives_the_one_call_bits() {
        let whole = |lat_rad: f64, height_m: f64, el_rad: f64| -> f64 {
            if el_rad <= 0.0 || !(-100.0..=1e4).contains(&height_m) {
                return 0.0;
            }
            let h = height_m.max(0.0);
            let p = 1013.25 * libm::pow(1.0 - 2.2557e-5 * h, 5.2568);
            let t = 15.0 - 6.5e-3 * h + 273.16;
            let e = 6.108 * RELATIVE_HUMIDITY * libm::exp((17.15 * t - 4684.0) / (t - 38.45));
            let cos_z = libm::sin(el_rad);
            0.002_276_8 * p
                / (1.0 - 0.002_66 * libm::cos(2.0 * lat_rad) - 0.000_28 * h / 1e3)
                / cos_z
                + 0.002_277 * (1255.0 / t + 0.05) * e / cos_z
        };
        for lat_deg in [-89.0f64, -45.0, -3.3, 0.0, 12.5, 55.5, 89.9] {
            for height_m in [-150.0, -100.0, -20.0, 0.0, 17.3, 850.0, 4321.0, 1e4, 1.2e4] {
                for el_deg in [-5.0f64, 0.0, 0.5, 5.0, 10.0, 33.3, 60.0, 89.0, 90.0] {
                    let (lat, el) = (lat_deg.to_radians(), el_deg.to_radians());
                    let site = SaastamoinenSite::at(lat, height_m);
                    assert_eq!(
                        site.slant_m(el).to_bits(),
                        whole(lat, height_m, el).to_bits(),
                        "{lat_deg} {height_m} {el_deg}"
                    );
                    assert_eq!(saastamoinen_m(lat, height_m, el), site.slant_m(el));
                }
            }
        }
    }

    /// 1/sin(el) mapping: at 30 deg the delay doubles; below the horizon 0.
    #[test]
    fn mapping_and_domain() {
        let z = saastamoinen_m(0.6, 100.0, std::f64::consts::FRAC_PI_2);
        let d30 = saastamoinen_m(0.6, 100.0, 30f64.to_radians());
        assert!((d30 - 2.0 * z).abs() < 1e-12);
        assert_eq!(saastamoinen_m(0.6, 100.0, -0.01), 0.0);
        assert_eq!(saastamoinen_m(0.6, 20_000.0, 0.5), 0.0);
        // Higher is drier: 1000 m loses ~12 % of the pressure.
        assert!(saastamoinen_m(0.6, 1000.0, 1.0) < 0.9 * saastamoinen_m(0.6, 0.0, 1.0));
    }
}
