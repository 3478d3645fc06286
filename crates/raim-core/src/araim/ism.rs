//! The integrity support message (ISM) and the ARAIM configuration
//! (SPEC §9.1), with their range checks.
//!
//! Per satellite: the geometry row, C_int and C_acc (from sigma_URA,
//! sigma_URE and the elevation model of `error_model`, or given directly),
//! b_nom and P_sat. Per constellation: P_const. Configuration: the LPV-200
//! integrity and continuity allocation of the ADD as defaults.
//! Probabilities stay `f64` (they are thresholds in the precision policy of
//! `real.rs`); the geometry and the variances are `T`.

use super::error::AraimError;
use crate::config_bounds::araim as b;
use crate::measurement::{SatId, System, MAX_SYSTEMS};
use crate::real::Real;

/// One satellite of an ARAIM epoch in the linearised form: the first three
/// columns of its geometry row (ENU, with the sign convention of the ADD:
/// the row is minus the unit line of sight), its error model and its ISM
/// entries. The clock column is implied by `id.system`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AraimSat<T> {
    /// The satellite.
    pub id: SatId,
    /// G row, east/north/up components (dimensionless).
    pub g_enu: [T; 3],
    /// Integrity variance C_int,ii (m^2): sigma_URA^2 + tropo^2 + user^2.
    pub c_int_m2: T,
    /// Accuracy variance C_acc,ii (m^2): sigma_URE^2 + tropo^2 + user^2.
    pub c_acc_m2: T,
    /// Maximum nominal bias b_nom,i (m).
    pub b_nom_m: T,
    /// Prior probability of a satellite fault, P_sat,i, in (0, 1).
    pub p_sat: f64,
    /// Measured minus predicted range (m); zero when only the protection
    /// levels are wanted.
    pub residual_m: T,
}

impl<T: Real> AraimSat<T> {
    /// All zero (the derived `Default`), for `const fn` constructors.
    pub const ZERO: Self = AraimSat {
        id: SatId::DEFAULT,
        g_enu: [T::ZERO; 3],
        c_int_m2: T::ZERO,
        c_acc_m2: T::ZERO,
        b_nom_m: T::ZERO,
        p_sat: 0.0,
        residual_m: T::ZERO,
    };
    /// The geometry row for an azimuth and elevation (radians), with the
    /// ADD's sign: `-[cos el sin az, cos el cos az, sin el]`.
    pub fn g_from_az_el(az_rad: T, el_rad: T) -> [T; 3] {
        let c = el_rad.cos_m();
        [
            -(c * az_rad.sin_m()),
            -(c * az_rad.cos_m()),
            -el_rad.sin_m(),
        ]
    }

    /// Range-checks every field against its operational bound
    /// (`config_bounds::araim`, docs/PROTOCOL.md "Configuration bounds"):
    /// finite first, then the unit geometry row, C_int and C_acc (C_acc <=
    /// C_int; both in the precision `T` they are held in, against their
    /// bounds rounded to `T`: `Bound::check_araim_in`), b_nom and P_sat. `index` is the satellite's position in the
    /// epoch, reported in the error.
    pub fn validate(&self, index: usize) -> Result<(), AraimError> {
        for (field, v) in [
            ("g_e", self.g_enu[0]),
            ("g_n", self.g_enu[1]),
            ("g_u", self.g_enu[2]),
            ("c_int_m2", self.c_int_m2),
            ("c_acc_m2", self.c_acc_m2),
            ("b_nom_m", self.b_nom_m),
            ("residual_m", self.residual_m),
        ] {
            finite(field, index, v.to_f64())?;
        }
        finite("p_sat", index, self.p_sat)?;
        let [e, n, u] = self.g_enu.map(|v| v.to_f64());
        b::G_NORM.check_araim(index, libm::sqrt(e * e + n * n + u * u))?;
        // In the precision they were formed in (`check_araim_in`).
        b::C_INT_M2.check_araim_in(index, self.c_int_m2)?;
        b::C_ACC_M2.check_araim_in(index, self.c_acc_m2)?;
        let (c_int, c_acc) = (self.c_int_m2.to_f64(), self.c_acc_m2.to_f64());
        if c_acc > c_int {
            return Err(AraimError::OutOfRange {
                field: "c_acc_m2",
                index,
                value: c_acc,
                min: b::C_ACC_M2.min,
                max: c_int,
            });
        }
        b::B_NOM_M.check_araim(index, self.b_nom_m.to_f64())?;
        b::P_SAT.check_araim(index, self.p_sat)
    }
}

/// The per-constellation part of the ISM: `p_const[System::index()]` is
/// `Some(P_const)` for each constellation in use and `None` otherwise.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Ism {
    /// P_const per constellation (`System::index`), `None` when not in use.
    pub p_const: [Option<f64>; MAX_SYSTEMS],
}

impl Ism {
    /// An ISM with the same P_const for the listed constellations.
    pub fn with(systems: &[System], p_const: f64) -> Self {
        let mut ism = Ism::default();
        for s in systems {
            if let Some(slot) = ism.p_const.get_mut(s.index()) {
                *slot = Some(p_const);
            }
        }
        ism
    }

    /// Range-checks every present P_const (finite, within
    /// `config_bounds::araim::P_CONST`).
    pub fn validate(&self) -> Result<(), AraimError> {
        for (j, p) in self.p_const.iter().enumerate() {
            if let Some(p) = *p {
                finite("p_const", j, p)?;
                b::P_CONST.check_araim(j, p)?;
            }
        }
        Ok(())
    }
}

/// Which protection level feeds the availability decision.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlOutput {
    /// The ADD's output: the upper end of the bisection bracket once it is
    /// narrower than TOL_PL (never below the root).
    #[default]
    AddBracket,
    /// The exact root of the PL equation.
    Exact,
}

/// ARAIM configuration: the integrity/continuity allocation and the alert
/// limits. Defaults are the ADD's LPV-200 values (SPEC §9.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AraimConfig {
    /// Vertical integrity budget PHMI_VERT (per approach).
    pub phmi_vert: f64,
    /// Horizontal integrity budget PHMI_HOR.
    pub phmi_hor: f64,
    /// Vertical continuity (false alert) budget P_FA_VERT.
    pub pfa_vert: f64,
    /// Horizontal continuity budget P_FA_HOR.
    pub pfa_hor: f64,
    /// Threshold on the probability of the fault modes left unmonitored.
    pub p_thres: f64,
    /// Modes with a prior at or above this enter the EMT.
    pub p_emt: f64,
    /// Vertical alert limit (m).
    pub val_m: f64,
    /// Horizontal alert limit (m).
    pub hal_m: f64,
    /// Bracket width of the ADD's PL bisection (m).
    pub tol_pl_m: f64,
    /// Availability limit on the effective monitor threshold (m).
    pub emt_max_m: f64,
    /// Availability limit on sigma_v,acc (m).
    pub sigma_acc_max_m: f64,
    /// Which PL the availability decision uses.
    pub pl_output: PlOutput,
}

impl Default for AraimConfig {
    fn default() -> Self {
        Self {
            phmi_vert: 9.8e-8,
            phmi_hor: 2e-9,
            pfa_vert: 3.9e-6,
            pfa_hor: 9e-8,
            p_thres: 8e-8,
            p_emt: 1e-5,
            val_m: 35.0,
            hal_m: 40.0,
            tol_pl_m: 0.05,
            emt_max_m: 15.0,
            sigma_acc_max_m: 1.87,
            pl_output: PlOutput::AddBracket,
        }
    }
}

impl AraimConfig {
    /// Range-checks every field against its operational bound
    /// (`config_bounds::araim`, docs/PROTOCOL.md "Configuration bounds"),
    /// then the cross-field rules: P_THRES below PHMI_VERT + PHMI_HOR (a
    /// positive adjusted PHMI) and the EMT limit at most the VAL.
    pub fn validate(&self) -> Result<(), AraimError> {
        for (bound, v) in [
            (b::PHMI_VERT, self.phmi_vert),
            (b::PHMI_HOR, self.phmi_hor),
            (b::PFA_VERT, self.pfa_vert),
            (b::PFA_HOR, self.pfa_hor),
            (b::P_THRES, self.p_thres),
            (b::P_EMT, self.p_emt),
            (b::VAL_M, self.val_m),
            (b::HAL_M, self.hal_m),
            (b::TOL_PL_M, self.tol_pl_m),
            (b::EMT_MAX_M, self.emt_max_m),
            (b::SIGMA_ACC_MAX_M, self.sigma_acc_max_m),
        ] {
            finite(bound.field, 0, v)?;
            bound.check_araim(0, v)?;
        }
        // The unmonitored budget must leave a positive adjusted PHMI.
        if !(self.p_thres < self.phmi_vert + self.phmi_hor) {
            return Err(AraimError::OutOfRange {
                field: "p_thres",
                index: 0,
                value: self.p_thres,
                min: b::P_THRES.min,
                max: self.phmi_vert + self.phmi_hor,
            });
        }
        if self.emt_max_m > self.val_m {
            return Err(AraimError::OutOfRange {
                field: "emt_max_m",
                index: 0,
                value: self.emt_max_m,
                min: b::EMT_MAX_M.min,
                max: self.val_m,
            });
        }
        Ok(())
    }
}

pub(crate) fn finite(field: &'static str, index: usize, v: f64) -> Result<(), AraimError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(AraimError::NotFinite {
            field,
            index,
            value: v,
        })
    }
}

#[cfg(test)]
#[path = "ism_cov_tests.rs"]
mod cov_tests;
