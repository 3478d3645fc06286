//! What the monitor says about one epoch: the decision, the statistics,
//! the per-satellite quantities, the exclusions and the protection levels.
//! Shared by the engines (`snapshot`, `sequential`) and returned by
//! [`crate::Raim::process`].

use crate::frames::Geodetic;
use crate::measurement::{SatId, MAX_SYSTEMS};
use crate::sequential::McusumReport;
use crate::snapshot::detection::TestStatistic;
use crate::snapshot::fde::{AlarmCause, Exclusion, MAX_EXCLUSIONS};
use crate::snapshot::protection::ProtectionLevels;

/// The epoch's verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Decision {
    /// The all-in-view test passes and the protection levels are within the
    /// alert limits.
    Ok,
    /// The test fails and exclusion could not restore consistency: do not use.
    Alarm,
    /// One or more satellites were excluded; the subset passes and its
    /// protection levels are within the alert limits.
    Excluded,
    /// The measurements are consistent, but integrity cannot be assured:
    /// a protection level exceeds its alert limit.
    Unavailable,
}

/// Per-satellite quantities from the all-in-view solution (where the
/// detection and the first identification happen).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SatelliteResult {
    /// The satellite.
    pub id: SatId,
    /// In the solution in force (not excluded).
    pub used: bool,
    /// Pseudorange sigma used, m.
    pub sigma_m: f64,
    /// Elevation of the satellite, rad.
    pub elevation_rad: f64,
    /// Diagonal of S (1 - leverage).
    pub s_ii: f64,
    /// Leverage h_ii = 1 - S_ii.
    pub h_ii: f64,
    /// Normalised residual w_i = r_i / sqrt(S_ii), sigma units.
    pub w: f64,
    /// Bias estimate b_i = r_i / S_ii, in metres (seed 000 eq. 8).
    pub bias_m: f64,
    /// Identification score under the configured rule; NaN if unidentifiable.
    pub score: f64,
    /// Whether a fault on this satellite can be identified (S_ii above the bound).
    pub identifiable: bool,
}

/// Everything the monitor says about one epoch.
#[derive(Debug, Clone)]
pub struct EpochResult<const N: usize> {
    /// Epoch time, s.
    pub time_s: f64,
    /// Ok, alarm, excluded or unavailable.
    pub decision: Decision,
    /// Why an alarm stands (None unless `decision == Alarm`).
    pub alarm_cause: Option<AlarmCause>,
    /// ECEF position of the solution in force (pseudorange input).
    pub position_ecef_m: Option<[f64; 3]>,
    /// Geodetic position of the solution in force (pseudorange input).
    pub geodetic: Option<Geodetic>,
    /// ENU correction to the linearisation point (linear input), m.
    pub correction_enu_m: [f64; 3],
    /// Receiver clock per system in `System::ALL` order, m.
    pub clock_m: [Option<f64>; MAX_SYSTEMS],
    /// The all-in-view test.
    pub initial_test: TestStatistic,
    /// The test of the solution in force.
    pub test: TestStatistic,
    /// Per satellite, in input order.
    pub satellites: heapless::Vec<SatelliteResult, N>,
    /// The satellite the rule identified on the all-in-view solution when
    /// the test failed.
    pub identified: Option<SatId>,
    /// Exclusion steps. They are in force only when `decision` is
    /// `Excluded` (or `Unavailable` after exclusion).
    pub exclusions: heapless::Vec<Exclusion, MAX_EXCLUSIONS>,
    /// Protection levels of the solution in force.
    pub protection: ProtectionLevels,
    /// Satellite with the largest horizontal slope.
    pub worst_h: Option<SatId>,
    /// Satellite with the largest vertical slope.
    pub worst_v: Option<SatId>,
    /// 1-sigma ENU position error of the solution in force, m.
    pub sigma_enu_m: [f64; 3],
    /// Non-centrality lambda_md used for the PLs (dof of the final set).
    pub lambda_md: f64,
    /// n - m >= 1 in the solution in force.
    pub detection_available: bool,
    /// n - m >= 2 in the solution in force.
    pub exclusion_available: bool,
    /// PLs within the alert limits.
    pub pl_available: bool,
    /// Gauss-Newton iterations of the all-in-view solve (0 for linear input).
    pub iterations: u32,
    /// The sequential test's state and decision; `None` when the MCUSUM is
    /// disabled (the result is then exactly the snapshot monitor's).
    pub mcusum: Option<McusumReport>,
    /// The reconstruction FDE's search (`FdeMethod::Reconstruction`, when
    /// the all-in-view test failed); `None` otherwise.
    pub multifault: Option<crate::multifault::MultifaultReport>,
}

impl<const N: usize> EpochResult<N> {
    /// The initial value of caller-owned result storage: an unavailable
    /// epoch with no satellites (a real, conservative verdict, never read
    /// as a fix), which [`crate::Raim::process_into`] overwrites in full. A
    /// caller that keeps the result in its own storage (the firmware's
    /// static server) builds one once and reuses it.
    pub const fn empty() -> Self {
        EpochResult {
            time_s: 0.0,
            decision: Decision::Unavailable,
            alarm_cause: None,
            position_ecef_m: None,
            geodetic: None,
            correction_enu_m: [0.0; 3],
            clock_m: [None; MAX_SYSTEMS],
            initial_test: TestStatistic::ZERO,
            test: TestStatistic::ZERO,
            satellites: heapless::Vec::new(),
            identified: None,
            exclusions: heapless::Vec::new(),
            // Unbounded until computed: never a level of 0.
            protection: ProtectionLevels {
                hpl_m: f64::INFINITY,
                vpl_m: f64::INFINITY,
                worst_h_row: None,
                worst_v_row: None,
            },
            worst_h: None,
            worst_v: None,
            sigma_enu_m: [0.0; 3],
            lambda_md: 0.0,
            detection_available: false,
            exclusion_available: false,
            pl_available: false,
            iterations: 0,
            mcusum: None,
            multifault: None,
        }
    }

    /// The model check's sample of this epoch (issue 35,
    /// docs/MODEL_CHECK.md): q = D^2 and the dof of the test of the
    /// solution in force (all in view, or the subset after an
    /// exclusion), with the sigma model's weights. `None` for an `Alarm`
    /// (no solution delivered, and a fault is not a model error) and
    /// without redundancy (dof 0).
    pub fn model_sample(&self) -> Option<(f64, u32)> {
        (self.decision != Decision::Alarm && self.test.dof > 0)
            .then_some((self.test.statistic, self.test.dof))
    }
}
