//! The per-epoch entry point: validate, solve, detect, identify, exclude,
//! protect (SPEC §1-6). Allocates nothing; the only state is a per-dof
//! threshold cache, so the caller owns time, bytes and configuration.

use crate::config::Config;
use crate::detection::{TestStatistic, Thresholds};
use crate::error::RaimError;
use crate::fde::{self, AlarmCause, Exclusion, MAX_EXCLUSIONS};
use crate::frames::Geodetic;
use crate::lraim;
use crate::measurement::{validate, Epoch, SatId, MAX_SYSTEMS};
use crate::protection::{self, ProtectionLevels};
use crate::solve::{solve, Solution};

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
    pub id: SatId,
    /// In the solution in force (not excluded).
    pub used: bool,
    pub sigma_m: f64,
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
    pub identifiable: bool,
}

/// Everything the monitor says about one epoch.
#[derive(Debug, Clone)]
pub struct EpochResult<const N: usize> {
    pub time_s: f64,
    pub decision: Decision,
    /// Why an alarm stands (None unless `decision == Alarm`).
    pub alarm_cause: Option<AlarmCause>,
    /// ECEF position of the solution in force (pseudorange input).
    pub position_ecef_m: Option<[f64; 3]>,
    pub geodetic: Option<Geodetic>,
    /// ENU correction to the linearisation point (linear input), m.
    pub correction_enu_m: [f64; 3],
    /// Receiver clock per system in `System::ALL` order, m.
    pub clock_m: [Option<f64>; MAX_SYSTEMS],
    /// The all-in-view test.
    pub initial_test: TestStatistic,
    /// The test of the solution in force.
    pub test: TestStatistic,
    pub satellites: heapless::Vec<SatelliteResult, N>,
    /// The satellite the rule identified on the all-in-view solution when
    /// the test failed.
    pub identified: Option<SatId>,
    /// Exclusion steps. They are in force only when `decision` is
    /// `Excluded` (or `Unavailable` after exclusion).
    pub exclusions: heapless::Vec<Exclusion, MAX_EXCLUSIONS>,
    pub protection: ProtectionLevels,
    pub worst_h: Option<SatId>,
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
    pub iterations: u32,
}

/// The integrity monitor. `N` is the satellite capacity (default 32); all
/// buffers are `[f64; N]`-sized and live on the stack.
#[derive(Debug, Clone, Default)]
pub struct Raim<const N: usize = 32> {
    thresholds: Thresholds<N>,
}

impl<const N: usize> Raim<N> {
    pub fn new() -> Self {
        Raim { thresholds: Thresholds::default() }
    }

    /// The chi-square threshold T^2 and lambda_md for a dof (cached).
    pub fn thresholds(&mut self, cfg: &Config, dof: usize) -> Result<(f64, f64), RaimError> {
        self.thresholds.get(cfg.pfa, cfg.pmd, dof)
    }

    /// Process one epoch: the snapshot test, identification, FDE and PLs.
    pub fn process(&mut self, cfg: &Config, epoch: &Epoch<'_>) -> Result<EpochResult<N>, RaimError> {
        cfg.validate()?;
        validate::<N>(epoch)?;
        let mut mask = [false; N];
        for v in mask.iter_mut().take(epoch.len()) {
            *v = true;
        }
        let first = solve::<N>(cfg, epoch, &mask)?;
        let initial_test = fde::test(cfg, &mut self.thresholds, &first)?;
        let satellites = per_satellite(cfg, &first);
        let outcome = fde::run(cfg, &mut self.thresholds, epoch, first)?;
        let sol = &outcome.solution;
        let dof = sol.parity.dof();
        let (_, lambda_md) = self.thresholds.get(cfg.pfa, cfg.pmd, dof)?;
        let protection = protection::slope_levels(&sol.parity, lambda_md, cfg.min_s_ii);
        let pl_available = protection.hpl_m <= cfg.alert.hal_m
            && cfg.alert.val_m.is_none_or(|val| protection.vpl_m <= val);
        let excluded = |id: SatId| outcome.exclusions.iter().any(|e| e.id == id);
        let passes = !outcome.test.alarm();
        let decision = match (passes, outcome.exclusions.is_empty(), pl_available) {
            (false, _, _) => Decision::Alarm,
            (true, _, false) => Decision::Unavailable,
            (true, true, true) => Decision::Ok,
            (true, false, true) => Decision::Excluded,
        };
        let mut satellites = satellites;
        if passes {
            for s in satellites.iter_mut() {
                s.used = !excluded(s.id);
            }
        }
        let id_at = |row: Option<usize>| row.and_then(|r| sol.ids.get(r).copied());
        Ok(EpochResult {
            time_s: epoch.time_s,
            decision,
            alarm_cause: if passes { None } else { outcome.cause },
            position_ecef_m: sol.position_ecef_m,
            geodetic: sol.geodetic,
            correction_enu_m: sol.correction_enu_m,
            clock_m: sol.clock_m,
            initial_test,
            test: outcome.test,
            satellites,
            identified: outcome.identified,
            worst_h: id_at(protection.worst_h_row),
            worst_v: id_at(protection.worst_v_row),
            protection,
            sigma_enu_m: protection::sigma_enu_m(&sol.parity),
            lambda_md,
            detection_available: dof >= 1,
            exclusion_available: dof >= 2,
            pl_available,
            iterations: sol.iterations,
            exclusions: outcome.exclusions,
        })
    }
}

fn per_satellite<const N: usize>(cfg: &Config, sol: &Solution<N>) -> heapless::Vec<SatelliteResult, N> {
    let mut out = heapless::Vec::new();
    let p = &sol.parity;
    let rows = p
        .residuals()
        .iter()
        .zip(p.s_ii())
        .zip(sol.ids.iter())
        .zip(sol.sigma_m.iter())
        .zip(sol.elevation_rad.iter());
    for ((((&r, &s), &id), &sigma), &el) in rows {
        let c = lraim::score(cfg.rule, r, s, cfg.min_s_ii);
        let (w, bias) = if s > 0.0 {
            (r / libm::sqrt(s), r / s * sigma)
        } else {
            (f64::NAN, f64::NAN)
        };
        // Capacity N equals the solution's row capacity, so push cannot fail.
        let _ = out.push(SatelliteResult {
            id,
            used: true,
            sigma_m: sigma,
            elevation_rad: el,
            s_ii: s,
            h_ii: 1.0 - s,
            w,
            bias_m: bias,
            score: c.map_or(f64::NAN, |c| c.score),
            identifiable: c.is_some(),
        });
    }
    out
}
