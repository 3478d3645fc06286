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
        /// Name of the offending field.
        field: &'static str,
        /// Index of the satellite (0 for the epoch time).
        index: usize,
        /// The value received.
        value: f64,
    },
    /// The same satellite appears twice in one epoch.
    DuplicateSatellite {
        /// The satellite that appears twice.
        id: SatId,
    },
    /// Fewer usable satellites than the FDI needs: each auxiliary filter
    /// (one satellite left out) must still see 3 + clocks + 1 satellites.
    TooFewSatellites {
        /// Usable satellites in the epoch.
        have: usize,
        /// Satellites the FDI needs.
        need: usize,
    },
    /// More satellites than the monitor's fixed capacity.
    Capacity {
        /// Name of the capacity exceeded.
        field: &'static str,
        /// The number asked for.
        have: usize,
        /// The monitor's fixed capacity.
        max: usize,
    },
    /// A configuration value outside its domain.
    InvalidConfig {
        /// Name of the offending configuration field.
        field: &'static str,
        /// The value received (in the field's unit).
        value: f64,
    },
    /// No calibrated threshold covers this configuration: the table lacks
    /// the model profile, the window, the likelihood, the filter and
    /// particle count, or the false-alarm probability is below the
    /// smallest certified node.
    NotCalibrated {
        /// What the table lacks.
        field: &'static str,
        /// The configured value.
        value: f64,
    },
    /// Epoch times must increase strictly.
    TimeNotIncreasing {
        /// The previous epoch's time, s.
        previous_s: f64,
        /// This epoch's time, s.
        now_s: f64,
    },
    /// The first-epoch least-squares fix (the filters' reference point)
    /// did not converge.
    NoInitialFix {
        /// Gauss-Newton iterations run.
        iterations: u32,
        /// Length of the last position step, m.
        step_m: f64,
    },
    /// A configuration value outside its operational bound
    /// (`config_bounds::pf`), or the epoch time outside
    /// `measurement::EPOCH_TIME_S`.
    OutOfRange {
        /// The field.
        field: &'static str,
        /// The value given.
        value: f64,
        /// The bound's floor.
        min: f64,
        /// The bound's ceiling.
        max: f64,
    },
    /// A per-satellite sigma outside the operational bound
    /// `config_bounds::SIGMA_M` (satellite `index`).
    SigmaOutOfRange {
        /// The satellite's index in the epoch.
        index: usize,
        /// The sigma given, m.
        sigma_m: f64,
        /// The bound's floor, m.
        min_m: f64,
        /// The bound's ceiling, m.
        max_m: f64,
    },
    /// A satellite number outside its system's range 1..=`max`
    /// (`System::max_prn`; satellite `index` of the epoch).
    PrnOutOfRange {
        /// The satellite's index in the epoch.
        index: usize,
        /// The satellite as given.
        id: SatId,
        /// The system's largest number.
        max: u8,
    },
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
            PfError::OutOfRange {
                field,
                value,
                min,
                max,
            } => write!(f, "{field} = {value} outside [{min}, {max}]"),
            PfError::PrnOutOfRange { index, id, max } => write!(
                f,
                "satellite number {} of {} at index {index} is outside 1..={max}",
                id.prn,
                id.system.letter()
            ),
            PfError::SigmaOutOfRange {
                index,
                sigma_m,
                min_m,
                max_m,
            } => write!(
                f,
                "sigma_m[{index}] = {sigma_m} m outside [{min_m}, {max_m}] m"
            ),
        }
    }
}

impl core::error::Error for PfError {}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::measurement::System;
    use std::format;

    /// Every particle-filter rejection's message names its field and shows
    /// its offending values.
    #[test]
    fn every_error_names_its_values() {
        let g07 = SatId::new(System::Gps, 7);
        let cases: [(PfError, &[&str]); 11] = [
            (
                PfError::NotFinite {
                    field: "pseudorange_m",
                    index: 3,
                    value: f64::NAN,
                },
                &["pseudorange_m[3]", "NaN"],
            ),
            (PfError::DuplicateSatellite { id: g07 }, &["G07"]),
            (
                PfError::TooFewSatellites { have: 3, need: 5 },
                &["3 usable", "5 needed"],
            ),
            (
                PfError::Capacity {
                    field: "particles",
                    have: 5000,
                    max: 1000,
                },
                &["particles", "5000", "1000"],
            ),
            (
                PfError::InvalidConfig {
                    field: "window",
                    value: 0.0,
                },
                &["window = 0"],
            ),
            (
                PfError::NotCalibrated {
                    field: "particles",
                    value: 77.0,
                },
                &["particles = 77"],
            ),
            (
                PfError::TimeNotIncreasing {
                    previous_s: 10.0,
                    now_s: 9.0,
                },
                &["9 s", "10 s"],
            ),
            (
                PfError::NoInitialFix {
                    iterations: 30,
                    step_m: 1e4,
                },
                &["30 iterations", "10000 m"],
            ),
            (
                PfError::OutOfRange {
                    field: "pfa",
                    value: 0.9,
                    min: 1e-6,
                    max: 0.1,
                },
                &["pfa = 0.9", "0.1]"],
            ),
            (
                PfError::SigmaOutOfRange {
                    index: 2,
                    sigma_m: 0.01,
                    min_m: 0.1,
                    max_m: 300.0,
                },
                &["sigma_m[2] = 0.01 m", "[0.1, 300] m"],
            ),
            (
                PfError::PrnOutOfRange {
                    index: 5,
                    id: SatId::new(System::Galileo, 40),
                    max: 36,
                },
                &["number 40 of E", "index 5", "1..=36"],
            ),
        ];
        for (e, parts) in cases {
            let msg = format!("{e}");
            for p in parts {
                assert!(msg.contains(p), "{e:?}: {msg:?} lacks {p:?}");
            }
        }
    }
}
