//! The observation weight's interval when time jumps to infinity, and a
//! hold released by its age.

use super::*;
use crate::measurement::{SatId, System};

/// The weight is 1 / sqrt(I(dt, tau)) with I = (1 + rho) / (1 - rho),
/// rho = exp(-dt / tau) (SPEC §7.1): 0 on the first epoch (no interval
/// yet), then the interval's; a non-finite interval keeps the last one.
#[test]
fn observation_weight_keeps_the_last_finite_interval() {
    let mut m = Mcusum::<8, f64>::new();
    assert_eq!(m.observation_weight(100.0, 30.0), 0.0);
    let w = m.observation_weight(101.0, 30.0);
    let rho = (-1.0f64 / 30.0).exp();
    let want = 1.0 / ((1.0 + rho) / (1.0 - rho)).sqrt();
    assert!((w - want).abs() < 1e-12, "{w} {want}");
    assert_eq!(m.observation_weight(f64::INFINITY, 30.0), w);
    // White noise: weight 1 whatever the interval.
    assert_eq!(m.observation_weight(5.0, 0.0), 1.0);
}

/// A hold lasts `hold_s` seconds: kept at its age limit, released past it,
/// and released when its satellite leaves.
#[test]
fn holds_are_released_by_age_and_absence() {
    let g5 = SatId::new(System::Gps, 5);
    let mut m = Mcusum::<8, f64>::new();
    m.hold(g5, 10.0);
    m.release(60.0, 50.0, |_| true);
    assert!(m.is_held(g5));
    m.release(60.5, 50.0, |_| true);
    assert!(!m.is_held(g5));
    m.hold(g5, 70.0);
    m.release(71.0, 50.0, |id| id != g5);
    assert!(m.held().is_empty());
}

/// A hold that lies in the future (time went backwards: a new run) is
/// released.
#[test]
fn a_hold_from_the_future_is_released() {
    let g7 = SatId::new(System::Gps, 7);
    let mut m = Mcusum::<8, f64>::new();
    m.hold(g7, 100.0);
    m.release(50.0, 1e6, |_| true);
    assert!(!m.is_held(g7));
}
