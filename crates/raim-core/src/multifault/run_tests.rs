//! The reconstruction FDE's decision paths (SPEC §8.4) through the
//! monitor, [`decide`] on hand-built searches, and the error mapping.
//!
//! Test code only (`#[cfg(test)] mod run_tests;` in `multifault/mod.rs`).
//! The chi-square quantiles the outcomes are checked against come from
//! statrs, not from the core's `stats::dist`.
extern crate std;

use super::tests::{epoch_sats, reconstruction, sky14};
use super::*;
use crate::config::{Config, FdeMethod, Phase};
use crate::measurement::{Epoch, SatId, System};
use crate::monitor::Raim;
use crate::result::Decision;
use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::vec::Vec;

const N: usize = 32;

/// The chi-square quantile at 1 - p with `dof` degrees of freedom (statrs).
fn chi2_upper(p: f64, dof: usize) -> f64 {
    ChiSquared::new(dof as f64).unwrap().inverse_cdf(1.0 - p)
}

/// The reconstruction FDE with `t_max`, a group budget and an exclusion cap.
fn cfg(t_max: u8, group_budget: u16, max_exclusions: u8) -> Config {
    Config {
        fde_method: FdeMethod::Reconstruction {
            t_max,
            group_budget,
        },
        max_exclusions,
        ..Config::preset(Phase::Npa)
    }
}

/// sky14's row 3 (odd rows are Galileo, PRN = row + 1).
const ROW3: SatId = SatId::new(System::Galileo, 4);

/// A clean epoch passes detection: no search is run, no report, no cause.
#[test]
#[cfg(feature = "multifault")]
fn clean_epoch_runs_no_search() {
    for seed in 0..4 {
        let sats = epoch_sats(&sky14(), seed, &[]);
        let r = Raim::<N>::new()
            .process(&reconstruction(2), &Epoch::linear(0.0, &sats))
            .unwrap();
        assert!(!r.initial_test.alarm(), "seed {seed}");
        assert_eq!(r.decision, Decision::Ok);
        assert_eq!(r.alarm_cause, None);
        assert!(r.multifault.is_none() && r.exclusions.is_empty());
    }
}

/// Five satellites of one system: dof = n - m = 5 - 4 = 1, so a detected
/// fault cannot be excluded (a candidate set needs dof - |T| >= 1 left):
/// `NoRedundancy`, no search.
#[test]
#[cfg(feature = "multifault")]
fn one_parity_dof_alarms_no_redundancy() {
    let five: Vec<(System, f64, f64)> = sky14()
        .iter()
        .take(5)
        .map(|&(_, az, el)| (System::Gps, az, el))
        .collect();
    let sats = epoch_sats(&five, 1, &[(2, 100.0)]);
    let r = Raim::<N>::new()
        .process(&reconstruction(2), &Epoch::linear(0.0, &sats))
        .unwrap();
    assert_eq!(r.test.dof, 1);
    assert_eq!(r.decision, Decision::Alarm);
    assert_eq!(r.alarm_cause, Some(AlarmCause::NoRedundancy));
    assert!(r.multifault.is_none() && r.exclusions.is_empty());
}

/// `max_exclusions = 0` caps the fault count at 0: a detected fault is an
/// alarm `MaxExclusions`, with no search and no exclusion.
#[test]
#[cfg(feature = "multifault")]
fn zero_exclusion_cap_alarms_max_exclusions() {
    let sats = epoch_sats(&sky14(), 0, &[(3, 60.0)]);
    let r = Raim::<N>::new()
        .process(&cfg(2, 200, 0), &Epoch::linear(0.0, &sats))
        .unwrap();
    assert_eq!(r.decision, Decision::Alarm);
    assert_eq!(r.alarm_cause, Some(AlarmCause::MaxExclusions));
    assert!(r.multifault.is_none() && r.exclusions.is_empty());
}

/// Three large faults searched with t_max = 1: no single satellite
/// explains them, so the alarm is `NoConsistentSet` with the least-RSS
/// single set reported, whose RSS_T is at or above the chi-square
/// quantile at 1 - pfa (dof - 1) from statrs.
#[test]
#[cfg(feature = "multifault")]
fn more_faults_than_searched_alarm_no_consistent_set() {
    let c = cfg(1, 200, 3);
    for seed in 0..3 {
        let sats = epoch_sats(&sky14(), seed, &[(3, 60.0), (8, -70.0), (12, 80.0)]);
        let r = Raim::<N>::new()
            .process(&c, &Epoch::linear(0.0, &sats))
            .unwrap();
        assert_eq!(r.decision, Decision::Alarm);
        assert_eq!(r.alarm_cause, Some(AlarmCause::NoConsistentSet));
        let report = r.multifault.unwrap();
        assert!(!report.budget_limited && report.t_searched == 1);
        let best = report.best.unwrap();
        assert_eq!((best.count, best.dof), (1, 14 - 5 - 1));
        assert!(best.rss >= chi2_upper(c.pfa, 8), "seed {seed}: {best:?}");
        assert!(r.exclusions.is_empty() && r.identified.is_none());
    }
}

/// sky14's row 2 (GPS PRN 3), inside the design's first group (the
/// even rows).
const ROW2: SatId = SatId::new(System::Gps, 3);

/// One fault, a group budget of 1 of the design's 2 groups: the best
/// single set passes its quantile, but the uniqueness check did not see
/// every group, so it is named (identified) and not excluded:
/// `SearchIncomplete` with the budget and the design's group count.
#[test]
#[cfg(feature = "multifault")]
fn budget_cut_names_the_consistent_set_without_excluding_it() {
    let c = cfg(1, 1, 3);
    let sats = epoch_sats(&sky14(), 0, &[(2, 60.0)]);
    let r = Raim::<N>::new()
        .process(&c, &Epoch::linear(0.0, &sats))
        .unwrap();
    assert_eq!(r.decision, Decision::Alarm);
    let report = r.multifault.unwrap();
    assert!(report.budget_limited);
    assert_eq!((report.groups_processed, report.groups_total), (1, 2));
    assert_eq!(
        r.alarm_cause,
        Some(AlarmCause::SearchIncomplete {
            groups: 2,
            budget: 1
        })
    );
    assert_eq!(r.identified, Some(ROW2));
    let best = report.best.unwrap();
    assert_eq!((best.count, best.satellites[0]), (1, ROW2));
    assert!(best.rss < chi2_upper(c.pfa, 8), "{best:?}");
    assert!((best.bias_m[0] - 60.0).abs() < 5.0, "{best:?}");
    assert!(r.exclusions.is_empty());
}

/// A small fault (8 m) searched up to three: the best single set passes,
/// but a pair without it also passes at level pwe (its own dof, statrs'
/// quantile), so the search alarms `Ambiguous` naming the single set's
/// satellite and one of the pair, and reports the pair as runner-up.
#[test]
#[cfg(feature = "multifault")]
fn larger_consistent_alternative_is_ambiguous() {
    let c = cfg(3, 200, 3);
    let sats = epoch_sats(&sky14(), 1, &[(3, 8.0)]);
    let r = Raim::<N>::new()
        .process(&c, &Epoch::linear(0.0, &sats))
        .unwrap();
    assert_eq!(r.decision, Decision::Alarm);
    let report = r.multifault.unwrap();
    let best = report.best.unwrap();
    let alt = report.runner_up.unwrap();
    assert_eq!((best.count, best.satellites[0]), (1, ROW3));
    assert_eq!(alt.count, 2);
    assert!(!alt.satellites[..2].contains(&ROW3));
    let dof = 14 - 5;
    assert!(best.rss < chi2_upper(c.pfa, dof - 1), "{best:?}");
    assert!(alt.rss < chi2_upper(c.pwe, dof - 2), "{alt:?}");
    let Some(AlarmCause::Ambiguous { best: b, runner_up }) = r.alarm_cause else {
        panic!("{:?}", r.alarm_cause);
    };
    assert_eq!(b, ROW3);
    assert!(alt.satellites[..2].contains(&runner_up));
    assert_eq!(r.identified, Some(ROW3));
    assert!(r.exclusions.is_empty());
}

/// A fit of `count` satellites (the first `count` bits) with RSS `rss`.
fn fit(set: SatSet, rss: f64) -> SubsetFit<f64> {
    SubsetFit {
        set,
        count: set.count_ones() as usize,
        rss,
        bias: [0.0; MAX_FAULTS],
    }
}

/// A level's (best, runner-up).
type Pair = (Option<SubsetFit<f64>>, Option<SubsetFit<f64>>);

/// A search whose levels hold the given (best, runner-up) pairs.
fn searched(levels: [Pair; 3]) -> Search<f64> {
    let mut s = Search {
        levels: [Level::default(); MAX_FAULTS],
        t_max: 3,
        groups_total: 4,
        groups_processed: 4,
        budget_limited: false,
        swapped: 0,
        repaired: 0,
        q_min: None,
    };
    for (l, (best, runner_up)) in s.levels.iter_mut().zip(levels) {
        l.best = best;
        l.runner_up = runner_up;
    }
    s
}

/// SPEC §8.4's rule on hand-built searches, against statrs' quantiles
/// (dof 6, pfa 1e-5, pwe 1e-3): sizes without a set are skipped; the
/// first size whose best passes decides; a runner-up under the pwe
/// quantile is `Ambiguous`, at or above it an exclusion; a budget cut is
/// `Incomplete`; without the uniqueness check the best is excluded
/// outright; sizes that leave no dof are not searched.
#[test]
fn decide_follows_the_fewest_faults_rule() {
    let (pfa, pwe, dof) = (1e-5, 1e-3, 6);
    let pass = |t: usize| 0.9 * chi2_upper(pfa, dof - t);
    let fail = |t: usize| 1.1 * chi2_upper(pfa, dof - t);
    let we_pass = |t: usize| 0.9 * chi2_upper(pwe, dof - t);
    let we_fail = |t: usize| 1.1 * chi2_upper(pwe, dof - t);
    let b2 = fit(0b11, pass(2));
    // Size 1 empty, size 2 passes, runner-up far off: exclude the pair.
    let s = searched([
        (None, None),
        (Some(b2), Some(fit(0b110, we_fail(2)))),
        (None, None),
    ]);
    assert_eq!(decide(&s, 1, dof, pfa, pwe, true), Ok(Verdict::Exclude(b2)));
    // The runner-up also explains the data at level pwe.
    let r2 = fit(0b110, we_pass(2));
    let s = searched([(None, None), (Some(b2), Some(r2)), (None, None)]);
    assert_eq!(
        decide(&s, 1, dof, pfa, pwe, true),
        Ok(Verdict::Ambiguous {
            best: b2,
            runner_up: r2
        })
    );
    // Without the uniqueness check the same search excludes.
    assert_eq!(
        decide(&s, 1, dof, pfa, pwe, false),
        Ok(Verdict::Exclude(b2))
    );
    // A budget cut with no runner-up: incomplete, never an exclusion.
    let mut s = searched([
        (Some(fit(0b1, fail(1))), None),
        (Some(b2), None),
        (None, None),
    ]);
    s.budget_limited = true;
    assert_eq!(
        decide(&s, 1, dof, pfa, pwe, true),
        Ok(Verdict::Incomplete(b2))
    );
    // Starting from size 3 skips the passing pair; the triple fails.
    let s = searched([
        (None, None),
        (Some(b2), None),
        (Some(fit(0b111, fail(3))), None),
    ]);
    assert_eq!(
        decide(&s, 3, dof, pfa, pwe, true),
        Ok(Verdict::NoConsistentSet)
    );
    // dof 2 leaves sizes 2 and 3 unsearched: only size 1 counts.
    let s = searched([
        (Some(fit(0b1, 1e9)), None),
        (Some(fit(0b11, 0.0)), None),
        (Some(fit(0b111, 0.0)), None),
    ]);
    assert_eq!(
        decide(&s, 1, 2, pfa, pwe, true),
        Ok(Verdict::NoConsistentSet)
    );
}

/// The search's errors as the epoch's: a capacity stays a capacity with
/// its values; any other is the configured `t_max` out of [1, 3].
#[test]
#[cfg(feature = "multifault")]
fn search_errors_map_to_the_epoch_errors() {
    assert_eq!(
        multifault_error(
            MultifaultError::CapacityExceeded {
                have: 65,
                capacity: 64
            },
            2
        ),
        RaimError::CapacityExceeded {
            have: 65,
            capacity: 64
        }
    );
    assert_eq!(
        multifault_error(
            MultifaultError::TooManyFaults {
                t: 3,
                n: 7,
                m: 4,
                max: 2
            },
            3
        ),
        RaimError::OutOfRange {
            field: "t_max",
            value: 3.0,
            min: 1.0,
            max: 3.0
        }
    );
}

/// A covering built for another satellite count than the model's is
/// refused with the model's n, m and the covering's fault count.
#[test]
fn covering_of_another_size_is_refused() {
    let zero = ResidualModel::<f64, N>::from_projector(8, |_, _| 0.0, &[0.0; 8]).unwrap();
    let c = Covering::new(9, 4, 2).unwrap();
    let mut ws = Workspace::default();
    let mut g = GroupFit::default();
    assert_eq!(
        search(&zero, &c, 2, 10, 1e-4, &mut ws, &mut g, |_, _| {}),
        Err(MultifaultError::TooManyFaults {
            t: 2,
            n: 8,
            m: 4,
            max: 2
        })
    );
}

/// The projector of a single clock column over `n` satellites,
/// S = I - 1 1^T / n (SPEC §2 with H = 1), and its residuals for a bias
/// of `bias` on satellite `sat` and no noise.
fn clock_only(n: usize, sat: usize, bias: f64) -> ResidualModel<f64, N> {
    let s = |i: usize, j: usize| f64::from(u8::from(i == j)) - 1.0 / n as f64;
    let r: Vec<f64> = (0..n).map(|i| s(i, sat) * bias).collect();
    ResidualModel::from_projector(n, s, &r).unwrap()
}

/// Candidate sets the fit cannot take give no fit: the empty set, four
/// satellites (above MAX_FAULTS) and a satellite beyond the model's n.
/// The faulty satellite alone explains a noise-free bias exactly: RSS_T
/// is 0 (never negative) and its bias estimate is the bias in sigma units
/// (b = S_ii^-1 r_i = bias for this projector).
#[test]
fn subset_fits_refuse_what_they_cannot_take() {
    let model = clock_only(8, 2, 50.0);
    assert_eq!(fit_subset(&model, 0), None);
    assert_eq!(fit_subset(&model, 0b1111), None);
    assert_eq!(fit_subset(&model, 1 << 9), None);
    assert_eq!(fit_subset(&model, 0b1 | 1 << 8), None);
    let fit = fit_subset(&model, 1 << 2).unwrap();
    assert_eq!(fit.count, 1);
    assert!(fit.rss >= 0.0 && fit.rss < 1e-9, "{}", fit.rss);
    assert!((fit.bias[0] - 50.0).abs() < 1e-9, "{:?}", fit.bias);
}

/// A group naming a satellite beyond the model's n keeps it out of the
/// identifiable set and reports it swapped; a residual vector shorter
/// than n is a capacity error with the counts.
#[test]
fn groups_and_models_out_of_range() {
    let model = clock_only(8, 2, 50.0);
    let mut ws = Workspace::default();
    let mut g = GroupFit::default();
    reconstruct(&model, 0b11 | 1 << 9, 1e-4, &mut ws, &mut g);
    assert_eq!(g.swapped & 1 << 9, 1 << 9);
    assert_eq!(g.identifiable & 1 << 9, 0);
    assert_eq!(g.identifiable, 0b11);
    assert_eq!(
        ResidualModel::<f64, 8>::from_projector(4, |_, _| 0.0, &[0.0; 3]).err(),
        Some(MultifaultError::CapacityExceeded {
            have: 4,
            capacity: 8
        })
    );
}
