//! Elevation-dependent ranging sigma (SPEC §1), DO-229 style:
//! sigma^2 = sigma_ura^2 + sigma_iono(el)^2 + sigma_tropo(el)^2 + sigma_user(el)^2.

use crate::araim::error_model::{iono_obliquity, multipath_sigma_m, tropo_sigma_m};
use crate::real::Real;

/// Parameters of the elevation model. Defaults are DO-229D's airborne
/// accuracy designator A receiver, a 0.75 m URA (ARAIM ADD baseline), and a
/// single-frequency Klobuchar residual of 2.5 m vertical (documented in
/// docs/CORE.md; set to 0 for iono-free measurements).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SigmaModel {
    /// Signal-in-space (URA/URE) sigma, m.
    pub ura_m: f64,
    /// Residual ionosphere sigma at zenith, m (scaled by the obliquity factor).
    pub iono_vertical_m: f64,
    /// Receiver noise sigma, m (DO-229D AAD-A: 0.36 m; AAD-B: 0.15 m).
    pub noise_m: f64,
    /// Lowest elevation used in the model (guards the obliquity terms), rad.
    pub min_elevation_rad: f64,
}

impl Default for SigmaModel {
    fn default() -> Self {
        SigmaModel {
            ura_m: 0.75,
            iono_vertical_m: 2.5,
            noise_m: 0.36,
            min_elevation_rad: 2.0 * core::f64::consts::PI / 180.0,
        }
    }
}

impl SigmaModel {
    /// One-sigma ranging error at elevation `el_rad`, m.
    pub fn sigma_m(&self, el_rad: f64) -> f64 {
        self.sigma::<f64>(el_rad)
    }

    /// [`Self::sigma_m`] in the precision `T` (the same operations; the
    /// engines evaluate it in their statistics precision, docs/CORE.md
    /// "Precision": a sigma needs no more than f32's 6e-8 relative).
    pub fn sigma<T: Real>(&self, el_rad: T) -> T {
        let min_el = T::of(self.min_elevation_rad);
        let el = if el_rad > min_el { el_rad } else { min_el };
        let tropo = tropo_sigma_m(el.sin_m());
        let el_deg = el * T::of(180.0) / T::of(core::f64::consts::PI);
        let multipath = multipath_sigma_m(el_deg);
        let iono = T::of(self.iono_vertical_m) * iono_obliquity(el);
        let (ura, noise) = (T::of(self.ura_m), T::of(self.noise_m));
        (ura * ura + iono * iono + tropo * tropo + multipath * multipath + noise * noise).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bound behind `solve::RELINEARISE_M`: an elevation error of
    /// `RELINEARISE_EL_RAD` moves the sigma by less than 3e-4 relative, at
    /// every elevation from the floor to the zenith, for the default model
    /// and for the terms alone that vary fastest (tropo + multipath).
    #[test]
    fn sigma_model_is_flat_within_the_relinearisation_bound() {
        const SIGMA_REL_TOL: f64 = 3e-4;
        let d = crate::solve::RELINEARISE_EL_RAD;
        assert!(d < 2.2e-5, "{d}");
        let steep = SigmaModel {
            ura_m: 0.0,
            iono_vertical_m: 0.0,
            noise_m: 0.0,
            ..SigmaModel::default()
        };
        let replay = SigmaModel {
            ura_m: 0.3,
            iono_vertical_m: 0.5,
            noise_m: 0.2,
            ..SigmaModel::default()
        };
        let mut worst = 0.0f64;
        for m in [SigmaModel::default(), steep, replay] {
            for k in 0..=9000 {
                let el = (k as f64 * 0.01).to_radians();
                for e2 in [el - d, el + d] {
                    let rel = (m.sigma_m(e2) - m.sigma_m(el)).abs() / m.sigma_m(el);
                    worst = worst.max(rel);
                }
            }
        }
        assert!(worst < SIGMA_REL_TOL, "{worst}");
        assert!(worst > 1e-5, "the bound is not vacuous: {worst}");
    }
}
