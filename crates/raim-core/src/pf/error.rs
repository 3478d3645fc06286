//! Typed errors of the particle-filter RAIM (`pf`): every rejected input
//! names the offending field and value, so nothing is lost silently.

use crate::measurement::SatId;

/// Why a `pf` epoch (or configuration) was refused. The filters are left
/// untouched by a refused epoch: the next good epoch predicts over the gap.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PfError {
    /// A measurement or time field is NaN or infinite.
    NotFinite {
        field: &'static str,
        index: usize,
        value: f64,
    },
    /// The same satellite appears twice in one epoch.
    DuplicateSatellite { id: SatId },
    /// Fewer usable satellites than the FDI needs: each auxiliary filter
    /// (one satellite left out) must still see 3 + clocks + 1 satellites.
    TooFewSatellites { have: usize, need: usize },
    /// More satellites than the monitor's fixed capacity.
    Capacity {
        field: &'static str,
        have: usize,
        max: usize,
    },
    /// A configuration value outside its domain.
    InvalidConfig { field: &'static str, value: f64 },
    /// No calibrated threshold covers this configuration: `field` names
    /// what the table lacks (the model profile, the window, the likelihood,
    /// the filter and particle count, or a false-alarm probability below
    /// the smallest certified node) and `value` the configured value.
    NotCalibrated { field: &'static str, value: f64 },
    /// Epoch times must increase strictly.
    TimeNotIncreasing { previous_s: f64, now_s: f64 },
    /// The first-epoch least-squares fix (the filters' reference point)
    /// did not converge.
    NoInitialFix { iterations: u32, step_m: f64 },
}

impl core::fmt::Display for PfError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PfError::NotFinite {
                field,
                index,
                value,
            } => write!(f, "{field}[{index}] is not finite ({value})"),
            PfError::DuplicateSatellite { id } => write!(f, "satellite {id} appears twice"),
            PfError::TooFewSatellites { have, need } => {
                write!(f, "too few satellites: {have} usable, {need} needed")
            }
            PfError::Capacity { field, have, max } => {
                write!(f, "{field}: {have} exceeds the capacity {max}")
            }
            PfError::InvalidConfig { field, value } => {
                write!(f, "configuration {field} = {value} is out of range")
            }
            PfError::NotCalibrated { field, value } => {
                write!(f, "no calibrated PF threshold for {field} = {value}")
            }
            PfError::TimeNotIncreasing { previous_s, now_s } => {
                write!(f, "time {now_s} s does not follow {previous_s} s")
            }
            PfError::NoInitialFix { iterations, step_m } => write!(
                f,
                "no initial fix after {iterations} iterations (last step {step_m} m)"
            ),
        }
    }
}
