//! The residual model's capacity: a model type wider than the 64-bit
//! satellite sets refuses more than MAX_SATS = 64 satellites, from a
//! projector and from a parity space alike.

extern crate std;

use super::*;
use crate::measurement::MAX_STATES;

#[test]
fn more_than_64_satellites_are_refused() {
    let r = [0.0; 65];
    let e = ResidualModel::<f64, 70>::from_projector(65, |i, j| if i == j { 1.0 } else { 0.0 }, &r)
        .unwrap_err();
    assert_eq!(
        e,
        MultifaultError::CapacityExceeded {
            have: 65,
            capacity: 64
        }
    );
    // A 65-row parity space (a clock column and a spread of directions).
    let n = 65;
    let mut h = [[0.0f64; 70]; MAX_STATES];
    for i in 0..n {
        let a = i as f64 * 0.7;
        let b = 0.2 + (i % 9) as f64 * 0.15;
        h[0][i] = b.cos() * a.sin();
        h[1][i] = b.cos() * a.cos();
        h[2][i] = b.sin();
        h[3][i] = 1.0;
    }
    let parity = Parity::<70, f64>::new(&h, &[0.0; 70], n, 4).unwrap();
    let mut model = std::boxed::Box::new(ResidualModel::<f64, 70>::empty());
    assert_eq!(
        model.fill_from_parity(&parity),
        Err(MultifaultError::CapacityExceeded {
            have: 65,
            capacity: 64
        })
    );
}
