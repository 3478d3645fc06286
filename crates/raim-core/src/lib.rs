//! raim-core: receiver autonomous integrity monitoring for GNSS, `no_std`,
//! heap-free and panic-free. The mathematics is `../shared/SPEC.md`; the
//! choices the SPEC leaves open are in `docs/CORE.md`.
//!
//! Entry point: [`Raim::process`] takes a [`Config`] and an [`Epoch`] and
//! returns an [`EpochResult`] or a typed [`RaimError`].
//!
//! Layout: one folder per method, each with its own orchestration and
//! tests: `snapshot` (detection, L-RAIM identification, FDE, protection
//! levels) and `sequential` (MCUSUM), and `pf` (particle-filter RAIM of
//! seed 004: GA-PF, SIR PF and EKF in a main + auxiliary LLR structure,
//! docs/PF.md), and `consistency` (the run-time check of the error model
//! against the residuals, docs/MODEL_CHECK.md). Shared layers beside them: `linalg`
//! (QR, parity space), `stats` (distributions), `solve` (measurement model
//! and Gauss-Newton), `measurement`, `frames`, `sigma`, `config`, `error`,
//! `result`, and `real` (the precision policy: which quantities are `f64`
//! and which run in the engine's precision `T`, f32 on the device). `monitor` is the thin entry that validates and dispatches.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// `!(a < b)` is deliberate throughout: it is true for NaN, so a NaN
// statistic alarms instead of passing.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub mod araim;
pub mod budget;
pub mod config;
pub mod config_bounds;
pub mod consistency;
pub mod error;
pub mod frames;
pub mod linalg;
pub mod measurement;
pub mod monitor;
pub mod multifault;
pub mod pf;
pub mod real;
pub mod result;
pub mod sequential;
pub mod sigma;
pub mod snapshot;
pub mod solve;
pub mod stats;
#[cfg(test)]
mod testutil;

pub use config::{AlertLimits, Carry, Config, FdeMethod, FiRule, McusumConfig, Phase};
pub use error::RaimError;
pub use measurement::{Epoch, LinearObservation, Observations, RangeObservation, SatId, System};
pub use monitor::Raim;
pub use real::{Real, Stat};
pub use result::{Decision, EpochResult, SatelliteResult};
pub use sequential::{AlarmSource, McusumReport};

/// The documented default capacity: 32 satellites.
pub const DEFAULT_CAPACITY: usize = 32;
