//! The ARAIM monitor's refusals of pseudorange epochs (SPEC §9 inputs):
//! a non-finite a-priori position, more satellites than the engine
//! holds, and an infinite sigma, each a typed error with its value.

extern crate std;

use super::monitor::{FdeLimits, Monitor, MonitorError, SatIsm};
use super::{AraimConfig, Ism};
use crate::measurement::{Epoch, RangeObservation, System};
use crate::testutil::{range_epoch, Rng, CLOCKS_GE_M, RX_ECEF_M, SKY_GE8};
use crate::{Config, Phase, RaimError};

fn entries(sats: &[RangeObservation]) -> std::vec::Vec<SatIsm> {
    sats.iter()
        .map(|o| SatIsm {
            id: o.id,
            sigma_ura_m: 0.75,
            sigma_ure_m: 0.5,
            b_nom_m: 0.5,
            p_sat: 1e-5,
        })
        .collect()
}

fn run<const N: usize>(
    sats: &[RangeObservation],
    apriori_m: Option<[f64; 3]>,
) -> Result<(), MonitorError> {
    let cfg = AraimConfig::default();
    let solver = Config::preset(Phase::Npa);
    let ism = Ism::with(&[System::Gps, System::Galileo], 1e-4);
    let mut monitor = std::boxed::Box::new(Monitor::<f64, N, 600>::new());
    monitor
        .epoch(
            &solver,
            &cfg,
            &ism,
            entries(sats).as_slice(),
            &Epoch::ranges(100.0, sats, apriori_m),
            FdeLimits::UNLIMITED,
        )
        .map(|_| ())
}

#[test]
fn range_epochs_refuse_bad_input() {
    let sats = range_epoch(
        RX_ECEF_M,
        &SKY_GE8,
        &CLOCKS_GE_M,
        1.0,
        &mut Rng::new(3),
        &[],
    );
    assert!(run::<16>(&sats, Some(RX_ECEF_M)).is_ok());
    let e = run::<16>(&sats, Some([RX_ECEF_M[0], f64::NAN, RX_ECEF_M[2]])).unwrap_err();
    assert!(
        matches!(
            e,
            MonitorError::Raim(RaimError::NotFinite {
                field: "apriori_m",
                index: 0,
                value
            }) if value.is_nan()
        ),
        "{e:?}"
    );
    assert_eq!(
        run::<6>(&sats, Some(RX_ECEF_M)).unwrap_err(),
        MonitorError::Raim(RaimError::CapacityExceeded {
            have: 8,
            capacity: 6
        })
    );
    let mut inf = sats.clone();
    inf[4].sigma_m = Some(f64::INFINITY);
    assert_eq!(
        run::<16>(&inf, Some(RX_ECEF_M)).unwrap_err(),
        MonitorError::Raim(RaimError::NonPositiveSigma {
            index: 4,
            sigma_m: f64::INFINITY
        })
    );
}
