//! Multiple simultaneous faults by error reconstruction over constraint
//! groups (SPEC §8, seed 002), for up to three faults.
//!
//! - [`covering`]: the constraint groups, a covering design (exact table for
//!   small n, an on-device construction for any n).
//! - [`reconstruct`](mod@reconstruct): per group, e_F, its covariance and the seed's Q; per
//!   candidate set T, the whitened subset statistic RSS_T and the biases.
//! - [`search`] (here): every group within the budget, every candidate set
//!   of 1..t_max satellites they cover, the least and runner-up RSS_T per
//!   size; [`decide`]: the decision rule of SPEC §8.4 with the uniqueness
//!   check. [`fde`] runs it as the snapshot monitor's FDE method
//!   (`Config::fde_method`), excluding and re-testing with a real solve.
//!
//! Without the feature `multifault` (docs/FLASH.md) [`run`] refuses, and the
//! FDE's private helpers below it are compiled but never called.
#![cfg_attr(not(feature = "multifault"), allow(dead_code, unused_imports))]

pub mod covering;
mod covering_table;
pub mod error;
pub mod reconstruct;

#[cfg(test)]
mod run_tests;
#[cfg(test)]
mod tests;

use crate::config::Config;
use crate::error::RaimError;
use crate::measurement::{Epoch, SatId};
use crate::real::{Real, Stat};
use crate::snapshot::detection::{TestStatistic, Thresholds};
use crate::snapshot::fde::{self, AlarmCause, Exclusion, FdeOutcome};
use crate::solve::{solve_into, Solution};
use crate::stats::dist;
use covering::{for_each_subset, Covering, SatSet, MAX_FAULTS};
use error::MultifaultError;
use reconstruct::{fit_subset, reconstruct, GroupFit, ResidualModel, SubsetFit, Workspace};

/// The least and runner-up candidate sets of one size.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Level<T> {
    /// The least RSS_T of the sets of this size.
    pub best: Option<SubsetFit<T>>,
    /// The second least RSS_T of the same size.
    pub runner_up: Option<SubsetFit<T>>,
    /// Candidate sets evaluated at this size (each once, but for repairs
    /// and designs of more than 64 groups).
    pub evaluated: u32,
}

impl<T: Real> Default for Level<T> {
    fn default() -> Self {
        Level {
            best: None,
            runner_up: None,
            evaluated: 0,
        }
    }
}

impl<T: Real> Level<T> {
    /// Keeps the two least RSS_T among distinct sets.
    fn offer(&mut self, fit: SubsetFit<T>) {
        self.evaluated += 1;
        let same = |o: &Option<SubsetFit<T>>| o.is_some_and(|b| b.set == fit.set);
        if same(&self.best) || same(&self.runner_up) {
            return;
        }
        match self.best {
            Some(b) if !(fit.rss < b.rss) => {
                if self.runner_up.is_none_or(|r| fit.rss < r.rss) {
                    self.runner_up = Some(fit);
                }
            }
            _ => {
                self.runner_up = self.best;
                self.best = Some(fit);
            }
        }
    }
}

/// What the group search found (SPEC §8.3-8.4).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Search<T> {
    /// The candidate sets of 1, 2, 3 satellites.
    pub levels: [Level<T>; MAX_FAULTS],
    /// The largest fault count searched.
    pub t_max: usize,
    /// Groups in the covering design.
    pub groups_total: usize,
    /// Groups searched within the budget.
    pub groups_processed: usize,
    /// The group budget stopped the search before the last group.
    pub budget_limited: bool,
    /// Satellites moved into a constrained set for rank (summed over groups).
    pub swapped: u32,
    /// Candidate sets evaluated directly because a swap took one of their
    /// satellites out of a group's identifiable set (keeps the search
    /// complete: SPEC §8.3's "swap and say so").
    pub repaired: u32,
    /// The least Q over the groups and the group that has it.
    pub q_min: Option<(T, usize)>,
}

/// How many earlier groups the search remembers to evaluate each
/// candidate set once (beyond, repeats are evaluated again: harmless).
const EARLIER: usize = 64;

/// Runs the groups of `covering` (at most `budget`) over `model`: each
/// group's reconstruction and Q, and RSS_T for every set of 1..t_max
/// satellites inside its identifiable set. `on_group` sees every group's
/// reconstruction (the seed's table; reports).
#[allow(clippy::too_many_arguments)]
pub fn search<T: Real, const N: usize>(
    model: &ResidualModel<T, N>,
    covering: &Covering,
    t_max: usize,
    budget: usize,
    min_s_ii: T,
    ws: &mut Workspace<T, N>,
    group: &mut GroupFit<T, N>,
    on_group: impl FnMut(usize, &GroupFit<T, N>),
) -> Result<Search<T>, MultifaultError> {
    search_where(
        model,
        covering,
        t_max,
        budget,
        min_s_ii,
        ws,
        group,
        on_group,
        |_| true,
    )
}

/// [`search`] over the candidate sets that `keep` accepts only (the
/// cross-size uniqueness check: the sets that do not contain the set about
/// to be excluded).
#[allow(clippy::too_many_arguments)]
pub fn search_where<T: Real, const N: usize>(
    model: &ResidualModel<T, N>,
    covering: &Covering,
    t_max: usize,
    budget: usize,
    min_s_ii: T,
    ws: &mut Workspace<T, N>,
    group: &mut GroupFit<T, N>,
    mut on_group: impl FnMut(usize, &GroupFit<T, N>),
    keep: impl Fn(SatSet) -> bool,
) -> Result<Search<T>, MultifaultError> {
    if budget == 0 {
        return Err(MultifaultError::ZeroGroupBudget {
            field: "group_budget",
        });
    }
    covering::check(model.n(), covering.states(), t_max)?;
    if covering.satellites() != model.n() || t_max > covering.faults() {
        return Err(MultifaultError::TooManyFaults {
            t: t_max,
            n: model.n(),
            m: covering.states(),
            max: covering.faults(),
        });
    }
    let mut out = Search {
        levels: [Level::default(); MAX_FAULTS],
        t_max,
        groups_total: covering.len(),
        groups_processed: 0,
        budget_limited: covering.len() > budget,
        swapped: 0,
        repaired: 0,
        q_min: None,
    };
    let mut swapped_union: SatSet = 0;
    let mut any_identifiable = false;
    // The design's earlier groups (up to EARLIER of them): a set inside one
    // of them was evaluated there, or holds a satellite swapped out of it
    // and is evaluated by the repair pass below, so it is skipped here.
    let mut earlier = [0 as SatSet; EARLIER];
    for (i, f) in covering.groups().enumerate().take(budget) {
        #[allow(clippy::indexing_slicing)] // i.min(EARLIER) <= EARLIER, the length
        let seen = &earlier[..i.min(EARLIER)];
        let first_cover = |set: SatSet| !seen.iter().any(|g| set & !g == 0);
        reconstruct(model, f, min_s_ii, ws, group);
        out.groups_processed += 1;
        out.swapped += group.swapped.count_ones();
        swapped_union |= group.swapped;
        if group.identifiable != 0 {
            any_identifiable = true;
            if out.q_min.is_none_or(|(q, _)| group.q < q) {
                out.q_min = Some((group.q, i));
            }
        }
        on_group(i, group);
        for_each_subset(group.identifiable, t_max, |set| {
            if !keep(set) || !first_cover(set) {
                return;
            }
            if let Some(fit) = fit_subset(model, set) {
                if let Some(level) = out.levels.get_mut(fit.count - 1) {
                    level.offer(fit);
                }
            }
        });
        if let Some(slot) = earlier.get_mut(i) {
            *slot = f;
        }
    }
    if swapped_union != 0 {
        // A set lost its cover only if it holds a swapped satellite.
        let mut repaired = 0;
        for_each_subset(covering::all(model.n()), t_max, |set| {
            if set & swapped_union != 0 && keep(set) {
                if let Some(fit) = fit_subset(model, set) {
                    repaired += 1;
                    if let Some(level) = out.levels.get_mut(fit.count - 1) {
                        level.offer(fit);
                    }
                }
            }
        });
        out.repaired = repaired;
    }
    if !any_identifiable && out.levels.iter().all(|l| l.best.is_none()) {
        return Err(MultifaultError::NoIdentifiableGroup {
            n: model.n(),
            groups: out.groups_processed,
        });
    }
    Ok(out)
}

/// The decision of SPEC §8.4 over a [`Search`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Verdict<T> {
    /// The least RSS_T among sets of `count` satellites passes its
    /// chi-square quantile and no other set of that size explains the data
    /// at level pwe: exclude it.
    Exclude(SubsetFit<T>),
    /// The best set passes, but so does the runner-up at level pwe.
    Ambiguous {
        /// The set with the least RSS_T.
        best: SubsetFit<T>,
        /// The runner-up that also passes.
        runner_up: SubsetFit<T>,
    },
    /// The best set passes, but the group budget cut the search short, so
    /// the uniqueness check is incomplete.
    Incomplete(SubsetFit<T>),
    /// No candidate set of 1..t_max satellites passes.
    NoConsistentSet,
}

/// Chi-square thresholds at the level `p` for a dof, in f64.
pub fn chi2_threshold(p: f64, dof: usize) -> Result<f64, RaimError> {
    dist::chi2_quantile_upper(p, u32::try_from(dof).unwrap_or(u32::MAX))
}

/// The decision rule (SPEC §8.4), from size `from` upward: the fewest
/// faults that explain the data. For size t the least RSS_T is accepted if
/// RSS_T < chi2 quantile(1 - pfa; dof - t); then the runner-up of the same
/// size must reach the quantile at 1 - pwe, else `Ambiguous` (never a silent
/// pick). `unique` = false skips the runner-up and budget checks.
pub fn decide<T: Real>(
    s: &Search<T>,
    from: usize,
    dof: usize,
    pfa: f64,
    pwe: f64,
    unique: bool,
) -> Result<Verdict<T>, RaimError> {
    for (t, level) in s
        .levels
        .iter()
        .enumerate()
        .take(s.t_max)
        .skip(from.max(1) - 1)
    {
        let t = t + 1;
        if t + 1 > dof {
            break;
        }
        let Some(best) = level.best else { continue };
        let t2 = chi2_threshold(pfa, dof - t)?;
        if !(best.rss.to_f64() < t2) {
            continue;
        }
        if !unique {
            return Ok(Verdict::Exclude(best));
        }
        if let Some(runner_up) = level.runner_up {
            let t2_we = chi2_threshold(pwe, dof - t)?;
            if runner_up.rss.to_f64() < t2_we {
                return Ok(Verdict::Ambiguous { best, runner_up });
            }
        }
        if s.budget_limited {
            return Ok(Verdict::Incomplete(best));
        }
        return Ok(Verdict::Exclude(best));
    }
    Ok(Verdict::NoConsistentSet)
}

/// One candidate set in the per-epoch report, in physical units.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FaultSet {
    /// How many satellites (1..=3); the first `count` entries below hold.
    pub count: u8,
    /// The satellites of the set.
    pub satellites: [SatId; MAX_FAULTS],
    /// Bias estimates b_T, m, in the order of `satellites`.
    pub bias_m: [f64; MAX_FAULTS],
    /// RSS_T (chi-square units) and its dof n - m - |T|.
    pub rss: f64,
    /// Degrees of freedom of RSS_T, n - m - |T|.
    pub dof: u32,
}

/// The multiple-fault search's part of an epoch result (`fde_method =
/// Reconstruction`).
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct MultifaultReport {
    /// The fault count searched (t_max, reduced to n - m - 1 if needed).
    pub t_searched: u8,
    /// The set excluded (or, with an alarm, the best candidate).
    pub best: Option<FaultSet>,
    /// The runner-up of the same size.
    pub runner_up: Option<FaultSet>,
    /// Groups in the covering design.
    pub groups_total: u32,
    /// Groups searched within the budget.
    pub groups_processed: u32,
    /// The group budget limited the search (then no exclusion is made
    /// while `require_unique_exclusion` holds).
    pub budget_limited: bool,
    /// Satellites moved into constrained sets for rank, and candidate sets
    /// evaluated directly to keep the search complete.
    pub swapped: u32,
    /// Candidate sets evaluated directly to keep the search complete.
    pub repaired: u32,
    /// The seed's least Q over the groups, sigma^2 units.
    pub q_min: Option<f64>,
}

fn fault_set<T: Real, P: Real, const N: usize>(
    fit: &SubsetFit<T>,
    sol: &Solution<N, P>,
    dof: usize,
) -> FaultSet {
    let (rows, k) = covering::members(fit.set);
    let mut out = FaultSet {
        count: 0,
        satellites: [SatId::default(); MAX_FAULTS],
        bias_m: [0.0; MAX_FAULTS],
        rss: fit.rss.to_f64(),
        dof: dof.saturating_sub(fit.count) as u32,
    };
    for (row, b) in rows.iter().take(k.min(MAX_FAULTS)).zip(fit.bias.iter()) {
        let row = usize::from(*row);
        let slot = usize::from(out.count);
        if let (Some(id), Some(&sigma), Some(dst_id), Some(dst_b)) = (
            sol.ids.get(row),
            sol.sigma_m.get(row),
            out.satellites.get_mut(slot),
            out.bias_m.get_mut(slot),
        ) {
            *dst_id = *id;
            *dst_b = b.to_f64() * sigma;
            out.count += 1;
        }
    }
    out
}

/// The scratch the reconstruction FDE needs (about 2 N^2 + 4 N values of
/// `T` and one subset solution: ~21 KB at N = 32 in f64, ~11 KB in
/// f32). Scratch, not state: every field is overwritten before it is read
/// in each epoch. The snapshot engine keeps one (on the
/// firmware's stack it took the reconstruction epoch to 22.7 KB; in the
/// engine's own storage it costs static RAM instead, whichever FDE is
/// configured).
#[derive(Debug, Clone)]
pub struct Scratch<const N: usize, T: Real = Stat> {
    /// The whitened residual model of the epoch.
    pub model: ResidualModel<T, N>,
    /// Factorisation workspace of one group.
    pub ws: Workspace<T, N>,
    /// One group's e_F, covariance and Q.
    pub group: GroupFit<T, N>,
    /// The re-solved subset before it becomes the solution in force.
    pub solution: Solution<N, T>,
}

impl<const N: usize, T: Real> Default for Scratch<N, T> {
    fn default() -> Self {
        Self::empty()
    }
}

impl<const N: usize, T: Real> Scratch<N, T> {
    /// Empty scratch, to be filled by each search.
    pub const fn empty() -> Self {
        Scratch {
            model: ResidualModel::empty(),
            ws: Workspace::empty(),
            group: GroupFit::empty(),
            solution: Solution::empty(),
        }
    }
}

/// The search's fixed arguments, for the second pass.
struct SearchArgs<'a> {
    covering: &'a Covering,
    t_max: usize,
    budget: usize,
}

fn s_args(covering: &Covering, t_max: usize, budget: u16) -> SearchArgs<'_> {
    SearchArgs {
        covering,
        t_max,
        budget: usize::from(budget),
    }
}

/// The least-RSS set of more than `best.count` satellites that does not
/// contain `best.set` and is consistent at level pwe (its own dof), if any.
#[inline(never)]
fn larger_alternative<const N: usize, T: Real>(
    cfg: &Config,
    args: &SearchArgs<'_>,
    best: SubsetFit<T>,
    dof: usize,
    scratch: &mut Scratch<N, T>,
) -> Result<Option<SubsetFit<T>>, RaimError> {
    let found = search_where(
        &scratch.model,
        args.covering,
        args.t_max,
        args.budget,
        T::of(cfg.min_s_ii),
        &mut scratch.ws,
        &mut scratch.group,
        |_, _| {},
        |set| set.count_ones() as usize > best.count && set & best.set != best.set,
    );
    let Ok(found) = found else {
        return Ok(None);
    };
    for level in found.levels.iter().skip(best.count) {
        let Some(alt) = level.best else { continue };
        if alt.count + 1 > dof {
            continue;
        }
        let t2_we = chi2_threshold(cfg.pwe, dof - alt.count)?;
        if alt.rss.to_f64() < t2_we {
            return Ok(Some(alt));
        }
    }
    Ok(None)
}

/// [`run`] without the feature `multifault`: the search is not built, and
/// the call is refused with the configuration check's error (`t_max`
/// outside [0, 0]), which `Config::validate` has already returned for such
/// a configuration, so nothing falls back to another FDE silently.
#[cfg(not(feature = "multifault"))]
pub fn run<const N: usize, P: Real>(
    _cfg: &Config,
    t_max: u8,
    _group_budget: u16,
    _thresholds: &mut Thresholds<N>,
    _epoch: &Epoch<'_>,
    _out: &mut FdeOutcome<N, P>,
    _scratch: &mut Scratch<N, P>,
) -> Result<Option<MultifaultReport>, RaimError> {
    let not_built = crate::config_bounds::T_MAX_NOT_BUILT;
    Err(RaimError::OutOfRange {
        field: not_built.field,
        value: f64::from(t_max),
        min: not_built.min,
        max: not_built.max,
    })
}

/// FDE by reconstruction (SPEC §8.4) on `out`, whose `solution` holds the
/// all-in-view solution: detect; if the test fails, search the groups for
/// the fewest satellites (1..t_max) that explain the residuals, check the
/// runner-up, exclude, re-solve and re-test; if the subset still fails, go
/// on with more satellites. Fills the same outcome as [`fde::run`] (so the
/// snapshot result is built the same way) and returns the report.
#[cfg(feature = "multifault")]
#[inline(never)]
pub fn run<const N: usize, P: Real>(
    cfg: &Config,
    t_max: u8,
    group_budget: u16,
    thresholds: &mut Thresholds<N>,
    epoch: &Epoch<'_>,
    out: &mut FdeOutcome<N, P>,
    scratch: &mut Scratch<N, P>,
) -> Result<Option<MultifaultReport>, RaimError> {
    let Some(before) = detect(cfg, thresholds, out)? else {
        return Ok(None);
    };
    let Some((dof, t_eff)) = redundancy(cfg, t_max, out) else {
        return Ok(None);
    };
    let to_raim = |e: MultifaultError| multifault_error(e, t_max);
    let covering =
        Covering::new(out.solution.rows(), out.solution.parity.states(), t_eff).map_err(to_raim)?;
    let Some(s) =
        search_groups(cfg, &covering, t_eff, group_budget, out, scratch).map_err(to_raim)?
    else {
        return Ok(None);
    };
    let mut report = MultifaultReport {
        t_searched: t_eff as u8,
        best: None,
        runner_up: None,
        groups_total: s.groups_total as u32,
        groups_processed: s.groups_processed as u32,
        budget_limited: s.budget_limited,
        swapped: s.swapped,
        repaired: s.repaired,
        q_min: s.q_min.map(|(q, _)| q.to_f64()),
    };
    let incomplete = AlarmCause::SearchIncomplete {
        groups: s.groups_total as u32,
        budget: u32::from(group_budget),
    };
    // §8.4's decision, from the fewest satellites up: a candidate whose
    // subset still fails after the re-solve sends the search on to more.
    let mut from = 1;
    loop {
        let verdict = decide(
            &s,
            from,
            dof,
            cfg.pfa,
            cfg.pwe,
            cfg.require_unique_exclusion,
        )?;
        let sol = &out.solution;
        match verdict {
            Verdict::NoConsistentSet => {
                if s.budget_limited {
                    out.cause = Some(incomplete);
                } else if out.cause.is_none() {
                    out.cause = Some(AlarmCause::NoConsistentSet);
                }
                if let Some(best) = s.levels.iter().take(t_eff).rev().find_map(|l| l.best) {
                    report.best = Some(fault_set(&best, sol, dof));
                }
                break;
            }
            Verdict::Ambiguous { best, runner_up } => {
                report.best = Some(fault_set(&best, sol, dof));
                report.runner_up = Some(fault_set(&runner_up, sol, dof));
                let (identified, cause) = ambiguous_cause(sol, best.set, runner_up.set);
                if identified.is_some() {
                    out.identified = identified;
                }
                out.cause = Some(cause);
                break;
            }
            Verdict::Incomplete(best) => {
                report.best = Some(fault_set(&best, sol, dof));
                out.identified = first_id(sol, best.set);
                out.cause = Some(incomplete);
                break;
            }
            Verdict::Exclude(best) => {
                report.best = Some(fault_set(&best, sol, dof));
                let search = s_args(&covering, t_eff, group_budget);
                let step = Candidate {
                    best,
                    before,
                    dof,
                    t_eff,
                    levels: &s.levels,
                };
                match step.exclude(cfg, &search, thresholds, epoch, out, scratch, &mut report)? {
                    Some(next) => from = next,
                    None => break,
                }
            }
        }
    }
    Ok(Some(report))
}

/// Detection (SPEC §8.4): the all-in-view test into `out`, whose
/// exclusions, identification and cause are cleared. The test when it
/// alarms; None when it passes.
#[cfg(feature = "multifault")]
fn detect<const N: usize, P: Real>(
    cfg: &Config,
    thresholds: &mut Thresholds<N>,
    out: &mut FdeOutcome<N, P>,
) -> Result<Option<TestStatistic>, RaimError> {
    let before = fde::test(cfg, thresholds, &out.solution)?;
    out.test = before;
    out.exclusions.clear();
    out.identified = None;
    out.cause = None;
    Ok(before.alarm().then_some(before))
}

/// The redundancy the search needs: the parity dof (n - m) at least 2 and
/// the effective fault count ([`effective_t`]) at least 1, returned as
/// (dof, t); None, with the alarm cause in `out`, otherwise.
#[cfg(feature = "multifault")]
fn redundancy<const N: usize, P: Real>(
    cfg: &Config,
    t_max: u8,
    out: &mut FdeOutcome<N, P>,
) -> Option<(usize, usize)> {
    let dof = out.solution.parity.dof();
    if dof < 2 {
        out.cause = Some(AlarmCause::NoRedundancy);
        return None;
    }
    let t_eff = effective_t(cfg, t_max, dof);
    if t_eff == 0 {
        out.cause = Some(AlarmCause::MaxExclusions);
        return None;
    }
    Some((dof, t_eff))
}

/// The search's errors as the epoch's: a capacity stays one, anything
/// else is the configured `t_max` out of its range.
#[cfg(feature = "multifault")]
fn multifault_error(e: MultifaultError, t_max: u8) -> RaimError {
    match e {
        MultifaultError::CapacityExceeded { have, capacity } => {
            RaimError::CapacityExceeded { have, capacity }
        }
        _ => RaimError::OutOfRange {
            field: "t_max",
            value: f64::from(t_max),
            min: 1.0,
            max: MAX_FAULTS as f64,
        },
    }
}

/// The groups of SPEC §8.3 over the solution's residual model, the
/// reconstruction of §8.2 in each and §8.4's candidate sets of 1..t
/// satellites ([`search`]). None, with `Unidentifiable` in `out`, when no
/// group can be identified.
#[cfg(feature = "multifault")]
fn search_groups<const N: usize, P: Real>(
    cfg: &Config,
    covering: &Covering,
    t_eff: usize,
    group_budget: u16,
    out: &mut FdeOutcome<N, P>,
    scratch: &mut Scratch<N, P>,
) -> Result<Option<Search<P>>, MultifaultError> {
    scratch.model.fill_from_parity(&out.solution.parity)?;
    let found = search(
        &scratch.model,
        covering,
        t_eff,
        usize::from(group_budget),
        P::of(cfg.min_s_ii),
        &mut scratch.ws,
        &mut scratch.group,
        |_, _| {},
    );
    match found {
        Ok(s) => Ok(Some(s)),
        Err(MultifaultError::NoIdentifiableGroup { .. }) => {
            out.cause = Some(AlarmCause::Unidentifiable);
            Ok(None)
        }
        Err(e) => Err(e),
    }
}

/// Two sets explain the data: the satellite to name (the best set's own)
/// and the `Ambiguous` cause, or `Unidentifiable` when a set names no
/// satellite.
fn ambiguous_cause<const N: usize, P: Real>(
    sol: &Solution<N, P>,
    best: SatSet,
    other: SatSet,
) -> (Option<SatId>, AlarmCause) {
    match ambiguity(sol, best, other) {
        Some((b, r)) => (
            Some(b),
            AlarmCause::Ambiguous {
                best: b,
                runner_up: r,
            },
        ),
        None => (None, AlarmCause::Unidentifiable),
    }
}

/// A consistent candidate set of §8.4's decision, with what its exclusion
/// reads: the all-in-view test, the dof, the fault count searched and the
/// search's levels.
#[cfg(feature = "multifault")]
struct Candidate<'a, P> {
    best: SubsetFit<P>,
    before: TestStatistic,
    dof: usize,
    t_eff: usize,
    levels: &'a [Level<P>; MAX_FAULTS],
}

#[cfg(feature = "multifault")]
impl<P: Real> Candidate<'_, P> {
    /// §8.4's exclusion of the candidate: with a unique exclusion
    /// required, a larger consistent set that does not contain it is an
    /// `Ambiguous` alarm; otherwise the runner-up of its level is
    /// reported, the set excluded, the subset re-solved and re-tested
    /// ([`exclude_set`]). None when the decision is final; the next fault
    /// count to search from when the subset still fails.
    #[allow(clippy::too_many_arguments)] // the epoch, its outcome and the report
    fn exclude<const N: usize>(
        &self,
        cfg: &Config,
        search: &SearchArgs<'_>,
        thresholds: &mut Thresholds<N>,
        epoch: &Epoch<'_>,
        out: &mut FdeOutcome<N, P>,
        scratch: &mut Scratch<N, P>,
        report: &mut MultifaultReport,
    ) -> Result<Option<usize>, RaimError> {
        let best = self.best;
        let sol = &out.solution;
        if cfg.require_unique_exclusion && best.count < self.t_eff {
            // Larger sets always fit at least as well; one that does not
            // contain `best` and is consistent at level pwe is another
            // explanation of the data.
            if let Some(alt) = larger_alternative(cfg, search, best, self.dof, scratch)? {
                report.runner_up = Some(fault_set(&alt, sol, self.dof));
                out.identified = first_id(sol, best.set);
                out.cause = Some(ambiguous_cause(sol, best.set, alt.set).1);
                return Ok(None);
            }
        }
        if let Some(level) = self.levels.get(best.count - 1) {
            report.runner_up = level.runner_up.map(|r| fault_set(&r, sol, self.dof));
        }
        out.identified = first_id(sol, best.set);
        match exclude_set(cfg, thresholds, epoch, &best, self.before, out, scratch)? {
            Excluded::Done => Ok(None),
            Excluded::Subset(cause) => {
                if cause.is_some() {
                    out.cause = cause;
                }
                Ok(Some(best.count + 1))
            }
        }
    }
}

/// The most satellites this epoch may lose: t_max, the configured
/// exclusion cap, and n - m - 1 (a subset statistic needs a dof).
fn effective_t(cfg: &Config, t_max: u8, dof: usize) -> usize {
    usize::from(t_max)
        .min(usize::from(cfg.max_exclusions))
        .min(fde::MAX_EXCLUSIONS)
        .min(dof - 1)
        .min(MAX_FAULTS)
}

/// The first satellite of `set` among `sol`'s rows.
fn first_id<const N: usize, P: Real>(sol: &Solution<N, P>, set: SatSet) -> Option<SatId> {
    let (rows, _) = covering::members(set);
    rows.first()
        .and_then(|r| sol.ids.get(usize::from(*r)).copied())
}

/// Two candidate sets explain the data: a satellite only in each (the
/// set's first when it lies inside the other), for the `Ambiguous`
/// cause; None when a row has no satellite.
fn ambiguity<const N: usize, P: Real>(
    sol: &Solution<N, P>,
    best: SatSet,
    other: SatSet,
) -> Option<(SatId, SatId)> {
    let only = |a: SatSet, b: SatSet| if a & !b != 0 { a & !b } else { a };
    Some((
        first_id(sol, only(best, other))?,
        first_id(sol, only(other, best))?,
    ))
}

/// What [`exclude_set`] did.
enum Excluded {
    /// The set is excluded: `out` holds the subset solution, its test and
    /// the exclusion records.
    Done,
    /// The subset failed (rank-deficient with the cause to report, or
    /// inconsistent with None): try more satellites.
    Subset(Option<AlarmCause>),
}

/// Excludes the candidate set `best` (§8.4): re-solves without its
/// satellites and re-tests; when the subset passes, records one
/// exclusion per satellite with its bias b_T (sigma units times sigma)
/// and swaps the subset solution into `out`.
#[allow(clippy::too_many_arguments)] // the epoch, its outcome and the candidate
fn exclude_set<const N: usize, P: Real>(
    cfg: &Config,
    thresholds: &mut Thresholds<N>,
    epoch: &Epoch<'_>,
    best: &SubsetFit<P>,
    before: TestStatistic,
    out: &mut FdeOutcome<N, P>,
    scratch: &mut Scratch<N, P>,
) -> Result<Excluded, RaimError> {
    let sol = &out.solution;
    let mut mask = [false; N];
    for v in mask.iter_mut().take(epoch.len()) {
        *v = true;
    }
    let (rows, k) = covering::members(best.set);
    for row in rows.iter().take(k) {
        if let Some(src) = sol.source.get(usize::from(*row)) {
            if let Some(v) = mask.get_mut(*src) {
                *v = false;
            }
        }
    }
    match solve_into(cfg, epoch, &mask, &mut scratch.solution) {
        Ok(()) => {}
        Err(e @ (RaimError::RankDeficient { .. } | RaimError::TooFewSatellites { .. })) => {
            // The set is a non-empty covering of the solution's rows, so it
            // names a satellite; without one the geometry error stands.
            return match first_id(sol, best.set) {
                Some(excluded) => Ok(Excluded::Subset(Some(AlarmCause::SubsetGeometry {
                    excluded,
                }))),
                None => Err(e),
            };
        }
        Err(e) => return Err(e),
    }
    let after = fde::test(cfg, thresholds, &scratch.solution)?;
    if after.alarm() {
        // The subset is not consistent after all (non-linear model, or a
        // lost clock column): try more satellites.
        return Ok(Excluded::Subset(None));
    }
    for (row, b) in rows.iter().take(k).zip(best.bias.iter()) {
        let row = usize::from(*row);
        let (Some(id), Some(index), Some(&sigma)) =
            (sol.ids.get(row), sol.source.get(row), sol.sigma_m.get(row))
        else {
            continue;
        };
        let pushed = out.exclusions.push(Exclusion {
            id: *id,
            index: *index,
            before,
            after,
            score: best.rss.to_f64(),
            bias_m: b.to_f64() * sigma,
        });
        // Cannot fill: capacity MAX_EXCLUSIONS >= t_eff >= k.
        debug_assert!(pushed.is_ok());
    }
    core::mem::swap(&mut out.solution, &mut scratch.solution);
    out.test = after;
    out.cause = None;
    Ok(Excluded::Done)
}

#[cfg(all(test, feature = "multifault"))]
mod mf_cov_tests;
