//! The covering helpers at their ends: binomials beyond t = 3 (0, as
//! documented), sets of all n >= 64 satellites, subsets of size 0, the
//! uncovered count with no group, and a design with no part.

extern crate std;

use super::*;

/// C(g, t) written out.
fn choose(g: usize, t: usize) -> usize {
    (0..t).fold(1, |acc, i| acc * (g - i) / (i + 1))
}

#[test]
fn binomials_and_the_full_set() {
    for g in 0..12 {
        for t in 0..=3 {
            if t <= g {
                assert_eq!(binomial(g, t), choose(g, t), "{g} {t}");
            }
        }
        assert_eq!(binomial(g, 4), 0);
    }
    assert_eq!(all(3), 0b111);
    assert_eq!(all(MAX_SATS), u64::MAX);
    assert_eq!(all(MAX_SATS + 6), u64::MAX);
}

#[test]
fn subsets_of_size_zero_and_uncovered_counts() {
    let mut calls = 0;
    for_each_subset(all(5), 0, |_| calls += 1);
    assert_eq!(calls, 0);
    // No group: every t-subset of 0..n is uncovered, C(n, t) of them.
    assert_eq!(uncovered(&[], 6, 2), choose(6, 2));
    assert_eq!(uncovered(&[], 7, 3), choose(7, 3));
    // One group holding every satellite covers them all.
    assert_eq!(uncovered(&[all(6)], 6, 2), 0);
}

#[test]
fn a_design_without_parts_has_no_group() {
    let c = Covering {
        n: 8,
        m: 4,
        t: 1,
        design: Design::Parts { parts: 0 },
    };
    assert!(c.is_empty());
    assert_eq!(c.group(0), None);
    let real = Covering::new(8, 4, 1).unwrap();
    assert!(!real.is_empty());
    assert_eq!(
        real.len(),
        (0..).take_while(|&i| real.group(i).is_some()).count()
    );
}
