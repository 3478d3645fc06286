//! A row under `min_s_ii` is no candidate, however large its residual.

use super::*;

/// Residuals (3, 1, 2) with S_ii (0.9, 0.01, 0.5): row 1's normalised
/// residual w = 1 / 0.1 = 10 is the largest, but S_ii 0.01 < 0.1 leaves
/// it out; the best is row 0 (w = 3 / sqrt 0.9 = 3.16), the runner-up
/// row 2 (w = 2 / sqrt 0.5 = 2.83).
#[test]
fn rows_under_min_s_ii_are_skipped() {
    let r = [3.0f64, 1.0, 2.0];
    let s = [0.9f64, 0.01, 0.5];
    let (best, second) = rank_rows(FiRule::Mle, &r, &s, 0.1);
    let (best, second) = (best.unwrap(), second.unwrap());
    assert_eq!((best.row, second.row), (0, 2));
    assert!((best.w - 3.0 / 0.9f64.sqrt()).abs() < 1e-12);
    assert!((second.w - 2.0 / 0.5f64.sqrt()).abs() < 1e-12);
    // Without the bound row 1 wins.
    let (best, _) = rank_rows(FiRule::Mle, &r, &s, 0.0);
    assert_eq!(best.unwrap().row, 1);
    // Every row under it: nothing.
    assert!(matches!(rank_rows(FiRule::Mle, &r, &s, 0.95), (None, None)));
}
