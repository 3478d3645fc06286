//! The f32/f64 equivalence suite, short form (CI): the replay files in
//! windows, the committed vectors and 20,000 seeded Monte Carlo epochs,
//! each through `Raim::<N, f32>` and `Raim::<N, f64>` side by side.
//! Decisions, causes, identifications and exclusions must be identical
//! except for near-threshold ties (counted, and bounded here); statistics
//! and PLs within the stated tolerances. The full form (whole files,
//! 10^6 epochs) is `cargo run --release -p host-tests --example
//! f32_equivalence`, with its output in docs/F32_EQUIVALENCE.md.

mod equivalence_common;

use equivalence_common::*;

/// Ties allowed in the short form's Monte Carlo: mostly dof-1 epochs under
/// MLE, where every w_i^2 equals D^2 (a one-dimensional parity space) and
/// rounding alone picks the identified satellite (~0.15 % of the epochs).
const MC_TIES_MAX: usize = 60;

fn check(t: &Tally, ties_max: usize) {
    eprintln!("{TABLE_HEAD}\n{}", t.row());
    for d in &t.disagreements {
        eprintln!("  {d:?}");
    }
    for o in &t.out_of_tolerance {
        eprintln!("  out of tolerance: {o}");
    }
    assert_eq!(
        t.ties(Tie::Unexplained),
        0,
        "{}: unexplained disagreements {:?}",
        t.name,
        t.disagreements
    );
    assert!(t.disagreements.len() <= ties_max, "{}", t.name);
    assert!(
        t.out_of_tolerance.is_empty(),
        "{}: {:?}",
        t.name,
        t.out_of_tolerance
    );
    assert!(t.max_stat_rel <= STAT_REL_TOL && t.max_pl_rel <= PL_REL_TOL);
    assert!(t.max_pl_rel_weak <= PL_REL_TOL_WEAK);
    // Not vacuous: both precisions ran and agreed on most epochs.
    assert!(t.agree * 10 >= t.epochs * 9, "{}", t.name);
}

#[test]
fn f32_matches_f64_on_replay_windows() {
    let windows: [(&str, (&str, &str)); 4] = [
        ("0759 50 m G24", ("00:18:00", "00:42:00")),
        ("0759 50 m G24, MCUSUM", ("00:18:00", "00:30:00")),
        ("ESBC 50 m G15+G28", ("00:59:00", "01:05:00")),
        ("GEOP G+E 60 m G12 + t3 noise", ("+0", "+40")),
    ];
    for mut case in replay_cases() {
        let Some((_, w)) = windows.iter().find(|(n, _)| *n == case.name) else {
            continue;
        };
        case.window = Some(*w);
        let t = run_replay(&case);
        assert!(t.epochs >= 13, "{}: {} epochs", case.name, t.epochs);
        check(&t, 0);
        // The faulted windows exercise exclusion, not only Ok.
        assert!(t.decisions[1] + t.decisions[3] > 0, "{}", case.name);
    }
}

/// Verifies: FW-EQUIV
#[test]
fn f32_matches_f64_on_the_vectors() {
    let t = run_vectors();
    check(&t, 0);
}

#[test]
fn f32_matches_f64_on_a_seeded_monte_carlo() {
    let t = run_monte_carlo(1, 0..20_000);
    check(&t, MC_TIES_MAX);
    // Every decision kind occurs.
    assert!(t.decisions.iter().all(|&d| d > 0), "{:?}", t.decisions);
}
