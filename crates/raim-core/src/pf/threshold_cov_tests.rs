//! The interpolation's segment whose first node is uncertified (NaN).

use super::*;

/// A NaN upper node refuses a Pfa inside its segment (10^-2.25 between
/// -2 and -2.5), naming the Pfa; the next segment, certified, answers
/// linearly (10^-2.75: halfway between 1 and 2).
#[test]
fn a_nan_upper_node_refuses_its_segment() {
    let row = [f64::NAN, 1.0, 2.0];
    let pfa = 10f64.powf(-2.25);
    assert_eq!(
        interpolate(&row, pfa),
        Err(PfError::NotCalibrated {
            field: "pfa",
            value: pfa
        })
    );
    let mid = interpolate(&row, 10f64.powf(-2.75)).unwrap();
    assert!((mid - 1.5).abs() < 1e-12, "{mid}");
}
