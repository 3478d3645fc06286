//! Particle-filter RAIM (SPEC §10, seed 004): a main filter on all
//! satellites and one auxiliary filter per satellite left out, compared by
//! an accumulated log-likelihood-ratio test; the faulty satellite is the
//! one whose auxiliary filter explains the data best. Three filters run in
//! the same structure: the genetic-resampling particle filter (GA-PF, the
//! seed's method), the plain SIR particle filter and the EKF (the seed's
//! baselines). no_std, no heap, no panic: particle count and satellite
//! capacity are const generics; the randomness is a seeded xoshiro256++.
//!
//! Modules: `config` (process model, likelihood, test), `model` (state,
//! measurement function, likelihoods, the [`Estimator`] trait), `rng`,
//! `resample` (systematic + genetic operators), `particle` (SIR / GA-PF),
//! `ekf`, `init` (first fix), `threshold` + `threshold_table` (the
//! calibrated decision thresholds), `llr` (eqs. 10, 13), `fdi` (Fig. 1: the
//! monitor), `error`. docs/PF.md has the experiment and the memory table.

pub mod config;
pub mod ekf;
pub mod error;
pub mod fdi;
pub mod init;
pub mod llr;
pub mod model;
pub mod particle;
pub mod resample;
pub mod rng;
#[cfg(test)]
mod tests;
pub mod threshold;
pub mod threshold_table;

pub use config::{Likelihood, PfConfig, ProcessModel};
pub use ekf::Ekf;
pub use error::PfError;
pub use fdi::{PfOutput, PfRaim, SatLlr};
pub use model::{Estimator, Reference, Step};
pub use particle::{GaPf, ParticleFilter, SirPf};
#[cfg(test)]
mod pf_cov_tests;
