//! The short CI run of the multiple-fault Monte Carlo (the long run and
//! its committed output: docs/MULTIFAULT.md). On the same draws, the
//! reconstruction must make no more wrong exclusions than today's FDE, and
//! identify at least as many 3-fault sets correctly.
#[path = "../examples/multifault_mc/campaign.rs"]
mod campaign;

use campaign::Outcome;

#[test]
fn reconstruction_against_todays_fde_on_the_same_draws() {
    let tally = campaign::run(600, 7, 1000);
    assert!(tally.draws > 300, "{} kept", tally.draws);
    let (seq, rec) = (0, 1);
    let wrong = |m| {
        (0..3)
            .map(|t| tally.total(m, t, Outcome::WrongExclusion))
            .sum::<u64>()
    };
    assert!(
        wrong(rec) <= wrong(seq),
        "wrong exclusions {} > {}",
        wrong(rec),
        wrong(seq)
    );
    let c_rec = tally.total(rec, 2, Outcome::Correct);
    let c_seq = tally.total(seq, 2, Outcome::Correct);
    assert!(c_rec >= c_seq, "t = 3: correct {c_rec} < {c_seq}");
    // Large single faults are found or alarmed, never missed or wrongly
    // excluded: above 30 sigma, >= 50 % correct (the rest ambiguous).
    let (c, n) = (3..campaign::BINS)
        .map(|b| tally.bin(rec, 0, b, Outcome::Correct))
        .fold((0, 0), |a, x| (a.0 + x.0, a.1 + x.1));
    assert!(n > 20 && c as f64 / n as f64 >= 0.5, "{c} / {n}");
}
