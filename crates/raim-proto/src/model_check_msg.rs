//! The run-time model check's settings on the wire (docs/MODEL_CHECK.md,
//! issue 35): the allocation P_h, the spacing and the window of
//! `raim_core::consistency::ModelCheck`, a part of the unit configuration
//! like the snapshot, ARAIM and PF parts: taken by
//! `Command::ModelCheck` (authenticated on a keyed unit,
//! `auth::Change::ModelCheck`), provisioned in `UnitConfig::model_check`,
//! covered by the fingerprint and the lock, and checked by the same
//! [`WireModelCheckConfig::check`] at run time, at boot and by
//! `raim provision`.
//!
//! The defaults are the core's (`ModelCheckConfig::DEFAULT`: 1,800 s,
//! 8 samples, 1e-6 per hour; docs/MODEL_CHECK.md "Defaults and where they
//! come from"), so that a configuration that does not set them runs the
//! check as the unit did before the settings existed.

use raim_core::consistency::{ModelCheckConfig, ModelCheckError};
use serde::{Deserialize, Serialize};

use crate::error::{field_name, WireError};

/// The largest window the unit holds (the capacity of the server's
/// `ModelCheck<W>`): twice the default, 24 bytes a sample.
pub const MAX_WINDOW: usize = 16;

/// What a `Command::ModelCheck` sets: the core's `ModelCheckConfig`, the
/// window as a `u32` (a `usize` has no fixed width on the wire). A TOML
/// table that omits a field takes its default.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WireModelCheckConfig {
    /// Least time between two samples, s (`SPACING_S`: [1e-3, 86,400]).
    pub spacing_s: f64,
    /// Samples in the window, 1..=[`MAX_WINDOW`].
    pub window: u32,
    /// Allocated probability of a false declaration per hour of
    /// operation (`P_FA_PER_HOUR`: [1e-12, 0.5]).
    pub p_fa_per_hour: f64,
}

impl Default for WireModelCheckConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl WireModelCheckConfig {
    /// The core's defaults.
    pub const DEFAULT: Self = WireModelCheckConfig {
        spacing_s: ModelCheckConfig::DEFAULT.spacing_s,
        window: ModelCheckConfig::DEFAULT.window as u32,
        p_fa_per_hour: ModelCheckConfig::DEFAULT.p_fa_per_hour,
    };

    /// The core's configuration, if every field is within its bounds
    /// (`ModelCheckConfig::validate` at the unit's capacity
    /// [`MAX_WINDOW`]); otherwise the typed error with the offending
    /// value: `NonFinite` or `OutOfRange` naming `spacing_s` or
    /// `p_fa_per_hour`, `OutOfRange` naming `window` (min 1, max the
    /// capacity).
    ///
    /// # Errors
    /// As above.
    pub fn check(&self) -> Result<ModelCheckConfig, WireError> {
        let window_error = || WireError::OutOfRange {
            field: field_name("window"),
            value: f64::from(self.window),
            min: 1.0,
            max: MAX_WINDOW as f64,
        };
        let window = usize::try_from(self.window).map_err(|_| window_error())?;
        let c = ModelCheckConfig {
            spacing_s: self.spacing_s,
            window,
            p_fa_per_hour: self.p_fa_per_hour,
        };
        match c.validate(MAX_WINDOW) {
            Ok(()) => Ok(c),
            Err(ModelCheckError::WindowOutOfRange { .. }) => Err(window_error()),
            Err(e) => Err(e.into()),
        }
    }
}

impl From<ModelCheckError> for WireError {
    fn from(e: ModelCheckError) -> Self {
        let u32_of = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
        match e {
            ModelCheckError::NotFinite { field, value } => WireError::NonFinite {
                field: field_name(field),
                index: 0,
                value,
            },
            ModelCheckError::OutOfRange {
                field,
                value,
                min,
                max,
            } => WireError::OutOfRange {
                field: field_name(field),
                value,
                min,
                max,
            },
            ModelCheckError::WindowOutOfRange { window, capacity } => WireError::OutOfRange {
                field: field_name("window"),
                value: window as f64,
                min: 1.0,
                max: capacity as f64,
            },
            ModelCheckError::ZeroDof => WireError::InvalidDof {
                dof: 0,
                max: raim_core::stats::dist::MAX_DOF,
            },
            ModelCheckError::DofOutOfRange { dof, max } => WireError::InvalidDof { dof, max },
            ModelCheckError::TimeNotIncreasing { time_s, last_s } => WireError::TimeNotIncreasing {
                previous_s: last_s,
                now_s: time_s,
            },
            ModelCheckError::Geometry { n, m } => WireError::TooFewSatellites {
                have: u32_of(n),
                need: u32_of(m.saturating_add(1)),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The defaults are the core's; every bound is refused with the
    /// offending value on either side of it, and a value on the bound is
    /// taken.
    ///
    /// Verifies: MODEL-CONFIG
    #[test]
    fn bounds_are_the_cores_and_refusals_carry_the_value() {
        let d = WireModelCheckConfig::default();
        assert_eq!(d.check(), Ok(ModelCheckConfig::DEFAULT));
        assert_eq!(d.spacing_s, 1800.0);
        assert_eq!(d.window, 8);
        assert_eq!(d.p_fa_per_hour, 1e-6);
        let with = |f: &dyn Fn(&mut WireModelCheckConfig)| {
            let mut c = d;
            f(&mut c);
            c.check()
        };
        let out = |field: &str, value: f64, min: f64, max: f64| {
            Err(WireError::OutOfRange {
                field: field_name(field),
                value,
                min,
                max,
            })
        };
        assert_eq!(with(&|c| c.window = 0), out("window", 0.0, 1.0, 16.0));
        assert_eq!(with(&|c| c.window = 17), out("window", 17.0, 1.0, 16.0));
        assert_eq!(
            with(&|c| c.window = u32::MAX),
            out("window", 4294967295.0, 1.0, 16.0)
        );
        assert!(with(&|c| c.window = 1).is_ok());
        assert!(with(&|c| c.window = 16).is_ok());
        assert_eq!(
            with(&|c| c.spacing_s = 1e-4),
            out("spacing_s", 1e-4, 1e-3, 86_400.0)
        );
        assert_eq!(
            with(&|c| c.spacing_s = f64::INFINITY),
            out("spacing_s", f64::INFINITY, 1e-3, 86_400.0)
        );
        assert!(matches!(
            with(&|c| c.spacing_s = f64::NAN),
            Err(WireError::NonFinite { ref field, index: 0, value }) if field == "spacing_s" && value.is_nan()
        ));
        assert!(with(&|c| c.spacing_s = 86_400.0).is_ok());
        assert_eq!(
            with(&|c| c.p_fa_per_hour = 0.6),
            out("p_fa_per_hour", 0.6, 1e-12, 0.5)
        );
        assert_eq!(
            with(&|c| c.p_fa_per_hour = 0.0),
            out("p_fa_per_hour", 0.0, 1e-12, 0.5)
        );
        assert!(with(&|c| c.p_fa_per_hour = 0.5).is_ok());
    }
}
