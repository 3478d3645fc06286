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
    let [c0, c1, c2, c3, ..] = &mut h;
    for (i, (((x, y), z), clk)) in c0
        .iter_mut()
        .zip(c1.iter_mut())
        .zip(c2.iter_mut())
        .zip(c3.iter_mut())
        .enumerate()
        .take(n)
    {
        let a = i as f64 * 0.7;
        let b = 0.2 + (i % 9) as f64 * 0.15;
        *x = b.cos() * a.sin();
        *y = b.cos() * a.cos();
        *z = b.sin();
        *clk = 1.0;
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
