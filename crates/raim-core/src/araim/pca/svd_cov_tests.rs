//! The principal components of degenerate covariances: a zero matrix
//! (no variance: no component needed, nothing covered) and a NaN entry
//! (refused).

use super::*;

#[test]
fn zero_and_nan_covariances() {
    let zero = nalgebra::SMatrix::<f64, 4, 4>::zeros();
    let p = principal(zero, 0.9).unwrap();
    assert_eq!(p.values, [0.0; 4]);
    assert_eq!((p.k, p.covered), (0, 0.0));
    let mut nan = nalgebra::SMatrix::<f64, 4, 4>::identity();
    nan[(1, 2)] = f64::NAN;
    nan[(2, 1)] = f64::NAN;
    assert!(principal(nan, 0.9).is_none());
    // A diagonal covariance: its entries, sorted, and k for the share.
    let d =
        nalgebra::SMatrix::<f64, 4, 4>::from_diagonal(&nalgebra::Vector4::new(1.0, 6.0, 2.0, 1.0));
    let p = principal(d, 0.7).unwrap();
    for (got, want) in p.values.iter().zip([6.0, 2.0, 1.0, 1.0]) {
        assert!((got - want).abs() < 1e-12, "{:?}", p.values);
    }
    // 6 / 10 < 0.7 <= 8 / 10: two components.
    assert_eq!(p.k, 2);
    assert!((p.covered - 0.8).abs() < 1e-12);
}
