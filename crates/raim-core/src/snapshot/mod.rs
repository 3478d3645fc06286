//! The snapshot monitor (SPEC §3-6): detect with the parity-space test,
//! identify (MLE or L-RAIM), exclude and re-test (FDE), and protect (slope
//! PLs). Its only state is the per-dof threshold cache.

pub mod detection;
pub mod fde;
pub mod lraim;
pub mod protection;
pub mod threshold_table;

use crate::config::{Config, FdeMethod};
use crate::error::RaimError;
use crate::measurement::{Epoch, SatId};
use crate::real::{Real, Stat};
use crate::result::{Decision, EpochResult, SatelliteResult};
use crate::solve::{solve_from, Fix, Solution, Start};
use detection::Thresholds;
use fde::FdeOutcome;

/// A warm start is used only if the last fix is at most this old (s): at
/// 300 m/s, 60 s is 18 km, still far inside Gauss-Newton's convergence
/// region, and a stale fix is never worse than the Earth's centre.
pub const WARM_START_MAX_AGE_S: f64 = 60.0;

/// The snapshot engine: one epoch in, one result out; it keeps the
/// chi-square thresholds per dof between epochs and, when enabled, the last
/// fix for a Gauss-Newton warm start. `T` is the precision of the
/// statistics path (docs/CORE.md, "Precision").
#[derive(Debug, Clone)]
pub struct Snapshot<const N: usize, T: Real = Stat> {
    pub(crate) thresholds: Thresholds<N>,
    warm_start: bool,
    last_fix: Option<Fix>,
    /// The reconstruction FDE's scratch (not state), here rather than on
    /// the stack.
    multifault: crate::multifault::Scratch<N, T>,
    _precision: core::marker::PhantomData<T>,
}

impl<const N: usize, T: Real> Default for Snapshot<N, T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, T: Real> Snapshot<N, T> {
    /// A snapshot engine with empty scratch.
    pub const fn new() -> Self {
        Snapshot {
            thresholds: Thresholds::empty(),
            warm_start: false,
            last_fix: None,
            multifault: crate::multifault::Scratch::empty(),
            _precision: core::marker::PhantomData,
        }
    }

    /// Start Gauss-Newton from the last epoch's solution (when it is at
    /// most [`WARM_START_MAX_AGE_S`] old) instead of the a-priori position.
    /// Off by default: with it, an epoch's answer depends on the previous
    /// epoch at the `convergence_m` level, so two engines fed different
    /// histories (a lost frame on the link, a host reference run epoch by
    /// epoch) are no longer bit-exact (docs/CORE.md, "Do the work once").
    pub fn set_warm_start(&mut self, on: bool) {
        self.warm_start = on;
        if !on {
            self.last_fix = None;
        }
    }

    fn start(&self, time_s: f64) -> Start<'static, N, T> {
        match self.last_fix {
            Some(f) if self.warm_start && libm::fabs(time_s - f.time_s) <= WARM_START_MAX_AGE_S => {
                Start::Fix(f)
            }
            _ => Start::Cold,
        }
    }

    /// The chi-square threshold T^2 and lambda_md for a dof (cached).
    pub fn thresholds(&mut self, cfg: &Config, dof: usize) -> Result<(f64, f64), RaimError> {
        self.thresholds.get(cfg.pfa, cfg.pmd, dof)
    }

    /// One epoch through the snapshot monitor. The caller has validated
    /// `cfg` and `epoch` (see [`crate::Raim::process`]).
    pub fn process(
        &mut self,
        cfg: &Config,
        epoch: &Epoch<'_>,
    ) -> Result<EpochResult<N>, RaimError> {
        let mut outcome = FdeOutcome::empty();
        let mut result = EpochResult::empty();
        self.run(cfg, epoch, &mut outcome, &mut result)?;
        Ok(result)
    }

    /// The snapshot monitor (SPEC §3-6): the result written into `out`
    /// (every field; on an error its contents are unspecified); the
    /// solution in force is left in `outcome.solution`, which must be
    /// `FdeOutcome::empty()` on entry. Caller storage: nothing solution- or
    /// result-sized is on this frame or returned by value, for the
    /// firmware's stack.
    pub(crate) fn run(
        &mut self,
        cfg: &Config,
        epoch: &Epoch<'_>,
        outcome: &mut FdeOutcome<N, T>,
        out: &mut EpochResult<N>,
    ) -> Result<(), RaimError> {
        let mut mask = [false; N];
        for v in mask.iter_mut().take(epoch.len()) {
            *v = true;
        }
        let start = self.start(epoch.time_s);
        solve_from(cfg, epoch, &mask, start, &mut outcome.solution)?;
        let initial_test = fde::test(cfg, &mut self.thresholds, &outcome.solution)?;
        // FDE ranks the all-in-view solution only if its test fails.
        let best = per_satellite(
            cfg,
            &outcome.solution,
            &mut out.satellites,
            initial_test.alarm(),
        );
        let multifault = match cfg.fde_method {
            FdeMethod::Sequential => {
                outcome.first_best = Some(best);
                fde::run(cfg, &mut self.thresholds, epoch, outcome)?;
                None
            }
            FdeMethod::Reconstruction {
                t_max,
                group_budget,
            } => crate::multifault::run(
                cfg,
                t_max,
                group_budget,
                &mut self.thresholds,
                epoch,
                outcome,
                &mut self.multifault,
            )?,
        };
        let sol = &outcome.solution;
        if self.warm_start {
            self.last_fix = Fix::of(epoch.time_s, sol).or(self.last_fix);
        }
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
        // `per_satellite` marked every row used; only exclusions change that
        // (the search per row, on every
        // clean epoch, found nothing to change).
        if passes && !outcome.exclusions.is_empty() {
            for s in out.satellites.iter_mut() {
                s.used = !excluded(s.id);
            }
        }
        let id_at = |row: Option<usize>| row.and_then(|r| sol.ids.get(r).copied());
        out.time_s = epoch.time_s;
        out.decision = decision;
        out.alarm_cause = if passes { None } else { outcome.cause };
        out.position_ecef_m = sol.position_ecef_m;
        out.geodetic = sol.geodetic;
        out.correction_enu_m = sol.correction_enu_m;
        out.clock_m = sol.clock_m;
        out.initial_test = initial_test;
        out.test = outcome.test;
        out.identified = outcome.identified;
        out.worst_h = id_at(protection.worst_h_row);
        out.worst_v = id_at(protection.worst_v_row);
        out.protection = protection;
        out.sigma_enu_m = protection::sigma_enu_m(&sol.parity);
        out.lambda_md = lambda_md;
        out.detection_available = dof >= 1;
        out.exclusion_available = dof >= 2;
        out.pl_available = pl_available;
        out.iterations = sol.iterations;
        out.exclusions.clone_from(&outcome.exclusions);
        out.mcusum = None;
        out.multifault = multifault;
        Ok(())
    }
}

/// The per-satellite output, computed in `T` and widened to f64, written
/// into `out` (cleared first). With `rank`, returns the rule's best
/// candidate, as [`lraim::rank`] on `sol` would (the same scores, offered
/// in row order); without, `None`.
pub(crate) fn per_satellite<const N: usize, T: Real>(
    cfg: &Config,
    sol: &Solution<N, T>,
    out: &mut heapless::Vec<SatelliteResult, N>,
    rank: bool,
) -> Option<lraim::Candidate<T>> {
    out.clear();
    let p = &sol.parity;
    let min_s_ii = T::of(cfg.min_s_ii);
    let rows = p
        .residuals()
        .iter()
        .zip(p.s_ii())
        .zip(sol.ids.iter())
        .zip(sol.sigma_m.iter())
        .zip(sol.elevation_rad.iter());
    // The rule's logarithms first, in a loop of their own (fourth
    // pass: inside the loop below, each `log1p` call spilled and reloaded
    // its dozen live values); the scores from them are [`lraim::score`]'s
    // bit for bit.
    let mut logs = [T::zero(); N];
    for (l, &s) in logs.iter_mut().zip(p.s_ii()) {
        if s >= min_s_ii {
            *l = lraim::log_term(cfg.rule, s);
        }
    }
    let mut ranking = lraim::Ranking::new();
    for (row, (((((&r, &s), &id), &sigma), &el), &log)) in rows.zip(logs.iter()).enumerate() {
        let c = (s >= min_s_ii).then(|| lraim::score_with(cfg.rule, r, s, log));
        if let (Some(mut c), true) = (c, rank) {
            c.row = row;
            ranking.offer(c);
        }
        let (w, bias) = if s > T::zero() {
            ((r / s.sqrt()).to_f64(), (r / s).to_f64() * sigma)
        } else {
            (f64::NAN, f64::NAN)
        };
        let pushed = out.push(SatelliteResult {
            id,
            used: true,
            sigma_m: sigma,
            elevation_rad: el,
            s_ii: s.to_f64(),
            h_ii: (T::one() - s).to_f64(),
            w,
            bias_m: bias,
            score: c.map_or(f64::NAN, |c| c.score.to_f64()),
            identifiable: c.is_some(),
        });
        // Cannot fill: capacity N equals the solution's row capacity.
        debug_assert!(pushed.is_ok());
    }
    ranking.best
}

#[cfg(test)]
mod tests;
