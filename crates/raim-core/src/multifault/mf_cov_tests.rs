//! The reconstruction FDE with the uniqueness check off: the best set is
//! excluded although a larger set without it is also consistent.

extern crate std;

use super::tests::{epoch_sats, sky14};
use crate::config::{Config, FdeMethod, Phase};
use crate::measurement::{Epoch, SatId, System};
use crate::monitor::Raim;
use crate::result::Decision;

fn cfg(t_max: u8) -> Config {
    Config {
        fde_method: FdeMethod::Reconstruction {
            t_max,
            group_budget: 200,
        },
        max_exclusions: 3,
        ..Config::preset(Phase::Npa)
    }
}

/// The 8 m fault on sky14's row 3 that `larger_consistent_alternative_is_ambiguous`
/// (run_tests) reports as ambiguous: with `require_unique_exclusion` off,
/// the best single set, row 3 (Galileo PRN 4), is excluded and the subset
/// passes.
#[test]
fn without_the_uniqueness_check_the_best_set_is_excluded() {
    let c = Config {
        require_unique_exclusion: false,
        ..cfg(3)
    };
    let sats = epoch_sats(&sky14(), 1, &[(3, 8.0)]);
    let r = Raim::<32>::new()
        .process(&c, &Epoch::linear(0.0, &sats))
        .unwrap();
    let row3 = SatId::new(System::Galileo, 4);
    assert_eq!(r.exclusions.len(), 1, "{:?}", r.exclusions);
    assert_eq!(r.exclusions[0].id, row3);
    assert!(!r.test.alarm());
    assert_ne!(r.decision, Decision::Alarm);
}
