//! The PF monitor's decision on NaN and empty LLR lists (a NaN statistic
//! is an alarm, never an all clear) and its exclusion list's capacity.

extern crate std;

use super::*;
use crate::measurement::System;
use crate::pf::Ekf;

fn output(llr: &[(u8, f64)]) -> PfOutput<8> {
    let mut list = heapless::Vec::new();
    for &(prn, windowed) in llr {
        list.push(SatLlr {
            id: SatId::new(System::Gps, prn),
            llr: windowed,
            windowed,
        })
        .unwrap();
    }
    PfOutput {
        time_s: 0.0,
        position_m: None,
        clock_m: [0.0; MAX_SYSTEMS],
        drift_m_s: 0.0,
        decision: f64::NEG_INFINITY,
        threshold: 10.0,
        alarm: false,
        isolated: None,
        excluded: None,
        n_eff: 0.0,
        n_eff_before_ga: 0.0,
        used: llr.len(),
        main_collapsed: false,
        aux_collapsed: 0,
        clock_jump: false,
        llr: list,
    }
}

/// A NaN windowed LLR is the statistic, whatever comes after it (a larger
/// finite one, another NaN): the epoch alarms and isolates its satellite.
#[test]
fn a_nan_llr_alarms_and_is_isolated() {
    let cfg = PfConfig {
        exclude: false,
        ..PfConfig::default()
    };
    let mut m = std::boxed::Box::new(PfRaim::<f64, Ekf<f64>, 8>::new(1));
    let mut out = output(&[(1, 2.0), (2, f64::NAN), (3, 50.0), (4, f64::NAN)]);
    m.decide(&cfg, 10.0, 0.0, &mut out).unwrap();
    assert!(out.decision.is_nan());
    assert!(out.alarm);
    assert_eq!(out.isolated, Some(SatId::new(System::Gps, 2)));
    assert_eq!(out.excluded, None);
    // Finite values: the largest, against the threshold.
    let mut out = output(&[(1, 2.0), (3, 9.5)]);
    m.decide(&cfg, 10.0, 0.0, &mut out).unwrap();
    assert_eq!((out.decision, out.alarm, out.isolated), (9.5, false, None));
    // No LLR (every auxiliary filter collapsed): nothing decided.
    let mut out = output(&[]);
    m.decide(&cfg, 10.0, 0.0, &mut out).unwrap();
    assert_eq!((out.decision, out.alarm), (f64::NEG_INFINITY, false));
}

/// The exclusion list holds S satellites; one more is refused with its
/// count, and the list is unchanged.
#[test]
fn the_exclusion_list_holds_s_satellites() {
    let mut m = std::boxed::Box::new(PfRaim::<f64, Ekf<f64>, 4>::new(1));
    for prn in 1..=4 {
        m.exclude(SatId::new(System::Gps, prn), f64::from(prn))
            .unwrap();
    }
    assert_eq!(
        m.exclude(SatId::new(System::Gps, 5), 5.0),
        Err(PfError::Capacity {
            field: "excluded",
            have: 5,
            max: 4
        })
    );
    assert_eq!(m.excluded().len(), 4);
    assert_eq!(m.excluded()[3], (SatId::new(System::Gps, 4), 4.0));
}
