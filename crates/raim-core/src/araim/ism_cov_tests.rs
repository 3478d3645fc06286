//! The cross-field rule P_THRES < PHMI_VERT + PHMI_HOR (a positive
//! adjusted PHMI), with every field inside its own bound.

use super::*;
use crate::config_bounds::araim as b;

#[test]
fn p_thres_must_leave_a_positive_adjusted_phmi() {
    let cfg = AraimConfig {
        phmi_vert: b::PHMI_VERT.min,
        phmi_hor: b::PHMI_HOR.min,
        p_thres: b::P_THRES.max,
        ..AraimConfig::default()
    };
    assert_eq!(
        cfg.validate(),
        Err(AraimError::OutOfRange {
            field: "p_thres",
            index: 0,
            value: 1e-7,
            min: 1e-10,
            max: 2e-9,
        })
    );
    // Just under the sum it is accepted.
    let ok = AraimConfig {
        p_thres: 1.5e-9,
        ..cfg
    };
    assert_eq!(ok.validate(), Ok(()));
}
