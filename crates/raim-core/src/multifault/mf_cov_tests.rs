//! The reconstruction FDE with the uniqueness check off (the best set is
//! excluded although a larger set without it is also consistent), and
//! the search's refusals.

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

/// A covering for fewer faults than `t_max` is refused with the model's n,
/// m and the covering's fault count; a model whose projector is zero (no
/// satellite has S_ii >= min_s_ii, no set has a nonsingular S_TT) has no
/// identifiable group, and the search says so with n and the groups tried.
#[test]
fn search_refuses_a_short_covering_and_a_model_with_no_identifiable_group() {
    use super::covering::Covering;
    use super::error::MultifaultError;
    use super::reconstruct::{GroupFit, ResidualModel, Workspace};
    use super::search;
    let zero = ResidualModel::<f64, 16>::from_projector(8, |_, _| 0.0, &[0.0; 8]).unwrap();
    let one = Covering::new(8, 4, 1).unwrap();
    let mut ws = Workspace::default();
    let mut g = GroupFit::default();
    assert_eq!(
        search(&zero, &one, 2, 10, 1e-4, &mut ws, &mut g, |_, _| {}).err(),
        Some(MultifaultError::TooManyFaults {
            t: 2,
            n: 8,
            m: 4,
            max: 1
        })
    );
    assert_eq!(
        search(&zero, &one, 1, 100, 1e-4, &mut ws, &mut g, |_, _| {}).err(),
        Some(MultifaultError::NoIdentifiableGroup {
            n: 8,
            groups: one.len()
        })
    );
}
