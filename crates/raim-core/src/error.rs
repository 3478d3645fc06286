//! Typed errors. Every rejection carries the offending value and, where it
//! applies, the field name and satellite index, so nothing is lost silently.

use crate::measurement::System;

/// Why an epoch (or a configuration, or a distribution query) was rejected.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum RaimError {
    /// A NaN or infinite input value.
    NotFinite {
        /// Name of the offending field.
        field: &'static str,
        /// Index of the satellite (0 for a per-epoch field).
        index: usize,
        /// The value received.
        value: f64,
    },
    /// The same satellite appears twice in one epoch.
    DuplicateSatellite {
        /// The satellite's constellation.
        system: System,
        /// The satellite's PRN.
        prn: u8,
        /// Index of its first appearance in the epoch.
        first: usize,
        /// Index of its second appearance.
        second: usize,
    },
    /// Fewer satellites than unknowns (+ the redundancy the operation needs).
    TooFewSatellites {
        /// Satellites in the epoch.
        have: usize,
        /// Satellites the operation needs.
        need: usize,
    },
    /// The geometry matrix lost rank: column `column` has a Householder
    /// pivot of `pivot` relative to its column norm.
    RankDeficient {
        /// Index of the geometry column that lost rank.
        column: usize,
        /// Its Householder pivot relative to the column norm (dimensionless).
        pivot: f64,
    },
    /// A sigma that is zero or negative.
    NonPositiveSigma {
        /// Index of the satellite.
        index: usize,
        /// The sigma received, m.
        sigma_m: f64,
    },
    /// More satellites than the capacity `N` of the engine.
    CapacityExceeded {
        /// Satellites in the epoch.
        have: usize,
        /// The engine's capacity `N`.
        capacity: usize,
    },
    /// A value outside its documented range.
    OutOfRange {
        /// Name of the offending field.
        field: &'static str,
        /// The value received (in the field's unit).
        value: f64,
        /// Smallest value accepted.
        min: f64,
        /// Largest value accepted.
        max: f64,
    },
    /// Gauss-Newton did not converge.
    NoConvergence {
        /// Gauss-Newton iterations run.
        iterations: u32,
        /// Length of the last position step, m.
        step_m: f64,
    },
    /// A chi-square degree of freedom outside 1..=max.
    InvalidDof {
        /// The degree of freedom asked for.
        dof: u32,
        /// The largest supported.
        max: u32,
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
        /// Its constellation.
        system: System,
        /// The number given.
        prn: u8,
        /// The system's largest number.
        max: u8,
    },
    /// An epoch whose time does not follow the last one a stateful monitor
    /// (the MCUSUM) took: refused, the monitor's state left as it was.
    TimeNotIncreasing {
        /// The time of the last epoch the monitor took, s.
        previous_s: f64,
        /// This epoch's time, s.
        now_s: f64,
    },
}

impl core::fmt::Display for RaimError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            RaimError::NotFinite {
                field,
                index,
                value,
            } => {
                write!(f, "non-finite {field} at index {index}: {value}")
            }
            RaimError::DuplicateSatellite {
                system,
                prn,
                first,
                second,
            } => write!(
                f,
                "duplicate satellite {}{prn:02} at indices {first} and {second}",
                system.letter()
            ),
            RaimError::TooFewSatellites { have, need } => {
                write!(f, "too few satellites: have {have}, need {need}")
            }
            RaimError::RankDeficient { column, pivot } => {
                write!(
                    f,
                    "rank-deficient geometry at column {column} (pivot {pivot:e})"
                )
            }
            RaimError::NonPositiveSigma { index, sigma_m } => {
                write!(f, "sigma at index {index} is not positive: {sigma_m} m")
            }
            RaimError::CapacityExceeded { have, capacity } => {
                write!(f, "{have} satellites exceed capacity {capacity}")
            }
            RaimError::OutOfRange {
                field,
                value,
                min,
                max,
            } => write!(f, "{field} = {value} outside [{min}, {max}]"),
            RaimError::NoConvergence { iterations, step_m } => write!(
                f,
                "no convergence after {iterations} iterations (last step {step_m} m)"
            ),
            RaimError::InvalidDof { dof, max } => {
                write!(f, "degrees of freedom {dof} outside 1..={max}")
            }
            RaimError::SigmaOutOfRange {
                index,
                sigma_m,
                min_m,
                max_m,
            } => write!(
                f,
                "sigma at index {index} is {sigma_m} m, outside [{min_m}, {max_m}] m"
            ),
            RaimError::PrnOutOfRange {
                index,
                system,
                prn,
                max,
            } => write!(
                f,
                "satellite number {prn} of {} at index {index} is outside 1..={max}",
                system.letter()
            ),
            RaimError::TimeNotIncreasing { previous_s, now_s } => write!(
                f,
                "time {now_s} s does not follow the last epoch's {previous_s} s"
            ),
        }
    }
}

impl core::error::Error for RaimError {}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::format;

    /// Every rejection says what was wrong with the values it carries: each
    /// variant's message names its field and shows its offending values.
    #[test]
    fn every_error_names_its_values() {
        let cases: [(RaimError, &[&str]); 12] = [
            (
                RaimError::NotFinite {
                    field: "pseudorange_m",
                    index: 7,
                    value: f64::NAN,
                },
                &["pseudorange_m", "7", "NaN"],
            ),
            (
                RaimError::DuplicateSatellite {
                    system: System::Galileo,
                    prn: 5,
                    first: 2,
                    second: 9,
                },
                &["E05", "2", "9"],
            ),
            (
                RaimError::TooFewSatellites { have: 4, need: 6 },
                &["have 4", "need 6"],
            ),
            (
                RaimError::RankDeficient {
                    column: 3,
                    pivot: 1.5e-13,
                },
                &["column 3", "1.5e-13"],
            ),
            (
                RaimError::NonPositiveSigma {
                    index: 11,
                    sigma_m: -0.25,
                },
                &["index 11", "-0.25 m"],
            ),
            (
                RaimError::CapacityExceeded {
                    have: 40,
                    capacity: 32,
                },
                &["40", "32"],
            ),
            (
                RaimError::OutOfRange {
                    field: "pfa",
                    value: 2.0,
                    min: 1e-9,
                    max: 0.5,
                },
                &["pfa = 2", "0.000000001", "0.5"],
            ),
            (
                RaimError::NoConvergence {
                    iterations: 20,
                    step_m: 12.5,
                },
                &["20 iterations", "12.5 m"],
            ),
            (RaimError::InvalidDof { dof: 0, max: 64 }, &["0", "1..=64"]),
            (
                RaimError::SigmaOutOfRange {
                    index: 3,
                    sigma_m: 900.0,
                    min_m: 0.1,
                    max_m: 300.0,
                },
                &["index 3", "900 m", "[0.1, 300] m"],
            ),
            (
                RaimError::PrnOutOfRange {
                    index: 1,
                    system: System::Gps,
                    prn: 0,
                    max: 32,
                },
                &["number 0 of G", "index 1", "1..=32"],
            ),
            (
                RaimError::TimeNotIncreasing {
                    previous_s: 101.0,
                    now_s: 51.0,
                },
                &["51 s", "101 s"],
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
