//! Fault detection and exclusion (SPEC §5): detect, identify, exclude,
//! re-solve and re-test the subset, while the test fails and redundancy
//! remains. An exclusion is accepted only if its subset passes, and (by
//! default) only if no other single satellite explains the data: every
//! alternative's subset statistic D^2 - w_j^2 (removing row j from a least
//! squares fit lowers the weighted SSE by r_j^2 / S_jj) must reach the
//! chi-square quantile at 1 - pwe. That check costs no second solve.

use crate::config::Config;
use crate::error::RaimError;
use crate::measurement::{Epoch, SatId};
use crate::real::{Real, Stat};
use crate::snapshot::detection::{TestStatistic, Thresholds};
use crate::snapshot::lraim::{rank, Candidate};
use crate::solve::{solve_from, Solution, Start};

/// Most exclusions reported per epoch (the capacity of the list; the
/// configured `max_exclusions` is clamped to it).
pub const MAX_EXCLUSIONS: usize = 4;

/// One accepted exclusion with the statistic before and after it.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Exclusion {
    /// The excluded satellite.
    pub id: SatId,
    /// Index of the satellite in the epoch's input.
    pub index: usize,
    /// The test before the exclusion.
    pub before: TestStatistic,
    /// The test of the subset after it.
    pub after: TestStatistic,
    /// The identification rule's score of the excluded satellite.
    pub score: f64,
    /// Its bias estimate at the time of exclusion, m.
    pub bias_m: f64,
}

/// Why an alarm could not be resolved by exclusion.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum AlarmCause {
    /// n - m < 2: a fault can be detected but not excluded.
    NoRedundancy,
    /// Every satellite's S_ii is below the identifiability bound.
    Unidentifiable,
    /// Excluding the best or the runner-up candidate both give consistent
    /// subsets: the faulty satellite cannot be told apart.
    Ambiguous {
        /// The best candidate.
        best: SatId,
        /// The runner-up.
        runner_up: SatId,
    },
    /// The configured number of exclusions is used up.
    MaxExclusions,
    /// The subset left after an exclusion cannot be solved (rank).
    SubsetGeometry {
        /// The satellite whose exclusion left a singular subset.
        excluded: SatId,
    },
    /// Reconstruction FDE (SPEC §8.4): no set of 1..t_max satellites
    /// explains the residuals.
    NoConsistentSet,
    /// Reconstruction FDE: a set explains the residuals, but the group
    /// budget stopped the search before all `groups`, so the uniqueness
    /// check is incomplete and nothing is excluded.
    SearchIncomplete {
        /// Groups in the design.
        groups: u32,
        /// Groups searched.
        budget: u32,
    },
}

/// The outcome of FDE for one epoch.
#[derive(Debug, Clone)]
pub struct FdeOutcome<const N: usize, T: Real = Stat> {
    /// The solution in force: all-in-view, or the subset after exclusions.
    pub solution: Solution<N, T>,
    /// The test of the solution in force.
    pub test: TestStatistic,
    /// The exclusions made, in order.
    pub exclusions: heapless::Vec<Exclusion, MAX_EXCLUSIONS>,
    /// The satellite the rule picked first (on the all-in-view solution).
    pub identified: Option<SatId>,
    /// Set when the final test still fails.
    pub cause: Option<AlarmCause>,
    /// Scratch, not state: the subset solution FDE works on (accepted ones
    /// are swapped into `solution`). Kept here, beside the solution in
    /// force, so that an epoch neither zero-fills nor carries a
    /// solution-sized value on its stack. Every solve writes
    /// every field it is later read through, so nothing in it depends on
    /// an earlier epoch.
    pub(crate) scratch: Solution<N, T>,
    /// The rule's best candidate on `solution` when the caller has ranked
    /// it already (the snapshot engine, from the per-satellite output it
    /// scores anyway); taken, and cleared, by [`run`].
    pub(crate) first_best: Option<Option<Candidate<T>>>,
}

/// Run the chi-square test on a solution. The statistic D^2, computed in
/// `T`, is widened to f64 and compared there with the f64 threshold, so the
/// comparison itself adds no rounding.
pub fn test<const N: usize, T: Real>(
    cfg: &Config,
    thresholds: &mut Thresholds<N>,
    solution: &Solution<N, T>,
) -> Result<TestStatistic, RaimError> {
    let dof = solution.parity.dof();
    let (t2, _) = thresholds.get(cfg.pfa, cfg.pmd, dof)?;
    Ok(TestStatistic {
        statistic: solution.parity.sse().to_f64(),
        threshold: t2,
        dof: dof as u32,
    })
}

fn without<const N: usize>(mask: &[bool; N], index: usize) -> [bool; N] {
    let mut m = *mask;
    if let Some(v) = m.get_mut(index) {
        *v = false;
    }
    m
}

/// The row other than `best` with the largest w_j^2 = r_j^2 / S_jj among
/// identifiable rows, and that w_j^2.
fn strongest_alternative<const N: usize, T: Real>(
    parity: &crate::linalg::parity::Parity<N, T>,
    best: usize,
    min_s_ii: f64,
) -> Option<(usize, f64)> {
    strongest_alternative_rows(parity.residuals(), parity.s_ii(), best, T::of(min_s_ii))
        .map(|(row, w2)| (row, w2.to_f64()))
}

/// `strongest_alternative` on residuals and S_ii. Fails safe on NaN
///: a row whose S_ii is NaN is kept, and a NaN w_j^2 counts as
/// +inf, an alternative that explains everything and so cannot be rejected.
/// (A NaN compared false and the row used to be passed over.)
fn strongest_alternative_rows<T: Real>(
    residuals: &[T],
    s_ii: &[T],
    best: usize,
    min_s_ii: T,
) -> Option<(usize, T)> {
    residuals
        .iter()
        .zip(s_ii)
        .enumerate()
        .filter(|(row, (_, s))| *row != best && !(**s < min_s_ii))
        .map(|(row, (&r, &s))| {
            let w2 = r * r / s;
            (
                row,
                if w2.is_nan_m() {
                    T::of(f64::INFINITY)
                } else {
                    w2
                },
            )
        })
        .fold(None, |acc: Option<(usize, T)>, c| match acc {
            Some(a) if a.1 >= c.1 => Some(a),
            _ => Some(c),
        })
}

/// The uniqueness test (docs/CORE.md FDE 3): the alternative explanation,
/// whose subset statistic is `alternative_statistic`, is rejected only when
/// that statistic reaches the pwe threshold. Written so that NaN is *not*
/// a rejection: an alternative that cannot be evaluated leaves the
/// exclusion ambiguous (`statistic < threshold` was false on NaN,
/// and the exclusion stood).
fn alternative_rejected(alternative_statistic: f64, threshold: f64) -> bool {
    alternative_statistic >= threshold
}

/// A pair of rows, their joint bias estimates (sigma units) and the
/// statistic of the subset without them.
#[derive(Debug, Clone, Copy)]
struct PairFit<T: Real> {
    rows: (usize, usize),
    bias_sigma: (T, T),
    statistic: T,
}

/// The relative determinant below which a pair's S_TT counts as singular:
/// 1e-9, floored at 100 machine epsilons of `T` (1.2e-5 in f32), since the
/// determinant S_jj S_kk - S_jk^2 of an exactly singular pair (two
/// satellites of one constellation) rounds to ~eps S_jj S_kk, not to 0.
fn pair_singular_tol<T: Real>() -> T {
    let floor = T::EPS * T::of(100.0);
    let tol = T::of(1e-9);
    if tol > floor {
        tol
    } else {
        floor
    }
}

/// The two pairs of identifiable rows whose removal leaves the smallest
/// weighted SSE: RSS_T = D^2 - r_T^T (S_TT)^-1 r_T for T = {j, k} (SPEC §8.4).
/// S_jk comes from the column S e_j = U2 U2^T e_j, one column at a time, so
/// nothing n x n is stored. Pairs whose S_TT is singular (e.g. the two
/// satellites of a constellation, whose sum is its clock column) are skipped.
#[inline(never)]
fn best_pairs<const N: usize, T: Real>(
    parity: &crate::linalg::parity::Parity<N, T>,
    min_s_ii: f64,
) -> [Option<PairFit<T>>; 2] {
    let min_s_ii = T::of(min_s_ii);
    let singular = pair_singular_tol::<T>();
    let d2 = parity.sse();
    let r = parity.residuals();
    let s = parity.s_ii();
    let mut best: [Option<PairFit<T>>; 2] = [None, None];
    let mut e = [T::zero(); N];
    let mut y = [T::zero(); N];
    for (j, (&rj, &sjj)) in r.iter().zip(s).enumerate() {
        if sjj < min_s_ii {
            continue;
        }
        if let Some(v) = e.get_mut(j) {
            *v = T::one();
        }
        let k_dims = parity.project(&e, &mut y);
        // `project` writes at most y.len() entries.
        let col = parity.lift(y.get(..k_dims).unwrap_or(&[]));
        if let Some(v) = e.get_mut(j) {
            *v = T::zero();
        }
        for (k, ((&rk, &skk), &sjk)) in r.iter().zip(s).zip(col.iter()).enumerate().skip(j + 1) {
            if skk < min_s_ii {
                continue;
            }
            let det = sjj * skk - sjk * sjk;
            if !(det > singular * sjj * skk) {
                continue;
            }
            let bj = (skk * rj - sjk * rk) / det;
            let bk = (sjj * rk - sjk * rj) / det;
            let fit = PairFit {
                rows: (j, k),
                bias_sigma: (bj, bk),
                statistic: d2 - (rj * bj + rk * bk),
            };
            insert_pair(&mut best, fit);
        }
    }
    best
}

/// Keep the two best pairs (smallest statistic first) in `best`.
fn insert_pair<T: Real>(best: &mut [Option<PairFit<T>>; 2], fit: PairFit<T>) {
    match *best {
        [Some(b0), _] if !fits_before(fit.statistic, b0.statistic) => {
            if best[1].is_none_or(|b1| fits_before(fit.statistic, b1.statistic)) {
                best[1] = Some(fit);
            }
        }
        _ => *best = [Some(fit), best[0]],
    }
}

/// Whether pair statistic `a` ranks before `b` (smaller fits better). A NaN
/// ranks before every number: a pair that cannot be evaluated
/// takes the best slot whatever the order of the rows, where it fails the
/// subset test, so the closed-form pair exclusion is not used and the
/// greedy path goes on with its own checks. It can never drop out of the
/// ranking and let another pair's exclusion look unique.
fn fits_before<T: Real>(a: T, b: T) -> bool {
    match (a.is_nan_m(), b.is_nan_m()) {
        (true, false) => true,
        (false, false) => a < b,
        (_, true) => false,
    }
}

/// What the pair search found. `Excluded` means the subset's solution was
/// written into the caller's scratch solution.
enum PairOutcome {
    Excluded(TestStatistic, [Exclusion; 2]),
    Ambiguous(AlarmCause),
    NotFound,
}

/// Exclude the best-fitting pair if its subset passes and no other pair
/// also explains the data at level pwe.
#[inline(never)]
fn exclude_pair<const N: usize, T: Real>(
    cfg: &Config,
    thresholds: &mut Thresholds<N>,
    epoch: &Epoch<'_>,
    mask: &[bool; N],
    current: &Solution<N, T>,
    before: TestStatistic,
    scratch: &mut Solution<N, T>,
) -> Result<PairOutcome, RaimError> {
    let [Some(pair), second] = best_pairs(&current.parity, cfg.min_s_ii) else {
        return Ok(PairOutcome::NotFound);
    };
    let dof_pair = current.parity.dof() - 2;
    let (t2, _) = thresholds.get(cfg.pfa, cfg.pmd, dof_pair)?;
    if !(pair.statistic.to_f64() < t2) {
        return Ok(PairOutcome::NotFound);
    }
    let (j, k) = pair.rows;
    let (Some(id_j), Some(id_k), Some(src_j), Some(src_k), Some(&sigma_j), Some(&sigma_k)) = (
        current.ids.get(j).copied(),
        current.ids.get(k).copied(),
        current.source.get(j).copied(),
        current.source.get(k).copied(),
        current.sigma_m.get(j),
        current.sigma_m.get(k),
    ) else {
        return Ok(PairOutcome::NotFound);
    };
    if let Some(alt) = second {
        let t2_we = thresholds.wrong_exclusion(cfg.pwe, dof_pair)?;
        if !alternative_rejected(alt.statistic.to_f64(), t2_we) {
            let (a, b) = alt.rows;
            let other = if a != j && a != k { a } else { b };
            let mine = if j != a && j != b { j } else { k };
            // A pair's rows are parity rows, < n <= N (`ids` has N); a row
            // without an id leaves the pair unidentifiable: alarm.
            let (Some(&best), Some(&runner_up)) = (current.ids.get(mine), current.ids.get(other))
            else {
                return Ok(PairOutcome::Ambiguous(AlarmCause::Unidentifiable));
            };
            return Ok(PairOutcome::Ambiguous(AlarmCause::Ambiguous {
                best,
                runner_up,
            }));
        }
    }
    let subset = without(&without(mask, src_j), src_k);
    match solve_from(cfg, epoch, &subset, Start::Sibling(current), scratch) {
        Ok(()) => {}
        Err(RaimError::RankDeficient { .. }) | Err(RaimError::TooFewSatellites { .. }) => {
            return Ok(PairOutcome::NotFound)
        }
        Err(e) => return Err(e),
    };
    let after = test(cfg, thresholds, scratch)?;
    if after.alarm() {
        return Ok(PairOutcome::NotFound);
    }
    let record = |id: SatId, index: usize, sigma_m: f64, bias_sigma: T| Exclusion {
        id,
        index,
        before,
        after,
        score: f64::NAN,
        bias_m: bias_sigma.to_f64() * sigma_m,
    };
    Ok(PairOutcome::Excluded(
        after,
        [
            record(id_j, src_j, sigma_j, pair.bias_sigma.0),
            record(id_k, src_k, sigma_k, pair.bias_sigma.1),
        ],
    ))
}

impl<const N: usize, T: Real> FdeOutcome<N, T> {
    /// Back to [`FdeOutcome::empty`]'s verdict, in place (an outcome kept
    /// in an engine's state and reused every epoch). The two
    /// solutions' storage is kept, not zero-filled (that was a
    /// fifth of a clean linearised epoch's instructions): the epoch's solve
    /// overwrites every field of the solution it fills (`solve::solve_from`;
    /// test `a_reused_engine_equals_a_fresh_one`).
    pub fn reset(&mut self) {
        self.test = TestStatistic::default();
        self.exclusions.clear();
        self.identified = None;
        self.cause = None;
        self.first_best = None;
    }

    /// An empty outcome whose `solution` is to be filled by
    /// [`crate::solve::solve_into`] before [`run`].
    pub const fn empty() -> Self {
        FdeOutcome {
            solution: Solution::empty(),
            test: TestStatistic::ZERO,
            exclusions: heapless::Vec::new(),
            identified: None,
            cause: None,
            scratch: Solution::empty(),
            first_best: None,
        }
    }
}

/// FDE on `out`, whose `solution` holds the all-in-view solution of
/// `epoch`; on return it holds the solution in force. In place, so no
/// solution is moved on the stack (the firmware's stack budget).
#[inline(never)]
pub fn run<const N: usize, T: Real>(
    cfg: &Config,
    thresholds: &mut Thresholds<N>,
    epoch: &Epoch<'_>,
    out: &mut FdeOutcome<N, T>,
) -> Result<(), RaimError> {
    let mut mask = [false; N];
    for v in mask.iter_mut().take(epoch.len()) {
        *v = true;
    }
    let mut test_now = test(cfg, thresholds, &out.solution)?;
    out.test = test_now;
    out.exclusions.clear();
    out.identified = None;
    out.cause = None;
    let max_excl = usize::from(cfg.max_exclusions).min(MAX_EXCLUSIONS);
    // The one subset solution FDE works on (the outcome's scratch);
    // accepted ones are swapped in.
    let mut first_best = out.first_best.take();
    while test_now.alarm() {
        let current = &out.solution;
        let best = match first_best.take() {
            Some(best) => best,
            None => rank(&current.parity, cfg.rule, cfg.min_s_ii).0,
        };
        let id_of = |row: usize| current.ids.get(row).copied();
        let src_of = |row: usize| current.source.get(row).copied();
        if out.identified.is_none() {
            out.identified = best.and_then(|b| id_of(b.row));
        }
        if current.parity.dof() < 2 {
            out.cause = Some(AlarmCause::NoRedundancy);
            break;
        }
        if out.exclusions.len() >= max_excl {
            out.cause = Some(AlarmCause::MaxExclusions);
            break;
        }
        let (Some(best), Some(best_id), Some(best_src), Some(&sigma)) = (
            best,
            best.and_then(|b| id_of(b.row)),
            best.and_then(|b| src_of(b.row)),
            best.and_then(|b| current.sigma_m.get(b.row)),
        ) else {
            out.cause = Some(AlarmCause::Unidentifiable);
            break;
        };
        if out.exclusions.is_empty()
            && max_excl >= 2
            && current.parity.dof() >= 3
            && pair_first(cfg, thresholds, epoch, &mask, test_now, best.w, out)?
        {
            break;
        }
        let current = &out.solution;
        let next_mask = without(&mask, best_src);
        match solve_from(
            cfg,
            epoch,
            &next_mask,
            Start::Sibling(current),
            &mut out.scratch,
        ) {
            Ok(()) => {}
            Err(RaimError::RankDeficient { .. }) | Err(RaimError::TooFewSatellites { .. }) => {
                out.cause = Some(AlarmCause::SubsetGeometry { excluded: best_id });
                break;
            }
            Err(e) => return Err(e),
        };
        let after = test(cfg, thresholds, &out.scratch)?;
        if !after.alarm() && cfg.require_unique_exclusion {
            if let Some(cause) = ambiguity(cfg, thresholds, current, test_now, best.row, best_id)? {
                out.cause = Some(cause);
                break;
            }
        }
        let record = Exclusion {
            id: best_id,
            index: best_src,
            before: test_now,
            after,
            score: best.score.to_f64(),
            bias_m: best.bias_sigma.to_f64() * sigma,
        };
        if out.exclusions.push(record).is_err() {
            out.cause = Some(AlarmCause::MaxExclusions);
            break;
        }
        mask = next_mask;
        core::mem::swap(&mut out.solution, &mut out.scratch);
        out.test = after;
        test_now = after;
    }
    if !out.test.alarm() {
        out.cause = None;
    }
    Ok(())
}

/// SPEC §8.4 with t = 2, before the first greedy exclusion: the subset
/// without the best-ranked row has statistic D^2 - w_best^2 (see
/// [`ambiguity`]); if even that fails, one exclusion is not enough, so
/// look for the pair that explains the all-in-view residuals, in closed
/// form. Returns whether FDE stops here: the pair was excluded (`out`
/// holds its subset and test), or it was ambiguous and the configuration
/// requires a unique exclusion (`out.cause`).
fn pair_first<const N: usize, T: Real>(
    cfg: &Config,
    thresholds: &mut Thresholds<N>,
    epoch: &Epoch<'_>,
    mask: &[bool; N],
    test_now: TestStatistic,
    best_w: T,
    out: &mut FdeOutcome<N, T>,
) -> Result<bool, RaimError> {
    let (t2_single, _) = thresholds.get(cfg.pfa, cfg.pmd, out.solution.parity.dof() - 1)?;
    if test_now.statistic - (best_w * best_w).to_f64() < t2_single {
        return Ok(false);
    }
    match exclude_pair(
        cfg,
        thresholds,
        epoch,
        mask,
        &out.solution,
        test_now,
        &mut out.scratch,
    )? {
        PairOutcome::Excluded(after, records) => {
            for r in records {
                let pushed = out.exclusions.push(r);
                // Cannot fill: the pair goes into an empty list of
                // capacity MAX_EXCLUSIONS >= 2.
                debug_assert!(pushed.is_ok());
            }
            core::mem::swap(&mut out.solution, &mut out.scratch);
            out.test = after;
            Ok(true)
        }
        PairOutcome::Ambiguous(cause) if cfg.require_unique_exclusion => {
            out.cause = Some(cause);
            Ok(true)
        }
        PairOutcome::Ambiguous(_) | PairOutcome::NotFound => Ok(false),
    }
}

/// The uniqueness check of an exclusion whose subset passed (SPEC §8.4):
/// excluding row j lowers the weighted SSE by exactly w_j^2 (r_j^2 / S_jj)
/// when the state keeps its dimension, so every alternative's subset
/// statistic is known without a solve. The most consistent alternative is
/// the other row of largest w_j^2; if its subset is consistent at level
/// pwe, the fault cannot be attributed safely: `Some(Ambiguous)`.
fn ambiguity<const N: usize, T: Real>(
    cfg: &Config,
    thresholds: &mut Thresholds<N>,
    current: &Solution<N, T>,
    test_now: TestStatistic,
    best_row: usize,
    best_id: SatId,
) -> Result<Option<AlarmCause>, RaimError> {
    let Some((alt_row, alt_w2)) = strongest_alternative(&current.parity, best_row, cfg.min_s_ii)
    else {
        return Ok(None);
    };
    let dof_alt = current.parity.dof() - 1;
    let threshold = thresholds.wrong_exclusion(cfg.pwe, dof_alt)?;
    if alternative_rejected(test_now.statistic - alt_w2, threshold) {
        return Ok(None);
    }
    Ok(Some(AlarmCause::Ambiguous {
        best: best_id,
        runner_up: current.ids.get(alt_row).copied().unwrap_or(best_id),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::solve;
    use crate::testutil::{at_stat, linear_epoch, Rng, SKY8};

    /// A detected fault with every satellite's S_ii under `min_s_ii` (0.5,
    /// the bound's maximum, on 6 satellites in two symmetric rings at 30
    /// and 40 deg, dof 2: S_ii 0.293 and 0.374 by a dense computation):
    /// no satellite can be named, so the alarm is `Unidentifiable`
    /// with nothing identified or excluded. The reported S_ii confirm the
    /// premise (to the dense computation's 3 decimals).
    #[test]
    fn no_identifiable_row_alarms_unidentifiable() {
        let cfg = Config {
            min_s_ii: 0.5,
            ..Config::default()
        };
        assert_eq!(cfg.validate(), Ok(()));
        let sats: [crate::measurement::LinearObservation; 6] = core::array::from_fn(|i| {
            let az_deg = i as f64 * 60.0;
            let el_deg: f64 = if i % 2 == 0 { 30.0 } else { 40.0 };
            let fault_m = if i == 2 { 200.0 } else { 0.0 };
            let mut o = crate::measurement::LinearObservation::from_az_el(
                crate::measurement::SatId::new(crate::measurement::System::Gps, i as u8 + 1),
                az_deg.to_radians(),
                el_deg.to_radians(),
                fault_m,
            );
            o.sigma_m = Some(1.0);
            o
        });
        let r = crate::monitor::Raim::<8>::new()
            .process(&cfg, &Epoch::linear(0.0, &sats))
            .unwrap();
        for (i, s) in r.satellites.iter().enumerate() {
            let want = if i % 2 == 0 { 0.293 } else { 0.374 };
            assert!((s.s_ii - want).abs() < 1e-3, "{i}: {}", s.s_ii);
        }
        assert_eq!(r.decision, crate::result::Decision::Alarm);
        assert_eq!(r.alarm_cause, Some(AlarmCause::Unidentifiable));
        assert!(r.identified.is_none() && r.exclusions.is_empty());
    }

    /// The identity behind the uniqueness check: the statistic of the subset
    /// without satellite j equals D^2 - w_j^2, checked against real subset
    /// solves for every j (linear model, so it holds to rounding).
    #[test]
    fn subset_statistic_is_sse_minus_w_squared() {
        let cfg = Config::default();
        for seed in 0..20 {
            let sats = linear_epoch(&SKY8, 1.5, &mut Rng::new(seed), &[(4, 12.0)]);
            let epoch = Epoch::linear(0.0, &sats);
            let all = [true; 8];
            let full = solve::<8>(&cfg, &epoch, &all).unwrap();
            for j in 0..8 {
                let s = full.parity.s_ii()[j];
                let w2 = full.parity.residuals()[j].powi(2) / s;
                let sub = solve::<8>(&cfg, &epoch, &without(&all, j)).unwrap();
                // Dimensionless (chi-square units): 1e-9 in f64; in f32
                // (D^2 up to ~100 here) a few eps x D^2 of the QR and the
                // two sums, 1e-4.
                const SSE_TOL: f64 = at_stat(1e-9, 1e-4);
                let (sub_sse, full_sse) = (sub.parity.sse().to_f64(), full.parity.sse().to_f64());
                assert!(
                    (sub_sse - (full_sse - w2.to_f64())).abs() < SSE_TOL,
                    "seed {seed} sat {j}"
                );
            }
        }
    }

    /// Two satellites whose parity directions are nearly parallel cannot be
    /// told apart: a fault on one leaves both subsets consistent, so FDE
    /// alarms with `Ambiguous` instead of excluding (docs/CORE.md, FDE step
    /// 3). Without the check it would exclude one of them, possibly the
    /// wrong one. The geometry is found by a deterministic grid search for
    /// a sixth satellite that makes |R_01| = |S_01| / sqrt(S_00 S_11) > 0.999
    /// (dof 2, like 0759 at 00:40:00, where G24 and G11 are parallel).
    #[test]
    fn near_parallel_parity_directions_alarm_as_ambiguous() {
        let base = [
            (30.0, 20.0),
            (200.0, 35.0),
            (110.0, 60.0),
            (290.0, 30.0),
            (0.0, 80.0),
        ];
        let cfg = Config::default();
        let mut found = None;
        'grid: for az in (0..360).step_by(2) {
            for el in (5..90).step_by(2) {
                let mut sky = base.to_vec();
                sky.push((az as f64, el as f64));
                let sats = linear_epoch(&sky, 1.0, &mut Rng::new(0), &[]);
                let mut mask = [false; 8];
                mask[..6].fill(true);
                let Ok(sol) = solve::<8>(&cfg, &Epoch::linear(0.0, &sats), &mask) else {
                    continue;
                };
                let e0 = sol.parity.lift(&[1.0, 0.0]);
                let e1 = sol.parity.lift(&[0.0, 1.0]);
                // S_jk = sum over the parity basis of U2_j U2_k.
                let s = |j: usize, k: usize| e0[j] * e0[k] + e1[j] * e1[k];
                let r01 = s(0, 1) / (s(0, 0) * s(1, 1)).sqrt();
                if r01.abs() > 0.999 && s(0, 0) > 0.05 && s(1, 1) > 0.05 {
                    found = Some(sky);
                    break 'grid;
                }
            }
        }
        let sky = found.expect("the grid holds a near-parallel geometry");
        let mut thresholds = Thresholds::<8>::default();
        for seed in 0..20 {
            let sats = linear_epoch(&sky, 1.0, &mut Rng::new(seed), &[(0, 40.0)]);
            let epoch = Epoch::linear(0.0, &sats);
            let mut mask = [false; 8];
            mask[..6].fill(true);
            let first = solve::<8>(&cfg, &epoch, &mask).unwrap();
            let mut out = FdeOutcome::empty();
            out.solution = first.clone();
            run(&cfg, &mut thresholds, &epoch, &mut out).unwrap();
            assert!(out.test.alarm(), "seed {seed}: {:?}", out.exclusions);
            match out.cause {
                // The grid's geometry puts the sixth satellite next to the
                // third, which leaves satellites 1, 2, 4 and 5 with one shared
                // parity direction: any two of them explain the fault.
                Some(AlarmCause::Ambiguous { best, runner_up }) => {
                    assert!([1, 2, 4, 5].contains(&best.prn), "seed {seed}: {best:?}");
                    assert!([1, 2, 4, 5].contains(&runner_up.prn), "seed {seed}");
                    assert_ne!(best, runner_up);
                }
                other => panic!("seed {seed}: {other:?}"),
            }
            let lax = Config {
                require_unique_exclusion: false,
                ..cfg
            };
            let mut out = FdeOutcome::empty();
            out.solution = first;
            run(&lax, &mut thresholds, &epoch, &mut out).unwrap();
            assert!(
                !out.test.alarm() && out.exclusions.len() == 1,
                "seed {seed}"
            );
        }
    }
}

/// The uniqueness checks and the pair ranking fail safe on NaN.
#[cfg(test)]
mod nan_tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// An alternative whose subset statistic is NaN is not rejected, so the
    /// exclusion is ambiguous; finite values compare as before.
    ///
    /// Verifies: SAFE-NAN
    #[test]
    fn a_nan_alternative_is_not_rejected() {
        assert!(!alternative_rejected(f64::NAN, 9.0));
        assert!(!alternative_rejected(9.0, f64::NAN));
        assert!(!alternative_rejected(8.9, 9.0));
        assert!(alternative_rejected(9.0, 9.0));
        assert!(alternative_rejected(f64::INFINITY, 9.0));
    }

    /// A NaN residual or S_ii on any row other than the excluded one is the
    /// strongest alternative, with w^2 = +inf; without NaN the strongest is
    /// the brute-force argmax of r^2 / S.
    #[test]
    fn a_nan_row_is_the_strongest_alternative() {
        let r = [1.0, -3.0, 0.5, 2.0, -0.1];
        let s = [0.5, 0.6, 0.4, 0.7, 0.3];
        let brute = |best: usize| {
            (0..5)
                .filter(|&j| j != best)
                .map(|j| (j, r[j] * r[j] / s[j]))
                .fold((usize::MAX, -1.0), |a, c| if c.1 > a.1 { c } else { a })
        };
        for best in 0..5 {
            assert_eq!(
                strongest_alternative_rows(&r, &s, best, 1e-4),
                Some(brute(best))
            );
            for bad in (0..5).filter(|&j| j != best) {
                let mut r2 = r;
                r2[bad] = f64::NAN;
                assert_eq!(
                    strongest_alternative_rows(&r2, &s, best, 1e-4),
                    Some((bad, f64::INFINITY)),
                    "residual: best {best} bad {bad}"
                );
                let mut s2 = s;
                s2[bad] = f64::NAN;
                assert_eq!(
                    strongest_alternative_rows(&r, &s2, best, 1e-4),
                    Some((bad, f64::INFINITY)),
                    "S_ii: best {best} bad {bad}"
                );
            }
        }
    }

    /// A NaN pair statistic takes the best slot wherever it comes in the
    /// sequence, so the pair exclusion is not used (it fails `< T^2`);
    /// among finite pairs the two smallest are kept, in order.
    #[test]
    fn a_nan_pair_takes_the_best_slot_in_any_order() {
        let fit = |i: usize, statistic: f64| PairFit {
            rows: (i, i + 1),
            bias_sigma: (0.0, 0.0),
            statistic,
        };
        let stats = [7.0, 2.0, 5.0, 3.0];
        let mut best = [None, None];
        for (i, &t) in stats.iter().enumerate() {
            insert_pair(&mut best, fit(i, t));
        }
        assert_eq!(best[0].unwrap().statistic, 2.0);
        assert_eq!(best[1].unwrap().statistic, 3.0);
        for pos in 0..=stats.len() {
            let mut best = [None, None];
            let mut seq: Vec<PairFit<f64>> =
                stats.iter().enumerate().map(|(i, &t)| fit(i, t)).collect();
            seq.insert(pos, fit(9, f64::NAN));
            for f in seq {
                insert_pair(&mut best, f);
            }
            let b0 = best[0].unwrap();
            assert_eq!(b0.rows, (9, 10), "NaN at {pos}");
            assert!(!(b0.statistic < 1e9));
        }
    }
}

#[cfg(test)]
#[path = "fde_cov_tests.rs"]
mod cov_tests;
