//! Typed rejections of an ARAIM epoch. Every variant carries the
//! offending values and, where it applies, the field name and the
//! satellite index, so nothing is lost silently.

use crate::measurement::System;

/// Why an ARAIM epoch, its ISM or its configuration was rejected.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AraimError {
    /// A NaN or infinite value. `index` is the satellite (or constellation)
    /// index, 0 for configuration fields.
    NotFinite {
        /// Name of the offending field.
        field: &'static str,
        /// Satellite (or constellation) index, 0 for configuration fields.
        index: usize,
        /// The value received.
        value: f64,
    },
    /// A value outside its documented range (`config_bounds::araim`;
    /// bounds inclusive, or the other field of a cross-field rule).
    OutOfRange {
        /// Name of the offending field.
        field: &'static str,
        /// Satellite (or constellation) index, 0 for configuration fields.
        index: usize,
        /// The value received (in the field's unit).
        value: f64,
        /// Smallest value accepted.
        min: f64,
        /// Largest value accepted.
        max: f64,
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
    /// More satellites than the capacity `N` of the engine (or than the
    /// 64 a mode's bit mask can hold).
    CapacityExceeded {
        /// Satellites in the epoch.
        have: usize,
        /// The capacity exceeded (`N`, or 64).
        capacity: usize,
    },
    /// A constellation that has an ISM entry (is declared in use) but no
    /// satellite in the epoch: its clock column would be unobservable.
    EmptyConstellation {
        /// The constellation with an ISM entry and no satellite.
        system: System,
    },
    /// A satellite of a constellation that has no ISM entry (no P_const).
    MissingConstellationIsm {
        /// The constellation without an ISM entry.
        system: System,
        /// Index of the first satellite of it in the epoch.
        index: usize,
    },
    /// Fewer satellites than the all-in-view unknowns (3 + clocks).
    TooFewSatellites {
        /// Satellites in the epoch.
        have: usize,
        /// Unknowns of the all-in-view solution (3 + clocks).
        need: usize,
    },
    /// The all-in-view normal matrix is singular: column `column` has a
    /// Cholesky pivot of `pivot` relative to its diagonal.
    RankDeficient {
        /// Index of the column whose pivot collapsed.
        column: usize,
        /// Its Cholesky pivot relative to the diagonal (dimensionless).
        pivot: f64,
    },
}

impl core::fmt::Display for AraimError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            AraimError::NotFinite {
                field,
                index,
                value,
            } => write!(f, "non-finite {field} at index {index}: {value}"),
            AraimError::OutOfRange {
                field,
                index,
                value,
                min,
                max,
            } => write!(
                f,
                "{field} at index {index} is {value}, outside [{min}, {max}]"
            ),
            AraimError::DuplicateSatellite {
                system,
                prn,
                first,
                second,
            } => write!(
                f,
                "duplicate satellite {}{prn:02} at indices {first} and {second}",
                system.letter()
            ),
            AraimError::CapacityExceeded { have, capacity } => {
                write!(f, "{have} satellites exceed capacity {capacity}")
            }
            AraimError::EmptyConstellation { system } => write!(
                f,
                "constellation {} has an ISM entry but no satellite",
                system.letter()
            ),
            AraimError::MissingConstellationIsm { system, index } => write!(
                f,
                "satellite at index {index} is of constellation {} which has no ISM entry",
                system.letter()
            ),
            AraimError::TooFewSatellites { have, need } => {
                write!(f, "too few satellites: have {have}, need {need}")
            }
            AraimError::RankDeficient { column, pivot } => write!(
                f,
                "rank-deficient all-in-view geometry at column {column} (pivot {pivot:e})"
            ),
        }
    }
}

impl core::error::Error for AraimError {}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::format;

    /// Every ARAIM rejection's message names its field and shows its
    /// offending values.
    #[test]
    fn every_error_names_its_values() {
        let cases: [(AraimError, &[&str]); 8] = [
            (
                AraimError::NotFinite {
                    field: "residual_m",
                    index: 4,
                    value: f64::INFINITY,
                },
                &["residual_m", "index 4", "inf"],
            ),
            (
                AraimError::OutOfRange {
                    field: "sigma_ura_m",
                    index: 2,
                    value: 0.01,
                    min: 0.3,
                    max: 100.0,
                },
                &["sigma_ura_m", "index 2", "0.01", "[0.3, 100]"],
            ),
            (
                AraimError::DuplicateSatellite {
                    system: System::Gps,
                    prn: 12,
                    first: 0,
                    second: 5,
                },
                &["G12", "0 and 5"],
            ),
            (
                AraimError::CapacityExceeded {
                    have: 30,
                    capacity: 24,
                },
                &["30", "24"],
            ),
            (
                AraimError::EmptyConstellation {
                    system: System::Galileo,
                },
                &["constellation E"],
            ),
            (
                AraimError::MissingConstellationIsm {
                    system: System::Beidou,
                    index: 9,
                },
                &["index 9", "constellation C"],
            ),
            (
                AraimError::TooFewSatellites { have: 4, need: 5 },
                &["have 4", "need 5"],
            ),
            (
                AraimError::RankDeficient {
                    column: 4,
                    pivot: 2.5e-14,
                },
                &["column 4", "2.5e-14"],
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
