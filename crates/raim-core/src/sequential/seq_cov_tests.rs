//! The MCUSUM's refusals to exclude (SPEC §7.4): a detection with no
//! identifiable satellite (`Unidentifiable`) and one on a single parity
//! dof (`NoRedundancy`); and `Raim::reset_mcusum`.

extern crate std;
use super::*;
use crate::config::{Carry, Phase};
use crate::measurement::{LinearObservation, System};
use crate::monitor::Raim;
use crate::testutil::{linear_epoch, Rng, SKY8};
use std::vec::Vec;

fn mcusum_cfg() -> Config {
    let mut c =
        Config::preset(Phase::Npa).split_false_alarm_budget(crate::config::DEFAULT_SNAPSHOT_SHARE);
    c.mcusum.carry = Carry::Transport;
    c
}

/// Six GPS satellites in two symmetric rings (S_ii 0.293 and 0.374, see
/// snapshot::fde's `no_identifiable_row_alarms_unidentifiable`) with
/// `min_s_ii` 0.5 and a persistent 3 m bias: every MCUSUM alarm is
/// `Unidentifiable`, names no one and excludes nothing.
#[test]
fn mcusum_alarm_without_an_identifiable_row_is_unidentifiable() {
    let c = Config {
        min_s_ii: 0.5,
        ..mcusum_cfg()
    };
    let mut raim = Raim::<16>::new();
    let mut rng = Rng::new(11);
    let mut alarms = 0;
    for t in 0..300 {
        let sats: Vec<LinearObservation> = (0..6)
            .map(|i| {
                let el_deg: f64 = if i % 2 == 0 { 30.0 } else { 40.0 };
                let mut o = LinearObservation::from_az_el(
                    SatId::new(System::Gps, i as u8 + 1),
                    (i as f64 * 60.0).to_radians(),
                    el_deg.to_radians(),
                    rng.normal() + if i == 2 { 3.0 } else { 0.0 },
                );
                o.sigma_m = Some(1.0);
                o
            })
            .collect();
        let r = raim.process(&c, &Epoch::linear(t as f64, &sats)).unwrap();
        let m = r.mcusum.unwrap();
        if m.alarm && !r.initial_test.alarm() {
            alarms += 1;
            assert_eq!(r.decision, Decision::Alarm, "t {t}");
            assert_eq!(r.alarm_cause, Some(AlarmCause::Unidentifiable), "t {t}");
            assert!(m.identified.is_none() && r.exclusions.is_empty(), "t {t}");
        }
    }
    assert!(alarms >= 1, "{alarms}");
}

/// Five GPS satellites: one parity dof. A persistent 4 m bias makes the
/// MCUSUM alarm; with one dof no subset can be tested, so the alarm is
/// `NoRedundancy` and nothing is excluded. `reset_mcusum` then empties
/// the accumulated vector.
#[test]
fn mcusum_alarm_on_one_dof_is_no_redundancy() {
    let sky: Vec<(f64, f64)> = SKY8.iter().copied().take(5).collect();
    let c = mcusum_cfg();
    let mut raim = Raim::<16>::new();
    let mut rng = Rng::new(12);
    let mut alarms = 0;
    for t in 0..300 {
        let sats = linear_epoch(&sky, 1.0, &mut rng, &[(2, 4.0)]);
        let r = raim.process(&c, &Epoch::linear(t as f64, &sats)).unwrap();
        assert_eq!(r.test.dof, 1);
        let m = r.mcusum.unwrap();
        if m.alarm && !r.initial_test.alarm() {
            alarms += 1;
            assert_eq!(r.decision, Decision::Alarm, "t {t}");
            assert_eq!(r.alarm_cause, Some(AlarmCause::NoRedundancy), "t {t}");
            assert!(r.exclusions.is_empty(), "t {t}");
        }
    }
    assert!(alarms >= 1, "{alarms}");
    // Accumulate once more, then reset: the vector is empty.
    let sats = linear_epoch(&sky, 1.0, &mut rng, &[(2, 4.0)]);
    raim.process(&c, &Epoch::linear(300.0, &sats)).unwrap();
    assert!(raim.mcusum().norm() > 0.0);
    raim.reset_mcusum();
    assert_eq!(raim.mcusum().norm(), 0.0);
}
