//! ESBC (G+E+C, ~22 satellites): steps on G15 from 01:00:00 and the G15 +
//! G28 double fault, on a 10-minute window. The README's RTKLIB facts: a
//! 20 m step excluded in ~95 % of epochs, 30 and 50 m in all; the double
//! fault leaves it without a solution (it excludes one satellite only).

mod replay_common;

use raim_core::{Decision, SatId, System};
use raim_gnss::ranging::RangingOptions;
use replay_common::{geodetic_config, replay};

const OBS: &str = "ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz";
const NAV: &str = "ESBC00DNK_R_20201770000_01D_MN.rnx.gz";

#[test]
fn clean_window_has_no_alarm_and_no_exclusion() {
    let rows = replay(
        OBS,
        NAV,
        &RangingOptions::default(),
        &geodetic_config(),
        &[],
        "00:55:00",
        "01:10:00",
    );
    assert_eq!(rows.len(), 31);
    for r in &rows {
        assert!(r.n >= 20, "{r:?}");
        assert_eq!(r.decision, Some(Decision::Ok), "{r:?}");
    }
}

/// 20 m and 50 m on G15: excluded (and only G15) at every faulted epoch.
///
/// Verifies: SPEC-5, TOOL-REPLAY
#[test]
fn g15_steps_are_excluded_every_epoch() {
    let g15 = SatId::new(System::Gps, 15);
    for bias in [20, 50] {
        let f = format!("step:G15:{bias}@01:00:00");
        let rows = replay(
            OBS,
            NAV,
            &RangingOptions::default(),
            &geodetic_config(),
            &[&f],
            "01:00:00",
            "01:10:00",
        );
        assert_eq!(rows.len(), 21);
        for r in &rows {
            assert_eq!(r.decision, Some(Decision::Excluded), "{bias} m {r:?}");
            assert_eq!(r.excluded, vec![g15], "{bias} m {r:?}");
        }
    }
}

/// 50 m on G15 and G28 together: both excluded, a solution kept.
#[test]
fn double_fault_is_excluded_with_a_solution_kept() {
    let both = [SatId::new(System::Gps, 15), SatId::new(System::Gps, 28)];
    let rows = replay(
        OBS,
        NAV,
        &RangingOptions::default(),
        &geodetic_config(),
        &["step:G15+G28:50@01:00:00"],
        "01:00:00",
        "01:10:00",
    );
    for r in &rows {
        assert_eq!(r.decision, Some(Decision::Excluded), "{r:?}");
        let mut e = r.excluded.clone();
        e.sort();
        assert_eq!(e, both, "{r:?}");
    }
}
