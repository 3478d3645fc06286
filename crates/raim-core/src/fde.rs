//! Fault detection and exclusion (SPEC §5): detect, identify, exclude,
//! re-solve and re-test the subset, while the test fails and redundancy
//! remains. An exclusion is accepted only if its subset passes, and (by
//! default) only if excluding the runner-up would not pass as well: the
//! runner-up's subset statistic is D^2 - w_j^2 (removing row j from a least
//! squares fit lowers the weighted SSE by r_j^2 / S_jj), so that check costs
//! no second solve.

use crate::config::Config;
use crate::detection::{TestStatistic, Thresholds};
use crate::error::RaimError;
use crate::lraim::rank;
use crate::measurement::{Epoch, SatId};
use crate::solve::{solve, Solution};

/// Most exclusions reported per epoch (the capacity of the list; the
/// configured `max_exclusions` is clamped to it).
pub const MAX_EXCLUSIONS: usize = 4;

/// One accepted exclusion with the statistic before and after it.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Exclusion {
    pub id: SatId,
    /// Index of the satellite in the epoch's input.
    pub index: usize,
    pub before: TestStatistic,
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
    Ambiguous { best: SatId, runner_up: SatId },
    /// The configured number of exclusions is used up.
    MaxExclusions,
    /// The subset left after an exclusion cannot be solved (rank).
    SubsetGeometry { excluded: SatId },
}

/// The outcome of FDE for one epoch.
#[derive(Debug, Clone)]
pub struct FdeOutcome<const N: usize> {
    /// The solution in force: all-in-view, or the subset after exclusions.
    pub solution: Solution<N>,
    pub test: TestStatistic,
    pub exclusions: heapless::Vec<Exclusion, MAX_EXCLUSIONS>,
    /// The satellite the rule picked first (on the all-in-view solution).
    pub identified: Option<SatId>,
    /// Set when the final test still fails.
    pub cause: Option<AlarmCause>,
}

/// Run the chi-square test on a solution.
pub fn test<const N: usize>(
    cfg: &Config,
    thresholds: &mut Thresholds<N>,
    solution: &Solution<N>,
) -> Result<TestStatistic, RaimError> {
    let dof = solution.parity.dof();
    let (t2, _) = thresholds.get(cfg.pfa, cfg.pmd, dof)?;
    Ok(TestStatistic {
        statistic: solution.parity.sse(),
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

/// FDE starting from the all-in-view solution `first` of `epoch`.
pub fn run<const N: usize>(
    cfg: &Config,
    thresholds: &mut Thresholds<N>,
    epoch: &Epoch<'_>,
    first: Solution<N>,
) -> Result<FdeOutcome<N>, RaimError> {
    let mut mask = [false; N];
    for v in mask.iter_mut().take(epoch.len()) {
        *v = true;
    }
    let mut test_now = test(cfg, thresholds, &first)?;
    let mut out = FdeOutcome {
        solution: first,
        test: test_now,
        exclusions: heapless::Vec::new(),
        identified: None,
        cause: None,
    };
    let max_excl = usize::from(cfg.max_exclusions).min(MAX_EXCLUSIONS);
    while test_now.alarm() {
        let current = &out.solution;
        let (best, second) = rank(&current.parity, cfg.rule, cfg.min_s_ii);
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
        let (Some(best), Some(best_id), Some(best_src)) = (
            best,
            best.and_then(|b| id_of(b.row)),
            best.and_then(|b| src_of(b.row)),
        ) else {
            out.cause = Some(AlarmCause::Unidentifiable);
            break;
        };
        let next_mask = without(&mask, best_src);
        let candidate = match solve::<N>(cfg, epoch, &next_mask) {
            Ok(s) => s,
            Err(RaimError::RankDeficient { .. }) | Err(RaimError::TooFewSatellites { .. }) => {
                out.cause = Some(AlarmCause::SubsetGeometry { excluded: best_id });
                break;
            }
            Err(e) => return Err(e),
        };
        let after = test(cfg, thresholds, &candidate)?;
        if !after.alarm() && cfg.require_unique_exclusion {
            // Excluding one row lowers the weighted SSE by exactly w_j^2
            // (r_j^2 / S_jj) when the state keeps its dimension, so the
            // runner-up's subset statistic needs no second solve.
            if let Some((s2, s2_id)) = second.and_then(|s| Some((s, id_of(s.row)?))) {
                let alt = TestStatistic {
                    statistic: test_now.statistic - s2.w * s2.w,
                    threshold: thresholds.get(cfg.pfa, cfg.pmd, current.parity.dof() - 1)?.0,
                    dof: test_now.dof - 1,
                };
                if !alt.alarm() {
                    out.cause = Some(AlarmCause::Ambiguous {
                        best: best_id,
                        runner_up: s2_id,
                    });
                    break;
                }
            }
        }
        let sigma = current.sigma_m.get(best.row).copied().unwrap_or(1.0);
        let record = Exclusion {
            id: best_id,
            index: best_src,
            before: test_now,
            after,
            score: best.score,
            bias_m: best.bias_sigma * sigma,
        };
        if out.exclusions.push(record).is_err() {
            out.cause = Some(AlarmCause::MaxExclusions);
            break;
        }
        mask = next_mask;
        out.solution = candidate;
        out.test = after;
        test_now = after;
    }
    if !out.test.alarm() {
        out.cause = None;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{linear_epoch, Rng, SKY8};

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
                const SSE_TOL: f64 = 1e-9; // dimensionless (chi-square units)
                assert!(
                    (sub.parity.sse() - (full.parity.sse() - w2)).abs() < SSE_TOL,
                    "seed {seed} sat {j}"
                );
            }
        }
    }
}
