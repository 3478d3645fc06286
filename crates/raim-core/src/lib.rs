//! raim-core: receiver autonomous integrity monitoring for GNSS, `no_std`,
//! heap-free and panic-free. The mathematics is `../shared/SPEC.md`; the
//! choices the SPEC leaves open are in `docs/CORE.md`.
//!
//! Entry point: [`Raim::process`] takes a [`Config`] and an [`Epoch`] and
//! returns an [`EpochResult`] or a typed [`RaimError`].
#![no_std]
#![forbid(unsafe_code)]
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

pub mod config;
pub mod detection;
pub mod dist;
pub mod error;
pub mod fde;
pub mod frames;
pub mod lraim;
pub mod mcusum;
#[rustfmt::skip]
pub mod mcusum_table;
pub mod measurement;
pub mod monitor;
pub mod parity;
pub mod protection;
pub mod qr;
pub mod sigma;
pub mod solve;
#[cfg(test)]
mod testutil;

pub use config::{AlertLimits, Carry, Config, FiRule, McusumConfig, Phase};
pub use error::RaimError;
pub use measurement::{Epoch, LinearObservation, Observations, RangeObservation, SatId, System};
pub use monitor::{AlarmSource, Decision, EpochResult, McusumReport, Raim, SatelliteResult};

/// The documented default capacity: 32 satellites.
pub const DEFAULT_CAPACITY: usize = 32;
