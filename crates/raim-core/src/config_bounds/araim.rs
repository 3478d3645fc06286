//! Operational bounds of the ARAIM configuration and integrity support
//! message (SPEC §9.1; docs/PROTOCOL.md "Configuration bounds").
//!
//! `AraimConfig::validate`, `Ism::validate` and `AraimSat::validate` check
//! every field against these ranges (NaN and infinities are refused, each
//! bound is inclusive); a rejection is `AraimError::OutOfRange` with the
//! field, the index (satellite or constellation, 0 for the
//! configuration), the value and the bound. The ADD's LPV-200 values
//! (SPEC §9.1) are inside every range.
//!
//! # The property the bounds guarantee
//!
//! No accepted configuration and ISM lets a single-satellite or a
//! constellation fault mode drop out of the mode list. Proof: the
//! enumeration (`araim::modes::enumerate`) takes N_fault,max = r as the
//! smallest r with P(more than r events) <= P_THRES, and lists every
//! combination of 1..=r events. Every single event (one satellite, or one
//! constellation) is therefore listed exactly when r >= 1, i.e. when
//! P(at least one event) > P_THRES. The tail is computed as
//! sum_i p_i prod_{j<i} (1 - p_j) from 0 by adding non-negative terms, and
//! its first term is the first satellite's P_sat exactly, so the computed
//! P(at least one event) >= that P_sat >= `P_SAT.min` (rounding is
//! monotone). Hence `P_THRES.max < P_SAT.min` (checked at compile time
//! below) gives r >= 1 for every sky with one satellite or more, whatever
//! P_const. A listed mode is then either monitored (solved and tested, its
//! prior in the PL sum) or unmonitorable (its prior added to P_unmon,
//! which makes the epoch `Unmonitored` once above P_THRES): it never
//! leaves the integrity budget. When the list does not fit the capacity,
//! or more than `MAX_EVENTS` events would be needed, the epoch is
//! unavailable with a typed cause (`ModeCapacity`, `TooManyEvents`),
//! never truncated. Tests: `config_bounds::araim::tests` (proptest over
//! random skies of 5-32 satellites and random accepted ISMs, corners
//! included).

use super::{Bound, SIGMA_M};
use crate::araim::AraimError;

impl Bound {
    /// `check` for the ARAIM inputs: `AraimError::OutOfRange` carrying
    /// `index` (satellite, constellation, or 0 for the configuration).
    pub fn check_araim(&self, index: usize, value: f64) -> Result<(), AraimError> {
        if self.contains(value) {
            Ok(())
        } else {
            Err(AraimError::OutOfRange {
                field: self.field,
                index,
                value,
                min: self.min,
                max: self.max,
            })
        }
    }

    /// [`Bound::check_araim`] on a value derived and stored in the
    /// engine's precision `T` (C_int, C_acc: sums of the ISM's and the
    /// sigma model's squares, formed in f64 and rounded to `T` once), held
    /// against the bound rounded to `T` the same way (issue 35). Rounding
    /// to nearest is monotone, so a value whose f64 origin is within the
    /// bound stays within the rounded bound: the check refuses only what
    /// the f64 check refuses. In f64 the f32 image of 0.2² + 0.3² =
    /// 0.13 m² is 0.1299999952 m², below 0.13 (every ARAIM epoch at those
    /// accepted floors was refused). The error carries the value and the
    /// bound as the check saw them (rounded to `T`).
    pub fn check_araim_in<T: crate::real::Real>(
        &self,
        index: usize,
        value: T,
    ) -> Result<(), AraimError> {
        let (min, max) = (T::of(self.min), T::of(self.max));
        if value >= min && value <= max {
            Ok(())
        } else {
            Err(AraimError::OutOfRange {
                field: self.field,
                index,
                value: value.to_f64(),
                min: min.to_f64(),
                max: max.to_f64(),
            })
        }
    }
}

/// Vertical integrity budget per approach. ADD LPV-200: 9.8e-8. Ceiling
/// 2e-7: ICAO Annex 10's integrity risk for APV and CAT I approaches (the
/// whole budget, the largest any operation allocates); near 1 the PL
/// equation's right-hand side allows almost any error. Floor 1e-9: a
/// smaller budget only inflates the PLs (unavailability, never a miss).
pub const PHMI_VERT: Bound = Bound {
    field: "phmi_vert",
    min: 1e-9,
    max: 2e-7,
};
/// Horizontal integrity budget. ADD LPV-200: 2e-9; range as `PHMI_VERT`
/// (horizontal-only operations allocate up to 1e-7 per hour).
pub const PHMI_HOR: Bound = Bound {
    field: "phmi_hor",
    min: 1e-9,
    max: 2e-7,
};
/// Vertical false-alert (continuity) budget. ADD LPV-200: 3.9e-6. Floor
/// 1e-9: below it K_fa grows without an operational reason (at 1e-300 it
/// is ~37 sigma and every threshold swallows the fault it should detect);
/// ceiling 1e-4: ICAO's loosest continuity allocation (en route, per hour).
pub const PFA_VERT: Bound = Bound {
    field: "pfa_vert",
    min: 1e-9,
    max: 1e-4,
};
/// Horizontal false-alert budget. ADD LPV-200: 9e-8; range as `PFA_VERT`.
pub const PFA_HOR: Bound = Bound {
    field: "pfa_hor",
    min: 1e-9,
    max: 1e-4,
};
/// Threshold on the unmonitored probability. ADD: 8e-8. Ceiling 1e-7,
/// strictly below `P_SAT.min`: this is what keeps every single-event mode
/// in the list (module doc). It must also stay below PHMI_VERT + PHMI_HOR
/// (the adjusted PHMI is then positive; `AraimConfig::validate`). Floor
/// 1e-10: smaller only enumerates more modes (capacity unavailability).
pub const P_THRES: Bound = Bound {
    field: "p_thres",
    min: 1e-10,
    max: 1e-7,
};
/// Prior at or above which a mode enters the EMT. ADD: 1e-5 (= P_sat,
/// so every single-satellite mode counts). Ceiling: the ADD's value (a
/// larger one drops the single-satellite modes of an ADD ISM from the
/// EMT, which then passes its limit by construction); floor 1e-8 (smaller
/// only adds multi-event modes: a larger, more conservative EMT).
pub const P_EMT: Bound = Bound {
    field: "p_emt",
    min: 1e-8,
    max: 1e-5,
};
/// Vertical alert limit, m: from CAT I's 10 m to LPV / APV-I's 50 m
/// (LPV-200: 35 m), as the snapshot's `VAL_M`.
pub const VAL_M: Bound = Bound {
    field: "val_m",
    min: super::VAL_M.min,
    max: super::VAL_M.max,
};
/// Horizontal alert limit, m: LPV-200 / APV-I's 40 m to oceanic en
/// route's 4 nm, as the snapshot's `HAL_M`.
pub const HAL_M: Bound = Bound {
    field: "hal_m",
    min: super::HAL_M.min,
    max: super::HAL_M.max,
};
/// Bracket width of the ADD's PL bisection, m. ADD: 0.05 m. The bracket
/// output is the upper end (never below the root), so a wide bracket only
/// inflates the PL; 10 m is the previous ceiling, 1e-3 m keeps the
/// bisection's iteration count small.
pub const TOL_PL_M: Bound = Bound {
    field: "tol_pl_m",
    min: 1e-3,
    max: 10.0,
};
/// Availability limit on the EMT, m. ADD LPV-200: 15 m. Ceiling: the
/// largest VAL (and `AraimConfig::validate` also requires it <= val_m: an
/// EMT beyond the VAL is no limit); floor 1 m (smaller only makes the
/// service unavailable).
pub const EMT_MAX_M: Bound = Bound {
    field: "emt_max_m",
    min: 1.0,
    max: 50.0,
};
/// Availability limit on sigma_v,acc, m. ADD LPV-200: 1.87 m. Ceiling
/// 10.2 m: APV-I's 20 m 95 % vertical accuracy over 1.96; floor 0.1 m.
pub const SIGMA_ACC_MAX_M: Bound = Bound {
    field: "sigma_acc_max_m",
    min: 0.1,
    max: 10.2,
};

/// Prior probability of a satellite fault. ADD: 1e-5 (the GPS and
/// Galileo commitments). Floor 1e-6, a decade below the commitment and
/// above `P_THRES.max` (the property of the module doc); ceiling 1e-3
/// (larger priors need more simultaneous events than the engines hold:
/// capacity unavailability).
pub const P_SAT: Bound = Bound {
    field: "p_sat",
    min: 1e-6,
    max: 1e-3,
};
/// Prior probability of a constellation fault. ADD: 1e-4 (Galileo) and
/// 1e-8 (GPS), the range's ends up to 1e-3. A constellation event is a
/// single event, listed whatever its prior (module doc).
pub const P_CONST: Bound = Bound {
    field: "p_const",
    min: 1e-8,
    max: 1e-3,
};
/// Maximum nominal bias, m. ADD: 0.5-0.75 m. 0 is a valid ISM value (no
/// bias beyond the Gaussian overbound); 10 m is far beyond any proposed
/// value (a larger bias only inflates the PLs).
pub const B_NOM_M: Bound = Bound {
    field: "b_nom_m",
    min: 0.0,
    max: 10.0,
};
/// sigma_URA, the integrity clock-and-ephemeris sigma, m. ADD: 0.75 m.
/// Floor 0.3 m and ceiling 100 m as the snapshot's `URA_M`.
pub const SIGMA_URA_M: Bound = Bound {
    field: "sigma_ura_m",
    min: super::URA_M.min,
    max: super::URA_M.max,
};
/// sigma_URE, the accuracy sigma, m. ADD: 0.5 m (2/3 of sigma_URA).
/// Floor 0.2 m (2/3 of the URA floor); it must not exceed sigma_URA
/// (`check_ism_entry`: the accuracy model is the less conservative one).
pub const SIGMA_URE_M: Bound = Bound {
    field: "sigma_ure_m",
    min: 0.2,
    max: super::URA_M.max,
};
/// C_int,ii, m^2: sigma_URA^2 plus the tropo and airborne variance, which
/// is the ADD model's (>= 0.28 m^2 at zenith) or a host sigma within
/// `SIGMA_M`; so from the floors' squares to the ceilings' squares.
pub const C_INT_M2: Bound = Bound {
    field: "c_int_m2",
    min: SIGMA_URA_M.min * SIGMA_URA_M.min + SIGMA_M.min * SIGMA_M.min,
    max: SIGMA_URA_M.max * SIGMA_URA_M.max + SIGMA_M.max * SIGMA_M.max,
};
/// C_acc,ii, m^2: as `C_INT_M2` with sigma_URE; it must not exceed C_int.
pub const C_ACC_M2: Bound = Bound {
    field: "c_acc_m2",
    min: SIGMA_URE_M.min * SIGMA_URE_M.min + SIGMA_M.min * SIGMA_M.min,
    max: C_INT_M2.max,
};
/// Norm of a geometry row's ENU part (a unit line of sight): the same
/// tolerance as the snapshot's linearised input (`los_enu_norm`).
pub const G_NORM: Bound = Bound {
    field: "g_norm",
    min: core::f64::consts::FRAC_1_SQRT_2,
    max: 1.224_744_871_391_589,
};

// The property of the module doc: every single event is listed.
const _: () = assert!(P_THRES.max < P_SAT.min);

/// One ISM entry on its own: sigma_URA, sigma_URE (<= sigma_URA), b_nom
/// and P_sat against their bounds (finite first). The protocol's ISM frame
/// is checked with this when it arrives.
pub fn check_ism_entry(
    index: usize,
    sigma_ura_m: f64,
    sigma_ure_m: f64,
    b_nom_m: f64,
    p_sat: f64,
) -> Result<(), AraimError> {
    for (field, v) in [
        ("sigma_ura_m", sigma_ura_m),
        ("sigma_ure_m", sigma_ure_m),
        ("b_nom_m", b_nom_m),
        ("p_sat", p_sat),
    ] {
        crate::araim::ism::finite(field, index, v)?;
    }
    SIGMA_URA_M.check_araim(index, sigma_ura_m)?;
    SIGMA_URE_M.check_araim(index, sigma_ure_m)?;
    if sigma_ure_m > sigma_ura_m {
        return Err(AraimError::OutOfRange {
            field: "sigma_ure_m",
            index,
            value: sigma_ure_m,
            min: SIGMA_URE_M.min,
            max: sigma_ura_m,
        });
    }
    B_NOM_M.check_araim(index, b_nom_m)?;
    P_SAT.check_araim(index, p_sat)
}

#[cfg(test)]
mod tests;
