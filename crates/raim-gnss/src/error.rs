//! Typed errors of the GNSS front end, each carrying the offending values.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum GnssError {
    #[error("file not found: {0}")]
    FileNotFound(PathBuf),
    #[error("cannot parse RINEX file {path}: {detail}")]
    Parse { path: PathBuf, detail: String },
    #[error("{path} is not a RINEX {expected} file")]
    WrongKind {
        path: PathBuf,
        expected: &'static str,
    },
    /// A corrupt epoch record, caught before the `rinex` crate
    /// (which panics on some) sees it. `line` counts from 1.
    #[error("{path}:{line}: bad epoch record: {detail}")]
    BadEpoch {
        path: PathBuf,
        line: usize,
        detail: String,
    },
    #[error("unknown system letter '{0}' (use G, R, E, C, J)")]
    UnknownSystem(char),
    #[error("bad satellite '{0}' (expected e.g. G24)")]
    BadSatellite(String),
    #[error("bad time '{0}' (expected HH:MM:SS, seconds, or an ISO date-time)")]
    BadTime(String),
    #[error("bad fault spec '{spec}': {detail}")]
    BadFault { spec: String, detail: String },
    #[error("scenario file {path}: {detail}")]
    Scenario { path: PathBuf, detail: String },
    #[error("{field} = {value} is out of range [{min}, {max}]")]
    OutOfRange {
        field: &'static str,
        value: f64,
        min: f64,
        max: f64,
    },
}

impl From<raim_nav::NavError> for GnssError {
    fn from(e: raim_nav::NavError) -> Self {
        match e {
            raim_nav::NavError::OutOfRange {
                field,
                value,
                min,
                max,
            } => GnssError::OutOfRange {
                field,
                value,
                min,
                max,
            },
        }
    }
}
