//! The sequential monitor (SPEC §7): the snapshot test and the Crosier
//! MCUSUM on the same parity vector, the satellites held excluded after an
//! MCUSUM alarm, and identification and exclusion from the accumulated
//! vector. Its state is the MCUSUM's (accumulated vector and holds); the
//! snapshot engine it runs on is passed in.

pub mod mcusum;
#[rustfmt::skip]
pub mod mcusum_table;

use crate::config::Config;
use crate::error::RaimError;
use crate::measurement::{Epoch, LinearObservation, Observations, RangeObservation, SatId};
use crate::real::{Real, Stat};
use crate::result::{Decision, EpochResult, SatelliteResult};
use crate::snapshot::detection::TestStatistic;
use crate::snapshot::fde::{self, AlarmCause, Exclusion, FdeOutcome, MAX_EXCLUSIONS};
use crate::snapshot::lraim::Candidate;
use crate::snapshot::{protection, Snapshot};
use crate::solve::{solve_into, Solution};
use mcusum::{Mcusum, MAX_HELD};

/// Which test raised the epoch's alarm (SPEC §7.4: alarm if D_snap >= T or
/// D_t >= h).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum AlarmSource {
    #[default]
    /// No alarm.
    None,
    /// The all-in-view snapshot test (D^2 >= T^2).
    Snapshot,
    /// The MCUSUM (D_t >= h).
    Cusum,
    /// The snapshot test and the MCUSUM together.
    Both,
}

/// The MCUSUM part of an epoch's result (SPEC §7).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct McusumReport {
    /// D_t = ||S_t|| before any exclusion this epoch (sigma units).
    pub statistic: f64,
    /// The alarm threshold h for this epoch's dimension (NaN if none).
    pub threshold: f64,
    /// The reference value k (sigma units).
    pub k: f64,
    /// C_t = ||S_(t-1) + y_t||.
    pub c: f64,
    /// Parity dimension d of the solution the MCUSUM ran on.
    pub dim: u32,
    /// ||S_(t-1)|| after the transport into this epoch's parity space.
    pub prior_norm: f64,
    /// False when the state restarted at 0 this epoch (reset mode on a set
    /// change, or no threshold for the dimension).
    pub carried: bool,
    /// D_t >= h.
    pub alarm: bool,
    /// Which test alarmed this epoch.
    pub source: AlarmSource,
    /// The satellite identified from the accumulated vector after an MCUSUM
    /// alarm (MLE rule on v = U2 S_t, see `Mcusum::identify`).
    pub identified: Option<SatId>,
    /// D after the identified satellite's row was removed from the state.
    pub after_exclusion: Option<f64>,
    /// Satellites held excluded after MCUSUM alarms (this one included).
    pub held: [Option<SatId>; MAX_HELD],
    /// False when the table has no threshold for this dimension (d > MAX_DIM):
    /// the MCUSUM did not run and its state was reset.
    pub available: bool,
}

/// The sequential engine: the MCUSUM state carried between epochs, and
/// the scratch for an epoch without its held satellites.
#[derive(Debug, Clone)]
pub struct Sequential<const N: usize, T: Real = Stat> {
    pub(crate) mcusum: Mcusum<N, T>,
    held_out: HeldOut<N>,
}

/// Scratch, not state: the input of an epoch with the held satellites left
/// out (one of the two arrays, the first `n` entries), and the input index
/// of each kept satellite. Here rather than on the stack (the
/// epochs after an MCUSUM exclusion were the firmware's deepest, 15.7 KB at
/// N = 32, of which 2 KB was this copy).
#[derive(Debug, Clone)]
struct HeldOut<const N: usize> {
    ranges: [RangeObservation; N],
    linear: [LinearObservation; N],
    src: [usize; N],
}

impl<const N: usize> HeldOut<N> {
    const fn new() -> Self {
        HeldOut {
            ranges: [RangeObservation::DEFAULT; N],
            linear: [LinearObservation::DEFAULT; N],
            src: [0; N],
        }
    }
}

impl<const N: usize, T: Real> Default for Sequential<N, T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, T: Real> Sequential<N, T> {
    /// A monitor with a zero MCUSUM state.
    pub const fn new() -> Self {
        Sequential {
            mcusum: Mcusum::new(),
            held_out: HeldOut::new(),
        }
    }
    /// Snapshot test + MCUSUM (SPEC §7.4). Satellites held excluded after
    /// earlier MCUSUM alarms are left out of the epoch first. The result
    /// is written into `out` and the FDE outcome (the solution in force)
    /// into caller storage, which is reset here (nothing result- or
    /// solution-sized on the stack; the monitor keeps both in its own
    /// state).
    pub(crate) fn process_into(
        &mut self,
        snap: &mut Snapshot<N, T>,
        cfg: &Config,
        epoch: &Epoch<'_>,
        outcome: &mut FdeOutcome<N, T>,
        out: &mut EpochResult<N>,
    ) -> Result<(), RaimError> {
        // Before any state changes: a refused epoch leaves it as it was.
        self.mcusum.check_time(epoch.time_s)?;
        self.mcusum.take_time(epoch.time_s);
        outcome.reset();
        let present = |id: SatId| (0..epoch.len()).any(|i| epoch.id(i) == Some(id));
        self.mcusum
            .release(epoch.time_s, cfg.mcusum.hold_s, present);
        if !self.mcusum.held().is_empty() {
            let filtered = match epoch.observations {
                Observations::Linear { sats } => {
                    self.without_held_linear(snap, cfg, epoch.time_s, sats, outcome, out)
                }
                Observations::Ranges { sats, apriori_m } => self.without_held_ranges(
                    snap,
                    cfg,
                    (epoch.time_s, sats, apriori_m),
                    outcome,
                    out,
                ),
            };
            match filtered {
                Err(RaimError::TooFewSatellites { .. }) | Err(RaimError::RankDeficient { .. }) => {
                    // The holds leave no solvable set: release them rather
                    // than lose the epoch (the snapshot test still guards).
                    self.mcusum.clear();
                    self.mcusum.take_time(epoch.time_s);
                    outcome.reset();
                }
                other => return other,
            }
        }
        let mut identity = [0usize; N];
        for (i, v) in identity.iter_mut().enumerate() {
            *v = i;
        }
        Self::sequential_on(
            &mut self.mcusum,
            snap,
            cfg,
            epoch,
            &identity,
            epoch,
            outcome,
            out,
        )
    }

    #[inline(never)]
    fn without_held_linear(
        &mut self,
        snap: &mut Snapshot<N, T>,
        cfg: &Config,
        time_s: f64,
        sats: &[LinearObservation],
        outcome: &mut FdeOutcome<N, T>,
        out: &mut EpochResult<N>,
    ) -> Result<(), RaimError> {
        let Sequential { mcusum, held_out } = self;
        let (buf, src) = (&mut held_out.linear, &mut held_out.src);
        let n = keep_unheld(mcusum, sats.iter().map(|s| s.id), |k, i| {
            if let (Some(b), Some(o)) = (buf.get_mut(k), sats.get(i)) {
                *b = *o;
            }
            if let Some(v) = src.get_mut(k) {
                *v = i;
            }
        });
        src.iter_mut().skip(n).for_each(|v| *v = 0);
        let Some(kept) = buf.get(..n) else {
            return Err(RaimError::CapacityExceeded {
                have: n,
                capacity: N,
            });
        };
        let e = Epoch::linear(time_s, kept);
        let input = Epoch::linear(time_s, sats);
        Self::sequential_on(mcusum, snap, cfg, &e, src, &input, outcome, out)
    }

    #[inline(never)]
    fn without_held_ranges(
        &mut self,
        snap: &mut Snapshot<N, T>,
        cfg: &Config,
        (time_s, sats, apriori_m): (f64, &[RangeObservation], Option<[f64; 3]>),
        outcome: &mut FdeOutcome<N, T>,
        out: &mut EpochResult<N>,
    ) -> Result<(), RaimError> {
        let Sequential { mcusum, held_out } = self;
        let (buf, src) = (&mut held_out.ranges, &mut held_out.src);
        let n = keep_unheld(mcusum, sats.iter().map(|s| s.id), |k, i| {
            if let (Some(b), Some(o)) = (buf.get_mut(k), sats.get(i)) {
                *b = *o;
            }
            if let Some(v) = src.get_mut(k) {
                *v = i;
            }
        });
        src.iter_mut().skip(n).for_each(|v| *v = 0);
        let Some(kept) = buf.get(..n) else {
            return Err(RaimError::CapacityExceeded {
                have: n,
                capacity: N,
            });
        };
        let e = Epoch::ranges(time_s, kept, apriori_m);
        let input = Epoch::ranges(time_s, sats, apriori_m);
        Self::sequential_on(mcusum, snap, cfg, &e, src, &input, outcome, out)
    }

    /// The snapshot monitor on `epoch` (the input without held satellites;
    /// `src[k]` is the input index of its satellite k), then the MCUSUM on
    /// the solution in force, and identification + exclusion after an
    /// MCUSUM alarm. The result is written into `result`; `outcome` (reset
    /// on entry) holds the snapshot monitor's solution in force.
    #[allow(clippy::too_many_arguments)] // the engines, the epoch twice and the two caller-owned outputs
    fn sequential_on(
        mcusum: &mut Mcusum<N, T>,
        snap: &mut Snapshot<N, T>,
        cfg: &Config,
        epoch: &Epoch<'_>,
        src: &[usize; N],
        input: &Epoch<'_>,
        outcome: &mut FdeOutcome<N, T>,
        result: &mut EpochResult<N>,
    ) -> Result<(), RaimError> {
        let mc = cfg.mcusum;
        snap.run(cfg, epoch, outcome, result)?;
        let sol = &outcome.solution;
        // k < N: an exclusion's index is a satellite of `epoch`, which
        // holds at most N (the monitor validated the input epoch), so the
        // fallback (the index unchanged) is never taken.
        let to_input = |k: usize| src.get(k).copied().unwrap_or(k);
        for e in result.exclusions.iter_mut() {
            e.index = to_input(e.index);
        }
        let rows = sol.rows();
        #[allow(clippy::indexing_slicing)] // rows <= N, a parity's rows
        let ids = &sol.ids[..rows.min(N)];
        let dim = sol.parity.dof();
        let snapshot_alarm = result.initial_test.alarm();
        let mut report = McusumReport {
            k: mc.k,
            dim: dim as u32,
            ..McusumReport::default()
        };
        let weight = mcusum.observation_weight(epoch.time_s, mc.correlation_time_s);
        match mcusum::threshold(dim, mc.k, mc.arl0) {
            Err(_) => {
                mcusum.reset();
                report.threshold = f64::NAN;
                report.statistic = f64::NAN;
                report.c = f64::NAN;
            }
            Ok(h) => {
                let step = mcusum.update_weighted(ids, &sol.parity, mc.k, mc.carry, h, weight);
                report.available = true;
                report.threshold = h;
                report.statistic = step.statistic;
                report.c = step.c;
                report.prior_norm = step.prior_norm;
                report.carried = step.carried;
                report.alarm = !(step.statistic < h);
            }
        }
        if report.alarm {
            Self::after_cusum_alarm(
                mcusum,
                snap,
                cfg,
                epoch,
                &to_input,
                sol,
                result,
                &mut report,
            )?;
        }
        report.source = match (snapshot_alarm, report.alarm) {
            (false, false) => AlarmSource::None,
            (true, false) => AlarmSource::Snapshot,
            (false, true) => AlarmSource::Cusum,
            (true, true) => AlarmSource::Both,
        };
        for (slot, h) in report.held.iter_mut().zip(mcusum.held().iter()) {
            *slot = Some(h.id);
        }
        // Satellites of the input that were held out are listed, unused.
        for i in 0..input.len() {
            let Some(id) = input.id(i) else { continue };
            if mcusum.is_held(id) && !result.satellites.iter().any(|s| s.id == id) {
                // A full list (N satellites) has no room for the rest of
                // the held-out satellites: they stay held, unlisted.
                if result
                    .satellites
                    .push(SatelliteResult {
                        id,
                        used: false,
                        sigma_m: f64::NAN,
                        elevation_rad: f64::NAN,
                        s_ii: f64::NAN,
                        h_ii: f64::NAN,
                        w: f64::NAN,
                        bias_m: f64::NAN,
                        score: f64::NAN,
                        identifiable: false,
                    })
                    .is_err()
                {
                    break;
                }
            }
        }
        result.mcusum = Some(report);
        Ok(())
    }

    /// After D_t >= h: identify from the accumulated vector, exclude the
    /// satellite (re-solve and re-test the subset, as FDE does), hold it
    /// excluded, and carry the state into the subset's parity space, which
    /// removes the identified fault's accumulated component (reset mode:
    /// restart at 0). Without redundancy or identification the alarm stands
    /// and the CUSUM restarts, as a CUSUM does after it signals.
    /// Not inlined: its subset solution then occupies stack only in the
    /// epochs that need it.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)] // the engine, the epoch and its solution, and the two results it edits
    fn after_cusum_alarm(
        mcusum: &mut Mcusum<N, T>,
        snap: &mut Snapshot<N, T>,
        cfg: &Config,
        epoch: &Epoch<'_>,
        to_input: &dyn Fn(usize) -> usize,
        sol: &Solution<N, T>,
        result: &mut EpochResult<N>,
        report: &mut McusumReport,
    ) -> Result<(), RaimError> {
        let snapshot_failed = result.decision == Decision::Alarm;
        let stand = |result: &mut EpochResult<N>, cause: AlarmCause| {
            result.decision = Decision::Alarm;
            if result.alarm_cause.is_none() {
                result.alarm_cause = Some(cause);
            }
        };
        let (cand, id, fidx) = match exclusion_candidate(mcusum, cfg, sol, report) {
            Ok(c) => c,
            Err(cause) => {
                stand(result, cause);
                mcusum.reset();
                return Ok(());
            }
        };
        let mut mask = [false; N];
        for (r, &k) in sol.source.iter().enumerate().take(sol.rows()) {
            if r != cand.row {
                if let Some(m) = mask.get_mut(k) {
                    *m = true;
                }
            }
        }
        let mut sub = Solution::<N, T>::empty();
        match solve_into(cfg, epoch, &mask, &mut sub) {
            Ok(()) => {}
            Err(RaimError::RankDeficient { .. }) | Err(RaimError::TooFewSatellites { .. }) => {
                stand(result, AlarmCause::SubsetGeometry { excluded: id });
                mcusum.reset();
                return Ok(());
            }
            Err(e) => return Err(e),
        };
        mcusum.hold(id, epoch.time_s);
        #[allow(clippy::indexing_slicing)] // rows <= N, a parity's rows
        let sub_ids = &sub.ids[..sub.rows().min(N)];
        report.after_exclusion = Some(mcusum.carry_to(sub_ids, &sub.parity, cfg.mcusum.carry));
        if snapshot_failed {
            // The snapshot alarm stands this epoch; the hold applies from the next.
            return Ok(());
        }
        let after = fde::test(cfg, &mut snap.thresholds, &sub)?;
        // cand.row < N: `sol.ids.get(cand.row)` found its satellite above.
        let nan = T::of(f64::NAN);
        let sigma = sol.sigma_m.get(cand.row).copied().unwrap_or(f64::NAN);
        let r_j = sol.parity.residuals().get(cand.row).copied().unwrap_or(nan);
        let s_jj = sol.parity.s_ii().get(cand.row).copied().unwrap_or(nan);
        let record = Exclusion {
            id,
            index: to_input(fidx),
            before: result.test,
            after,
            score: cand.score.to_f64(),
            bias_m: (r_j / s_jj).to_f64() * sigma,
        };
        // The snapshot FDE may have used every slot already: refused with
        // the capacity rather than dropped.
        result
            .exclusions
            .push(record)
            .map_err(|_| RaimError::CapacityExceeded {
                have: MAX_EXCLUSIONS + 1,
                capacity: MAX_EXCLUSIONS,
            })?;
        publish_subset(cfg, snap, &sub, after, result)
    }
}

/// The MCUSUM's exclusion candidate after its alarm (SPEC §7.4): the
/// best-identified row with its satellite and input index, noted in
/// `report`. Refused with the alarm's cause when nothing is identifiable,
/// when the geometry has no redundancy left (dof < 2), or when the
/// runner-up's score is within `mcusum::AMBIGUITY_RATIO` of the best's (two
/// fault directions explain the accumulated vector about equally well:
/// alarm rather than guess, as FDE does).
fn exclusion_candidate<const N: usize, T: Real>(
    mcusum: &Mcusum<N, T>,
    cfg: &Config,
    sol: &Solution<N, T>,
    report: &mut McusumReport,
) -> Result<(Candidate<T>, SatId, usize), AlarmCause> {
    let (best, second) = mcusum.identify(&sol.parity, cfg.min_s_ii);
    let best = best.and_then(|b| Some((b, *sol.ids.get(b.row)?, *sol.source.get(b.row)?)));
    report.identified = best.map(|(_, id, _)| id);
    let runner_up = second.and_then(|s| Some((s, *sol.ids.get(s.row)?)));
    let Some((cand, id, fidx)) = best else {
        return Err(AlarmCause::Unidentifiable);
    };
    if sol.parity.dof() < 2 {
        return Err(AlarmCause::NoRedundancy);
    }
    if let Some((s2, id2)) = runner_up {
        if !(s2.score < T::of(mcusum::AMBIGUITY_RATIO) * cand.score) {
            return Err(AlarmCause::Ambiguous {
                best: id,
                runner_up: id2,
            });
        }
    }
    Ok((cand, id, fidx))
}

/// The epoch's result from the subset without the MCUSUM's satellite,
/// whose test `after` passed or not: the decision (Excluded, Unavailable
/// when the subset's PLs exceed the alert limits, Alarm when it still
/// fails), its position, clocks, PLs (SPEC §9) and the satellites used.
fn publish_subset<const N: usize, T: Real>(
    cfg: &Config,
    snap: &mut Snapshot<N, T>,
    sub: &Solution<N, T>,
    after: TestStatistic,
    result: &mut EpochResult<N>,
) -> Result<(), RaimError> {
    let dof = sub.parity.dof();
    let (_, lambda_md) = snap.thresholds.get(cfg.pfa, cfg.pmd, dof)?;
    let protection = protection::slope_levels(&sub.parity, lambda_md, cfg.min_s_ii);
    let pl_available = protection.hpl_m <= cfg.alert.hal_m
        && cfg.alert.val_m.is_none_or(|val| protection.vpl_m <= val);
    let id_at = |row: Option<usize>| row.and_then(|r| sub.ids.get(r).copied());
    result.decision = match (!after.alarm(), pl_available) {
        (false, _) => Decision::Alarm,
        (true, false) => Decision::Unavailable,
        (true, true) => Decision::Excluded,
    };
    result.alarm_cause = None;
    result.position_ecef_m = sub.position_ecef_m;
    result.geodetic = sub.geodetic;
    result.correction_enu_m = sub.correction_enu_m;
    result.clock_m = sub.clock_m;
    result.test = after;
    result.worst_h = id_at(protection.worst_h_row);
    result.worst_v = id_at(protection.worst_v_row);
    result.protection = protection;
    result.sigma_enu_m = protection::sigma_enu_m(&sub.parity);
    result.lambda_md = lambda_md;
    result.detection_available = dof >= 1;
    result.exclusion_available = dof >= 2;
    result.pl_available = pl_available;
    let in_sub = |sid: SatId| sub.ids.iter().take(sub.rows()).any(|&x| x == sid);
    for s in result.satellites.iter_mut() {
        s.used = in_sub(s.id);
    }
    Ok(())
}

/// Calls `keep(k, i)` for the k-th input satellite i that `mcusum` does not
/// hold; returns the count.
fn keep_unheld<const N: usize, T: Real>(
    mcusum: &Mcusum<N, T>,
    ids: impl Iterator<Item = SatId>,
    mut keep: impl FnMut(usize, usize),
) -> usize {
    let mut k = 0;
    for (i, id) in ids.enumerate() {
        if !mcusum.is_held(id) {
            keep(k, i);
            k += 1;
        }
    }
    k
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod seq_cov_tests;
