//! The pair search's skips (SPEC §8.4): rows under `min_s_ii`, and pairs
//! whose S_TT is singular (a constellation's only two satellites); the pair
//! statistic against a real solve without the pair; the singular
//! tolerance in both precisions.

extern crate std;

use super::*;
use crate::testutil::{linear_epoch, Rng, SKY8};

fn solve64(sky: &[(f64, f64)], seed: u64) -> Solution<8, f64> {
    let sats = linear_epoch(sky, 1.0, &mut Rng::new(seed), &[(2, 9.0)]);
    let epoch = Epoch::linear(0.0, &sats);
    let mut mask = [false; 8];
    mask[..sky.len()].fill(true);
    let mut out = Solution::empty();
    solve_from(&Config::default(), &epoch, &mask, Start::Cold, &mut out).unwrap();
    out
}

fn subset_sse(sky: &[(f64, f64)], seed: u64, drop: (usize, usize)) -> f64 {
    let sats = linear_epoch(sky, 1.0, &mut Rng::new(seed), &[(2, 9.0)]);
    let epoch = Epoch::linear(0.0, &sats);
    let mut mask = [false; 8];
    mask[..sky.len()].fill(true);
    mask[drop.0] = false;
    mask[drop.1] = false;
    let mut out = Solution::<8, f64>::empty();
    solve_from(&Config::default(), &epoch, &mask, Start::Cold, &mut out).unwrap();
    out.parity.sse()
}

#[test]
fn singular_tolerance_is_floored_at_100_eps() {
    assert_eq!(pair_singular_tol::<f64>(), 1e-9);
    assert_eq!(pair_singular_tol::<f32>(), 100.0 * f32::EPSILON);
}

/// The two best pairs are the two smallest subset statistics, each equal
/// to the weighted SSE of a real solve without the pair; a bound on S_ii
/// keeps the rows under it out of every pair, and a bound above every S_ii
/// leaves no pair.
#[test]
fn best_pairs_match_subset_solves_and_respect_min_s_ii() {
    let sol = solve64(&SKY8, 3);
    let [Some(b0), Some(b1)] = best_pairs(&sol.parity, 0.0) else {
        panic!("two pairs on eight satellites");
    };
    let mut all = std::vec::Vec::new();
    for j in 0..8 {
        for k in j + 1..8 {
            all.push(((j, k), subset_sse(&SKY8, 3, (j, k))));
        }
    }
    all.sort_by(|a, b| a.1.total_cmp(&b.1));
    assert_eq!(b0.rows, all[0].0);
    assert_eq!(b1.rows, all[1].0);
    assert!((b0.statistic - all[0].1).abs() < 1e-8 * (1.0 + all[0].1));
    assert!((b1.statistic - all[1].1).abs() < 1e-8 * (1.0 + all[1].1));

    // A bound between the S_ii: the rows under it appear in no pair.
    let mut s: std::vec::Vec<f64> = sol.parity.s_ii()[..8].to_vec();
    s.sort_by(f64::total_cmp);
    let bound = 0.5 * (s[3] + s[4]);
    let low = |r: usize| sol.parity.s_ii()[r] < bound;
    let [Some(c0), second] = best_pairs(&sol.parity, bound) else {
        panic!("four rows are above the bound");
    };
    for p in [Some(c0), second].into_iter().flatten() {
        assert!(!low(p.rows.0) && !low(p.rows.1), "{:?}", p.rows);
    }
    // Above every S_ii (S_ii <= 1): nothing.
    assert!(matches!(best_pairs(&sol.parity, 1.01), [None, None]));
}

/// The only two Galileo satellites of an epoch: without them the Galileo
/// clock has no row, so their S_TT is singular (S_jj S_kk - S_jk^2 = 0 to
/// rounding) and the pair is never proposed: the two best are the two
/// smallest subset statistics among the other pairs.
#[test]
fn a_constellations_only_pair_is_skipped() {
    let galileo = |mut sats: std::vec::Vec<crate::measurement::LinearObservation>| {
        sats[6].id = SatId::new(crate::measurement::System::Galileo, 1);
        sats[7].id = SatId::new(crate::measurement::System::Galileo, 2);
        sats
    };
    let solve_without = |drop: Option<(usize, usize)>| {
        let sats = galileo(linear_epoch(&SKY8, 1.0, &mut Rng::new(5), &[(2, 9.0)]));
        let epoch = Epoch::linear(0.0, &sats);
        let mut mask = [true; 8];
        if let Some((j, k)) = drop {
            mask[j] = false;
            mask[k] = false;
        }
        let mut out = Solution::<8, f64>::empty();
        solve_from(&Config::default(), &epoch, &mask, Start::Cold, &mut out).unwrap();
        out
    };
    let sol = solve_without(None);
    assert_eq!(sol.parity.dof(), 3);
    let [Some(b0), Some(b1)] = best_pairs(&sol.parity, 0.0) else {
        panic!("other pairs remain");
    };
    let mut all = std::vec::Vec::new();
    for j in 0..8 {
        for k in j + 1..8 {
            if (j, k) != (6, 7) {
                all.push(((j, k), solve_without(Some((j, k))).parity.sse()));
            }
        }
    }
    all.sort_by(|a, b| a.1.total_cmp(&b.1));
    assert_eq!((b0.rows, b1.rows), (all[0].0, all[1].0));
    assert!((b0.statistic - all[0].1).abs() < 1e-8 * (1.0 + all[0].1));
}

/// With an exclusion cap of 1 the pair search is not tried: a 50 m step
/// on one of eight satellites is excluded alone (the faulty one, GPS
/// PRN 3) and the subset passes.
#[test]
fn a_cap_of_one_excludes_the_single_faulty_satellite() {
    let cfg = Config {
        max_exclusions: 1,
        ..Config::default()
    };
    let mut thresholds = Thresholds::<8>::default();
    for seed in 0..5 {
        let sats = linear_epoch(&SKY8, 1.0, &mut Rng::new(seed), &[(2, 50.0)]);
        let epoch = Epoch::linear(0.0, &sats);
        let mut out = FdeOutcome::<8, f64>::empty();
        solve_from(&cfg, &epoch, &[true; 8], Start::Cold, &mut out.solution).unwrap();
        run(&cfg, &mut thresholds, &epoch, &mut out).unwrap();
        assert_eq!(out.exclusions.len(), 1, "seed {seed}");
        assert_eq!(
            out.exclusions[0].id,
            SatId::new(crate::measurement::System::Gps, 3)
        );
        assert!(!out.test.alarm(), "seed {seed}");
    }
}
