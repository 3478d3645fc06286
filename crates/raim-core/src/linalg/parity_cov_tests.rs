//! S_ii's clamp to [0, 1] and the factorisation accessor.

use super::*;

#[test]
fn s_ii_is_clamped_to_the_unit_interval() {
    assert_eq!(clamp_unit(-1e-17f64), 0.0);
    assert_eq!(clamp_unit(1.0 + 1e-15f64), 1.0);
    assert_eq!(clamp_unit(0.25f64), 0.25);
    assert!(clamp_unit(f64::NAN).is_nan());
}

/// `qr()` is the factorisation of H: U^T applied to H's first column
/// gives (r_00, 0, ..., 0) with |r_00| the column's norm.
#[test]
fn qr_is_the_factorisation_of_h() {
    const N: usize = 8;
    let n = 6;
    let mut h = [[0.0f64; N]; MAX_STATES];
    let col0 = [1.0, 2.0, -1.0, 0.5, 3.0, -2.0];
    for i in 0..n {
        h[0][i] = col0[i];
        h[1][i] = (i as f64).sin();
        h[2][i] = 1.0;
    }
    let z = [0.0; N];
    let p = Parity::<N, f64>::new(&h, &z, n, 3).unwrap();
    assert_eq!((p.qr().rows(), p.qr().cols()), (n, 3));
    let mut x = [0.0; N];
    x[..n].copy_from_slice(&col0);
    p.qr().apply_ut(&mut x);
    let norm = col0.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!((x[0].abs() - norm).abs() < 1e-12, "{x:?}");
    for v in &x[1..n] {
        assert!(v.abs() < 1e-12, "{x:?}");
    }
}
