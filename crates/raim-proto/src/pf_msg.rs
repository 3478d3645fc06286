//! Particle-filter RAIM on the wire (docs/PROTOCOL.md "Particle
//! filter"): the configuration a `PfConfigure` carries, the per-epoch
//! answer to a `PfRanges` epoch, the compiled capacities, and the
//! configuration fingerprint that covers both the snapshot and the PF
//! configuration.
//!
//! The engine is `raim_core::pf::PfRaim` with `f32` particle state (the
//! offset state the pf module supports; docs/PF.md "Memory": the only
//! precision at which 300 particles fit a 192 KiB part) on host and device
//! alike, so that the host's `Server` is the device's reference bit for bit.

use raim_core::measurement::MAX_SYSTEMS;
use raim_core::pf::{PfConfig, PfOutput, SatLlr};
use raim_core::SatId;
use serde::{Deserialize, Serialize};

/// Satellites per PF epoch: the main filter plus one auxiliary filter per
/// satellite are fixed arrays of this many. The 6 to 12 satellites;
/// an epoch with more is answered `TooManySatellites { capacity: 12 }`.
pub const PF_SATS: usize = 12;

/// The particle counts compiled into the PF engine (one monomorphised
/// filter each, sharing one static storage; `raim_server`'s `pf`). A
/// `PfConfigure` with another count is refused with
/// `WireError::PfParticles`.
pub const PF_PARTICLE_COUNTS: [u32; 2] = [100, 300];

/// The largest compiled particle count: the capacity the storage is sized
/// for.
pub const PF_MAX_PARTICLES: u32 = 300;

/// Which filter runs in seed 004's main + auxiliary structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PfKind {
    /// The extended Kalman filter baseline (`particles` must be 0).
    Ekf,
    /// The plain SIR particle filter.
    Pf,
    /// The genetic-algorithm-aided particle filter (seed 004's method).
    Gapf,
}

/// What a `PfConfigure` sets: the filter, its particle count, the seed of
/// its random stream (xoshiro256++, identical on every target) and the
/// core's `PfConfig` (process model, likelihood, LLR window U and
/// threshold, exclusion, collapse level). Taking it restarts the filter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WirePfConfig {
    /// Which filter: EKF, SIR PF or GA-PF.
    pub kind: PfKind,
    /// One of [`PF_PARTICLE_COUNTS`] for `Pf`/`Gapf`; 0 for `Ekf`.
    pub particles: u32,
    /// Seed of the filter's xoshiro256++ random stream.
    pub seed: u64,
    /// The core's PF configuration.
    pub config: PfConfig,
}

impl WirePfConfig {
    /// The seed 004 GA-PF at `particles` with the core's default PfConfig.
    pub fn gapf(particles: u32, seed: u64) -> Self {
        WirePfConfig {
            kind: PfKind::Gapf,
            particles,
            seed,
            config: PfConfig::default(),
        }
    }
}

/// One PF epoch's answer: `raim_core::pf::PfOutput` on the wire.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WirePfResult {
    /// Epoch time, s.
    pub time_s: f64,
    /// The main filter's ECEF position; `None` when it collapsed this epoch
    /// (never a position from a collapsed filter).
    pub position_ecef_m: Option<[f64; 3]>,
    /// Clock bias per constellation (System::index), m.
    pub clock_m: [f64; MAX_SYSTEMS],
    /// Clock drift, m/s.
    pub drift_m_s: f64,
    /// D_k = max_q max_j S_j^k(q) (seed 004 eq. 13); -inf before any LLR.
    pub decision: f64,
    /// The alarm threshold on D_k.
    pub threshold: f64,
    /// D_k > threshold (or D_k is NaN).
    pub alarm: bool,
    /// argmax_q at an alarm (eq. 14).
    pub isolated: Option<SatId>,
    /// The satellite excluded this epoch (with `exclude`).
    pub excluded: Option<SatId>,
    /// The main filter's effective sample size (eq. 16) of the weights
    /// entering resampling: after the genetic step for the GA-PF; 0 for
    /// the EKF.
    pub n_eff: f64,
    /// The main filter's effective sample size of the likelihood weights,
    /// before the genetic step (equal to `n_eff` for the SIR filter; 0 for
    /// the EKF): the GA step raises `n_eff` partly by construction.
    pub n_eff_before_ga: f64,
    /// Satellites the main filter used.
    pub used: u32,
    /// The main filter collapsed and was reinitialised this epoch.
    pub main_collapsed: bool,
    /// Auxiliary filters that collapsed and were reinitialised this epoch.
    pub aux_collapsed: u32,
    /// A receiver clock jump moved a clock reference.
    pub clock_jump: bool,
    /// Per auxiliary filter: the satellite it leaves out, this epoch's
    /// s_k(q) (eq. 15) and its windowed accumulated LLR (eq. 13).
    pub llr: heapless::Vec<SatLlr, PF_SATS>,
}

impl WirePfResult {
    /// The wire form of a core PF output.
    pub fn from_output(o: &PfOutput<PF_SATS>) -> Self {
        WirePfResult {
            time_s: o.time_s,
            position_ecef_m: o.position_m,
            clock_m: o.clock_m,
            drift_m_s: o.drift_m_s,
            decision: o.decision,
            threshold: o.threshold,
            alarm: o.alarm,
            isolated: o.isolated,
            excluded: o.excluded,
            n_eff: o.n_eff,
            n_eff_before_ga: o.n_eff_before_ga,
            used: u32::try_from(o.used).unwrap_or(u32::MAX),
            main_collapsed: o.main_collapsed,
            aux_collapsed: u32::try_from(o.aux_collapsed).unwrap_or(u32::MAX),
            clock_jump: o.clock_jump,
            llr: o.llr.clone(),
        }
    }
}
