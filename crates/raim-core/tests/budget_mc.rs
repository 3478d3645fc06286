//! The short CI run of the combined false-alarm Monte Carlo (the long run
//! and its output: docs/BUDGET.md). With a total of 2e-3 per epoch split
//! 0.5 / 0.45 / 0.05 among the snapshot test, the MCUSUM and ARAIM (ARAIM's
//! P_FA,vert is bounded at 1e-4), the combined event rate over 40,000
//! fault-free epochs must not exceed the total: the Clopper-Pearson 95 %
//! interval's lower end stays below it.
#[path = "../examples/budget_mc/sim.rs"]
mod sim;

/// Verifies: SPEC-12
#[test]
fn combined_false_alarms_stay_within_the_total() {
    const EPOCHS: u64 = 40_000;
    const TOTAL: f64 = 2e-3;
    let b = sim::budget(TOTAL, 0.5, 0.45, 0.05);
    let t = sim::run(&b, EPOCHS, 3, 2).unwrap();
    assert_eq!(t.epochs, EPOCHS);
    assert_eq!(t.refused, 0);
    let (lo, _) = sim::interval(t.combined, EPOCHS);
    assert!(lo <= TOTAL, "combined {} / {EPOCHS}", t.combined);
    // Each monitor within its own share.
    for (k, share) in [(t.snapshot, 0.5), (t.mcusum, 0.45), (t.araim, 0.05)] {
        let (lo, _) = sim::interval(k, EPOCHS);
        assert!(lo <= TOTAL * share, "{k} events at share {share}");
    }
    // The snapshot test is exact (chi-square): its count is not far below
    // its allocation either (the test can fail both ways).
    let (_, hi) = sim::interval(t.snapshot, EPOCHS);
    assert!(hi >= TOTAL * 0.5, "snapshot {} events", t.snapshot);
}
