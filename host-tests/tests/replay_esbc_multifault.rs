//! ESBC (G+E+C, ~22 satellites) with the reconstruction FDE (SPEC §8,
//! docs/MULTIFAULT.md): 50 m on G15 and G28 from 01:00:00, then a third
//! 50 m fault on a Galileo satellite in view (the first
//! Galileo satellite of the 01:00:00 epoch). Every faulted epoch must
//! be identified and excluded with a solution kept, or be an alarm; there
//! must be no wrong exclusion.

mod replay_common;

use raim_core::config::FdeMethod;
use raim_core::{Config, Decision, SatId, System};
use raim_gnss::ranging::RangingOptions;
use replay_common::{geodetic_config, replay};

const OBS: &str = "ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz";
const NAV: &str = "ESBC00DNK_R_20201770000_01D_MN.rnx.gz";

fn reconstruction() -> Config {
    Config {
        fde_method: FdeMethod::Reconstruction {
            t_max: 3,
            group_budget: 1000,
        },
        max_exclusions: 3,
        ..geodetic_config()
    }
}

/// Checks the rows: no satellite outside `faulted` is ever excluded; every
/// epoch is Excluded (with exactly the faulted set) or an Alarm. Returns
/// the number of epochs excluded exactly.
fn check(rows: &[replay_common::Row], faulted: &[SatId]) -> usize {
    let mut exact = 0;
    for r in rows {
        for e in &r.excluded_any {
            assert!(faulted.contains(e), "wrong exclusion {e}: {r:?}");
        }
        match r.decision {
            Some(Decision::Excluded) => {
                let mut e = r.excluded.clone();
                e.sort();
                assert_eq!(e, faulted, "{r:?}");
                exact += 1;
            }
            Some(Decision::Alarm) => {}
            other => panic!("{other:?}: {r:?}"),
        }
    }
    exact
}

#[test]
fn two_faults_g15_g28_are_excluded() {
    let mut both = vec![SatId::new(System::Gps, 15), SatId::new(System::Gps, 28)];
    both.sort();
    let rows = replay(
        OBS,
        NAV,
        &RangingOptions::default(),
        &reconstruction(),
        &["step:G15+G28:50@01:00:00"],
        "01:00:00",
        "01:10:00",
    );
    assert_eq!(rows.len(), 21);
    let exact = check(&rows, &both);
    println!("G15+G28: {exact} of {} epochs excluded exactly", rows.len());
    assert_eq!(exact, rows.len());
}

#[test]
fn three_faults_g15_g28_and_a_galileo_satellite() {
    // The Galileo satellites in view at 01:00:00.
    let clean = replay(
        OBS,
        NAV,
        &RangingOptions::default(),
        &reconstruction(),
        &[],
        "01:00:00",
        "01:00:00",
    );
    assert_eq!(clean.len(), 1);
    let galileo: Vec<SatId> = clean[0]
        .in_view
        .iter()
        .copied()
        .filter(|s| s.system == System::Galileo)
        .collect();
    assert!(galileo.len() >= 3, "{galileo:?}");
    let third = galileo[0];
    let spec = format!("step:G15+G28+{third}:50@01:00:00");
    let mut all = vec![
        SatId::new(System::Gps, 15),
        SatId::new(System::Gps, 28),
        third,
    ];
    all.sort();
    let rows = replay(
        OBS,
        NAV,
        &RangingOptions::default(),
        &reconstruction(),
        &[&spec],
        "01:00:00",
        "01:10:00",
    );
    assert_eq!(rows.len(), 21);
    let exact = check(&rows, &all);
    println!(
        "G15+G28+{third}: {exact} of {} epochs excluded exactly",
        rows.len()
    );
    assert_eq!(exact, rows.len());
    // Today's FDE on the same epochs, for docs/MULTIFAULT.md.
    let today = replay(
        OBS,
        NAV,
        &RangingOptions::default(),
        &Config {
            max_exclusions: 3,
            ..geodetic_config()
        },
        &[&spec],
        "01:00:00",
        "01:10:00",
    );
    let count = |d| today.iter().filter(|r| r.decision == Some(d)).count();
    let wrong = today
        .iter()
        .filter(|r| r.excluded_any.iter().any(|e| !all.contains(e)))
        .count();
    println!(
        "today's FDE: {} excluded, {} alarms, {} epochs with a wrong exclusion",
        count(Decision::Excluded),
        count(Decision::Alarm),
        wrong
    );
}
