//! Speed and course over ground for the replay's RMC and VTG, from the
//! Doppler of the source (RINEX D observables, MSM5/MSM7 phase-range
//! rates, UBX doMes): the unit's rule (raim-server's
//! `stream::ground_velocity`, docs/RECEIVERS.md "Speed and course") on the
//! host's epochs. None unless the monitor's decision is `Ok` or `Excluded`
//! with a position; else the velocity solution
//! ([`raim_nav::velocity::solve`] through
//! [`raim_gnss::ranging::solve_velocity`]) at that position from the
//! satellites the answer used (an excluded satellite is left out), each
//! weighted by its range sigma; none with fewer than four rates or a
//! singular geometry. The velocity carries no integrity bound
//! (docs/REPLAY.md "Speed and course").

use raim_core::real::Real;
use raim_core::sigma::SigmaModel;
use raim_core::{Decision, RangeObservation};
use raim_gnss::ranging::PreparedEpoch;
use raim_proto::nmea::GroundVelocity;
use raim_proto::result::WireResult;

/// The speed and course of epoch `e` whose observations given to the
/// monitor were `sats` (faults included, in `e.sats`' order) and whose
/// answer is `wire`. A satellite without a sigma of its own is weighted
/// by `model` at its elevation, evaluated as the unit's stream receiver
/// evaluates a sigma (f32, raim-nav's `stream_sigma_for_m`), so that a
/// stream's velocity is the unit's to the bit.
pub fn ground_velocity(
    wire: &WireResult,
    e: &PreparedEpoch,
    sats: &[RangeObservation],
    model: &SigmaModel,
) -> Option<GroundVelocity> {
    if !matches!(wire.decision, Decision::Ok | Decision::Excluded) {
        return None;
    }
    let rx_m = wire.position_ecef_m?;
    let used = |id| wire.satellites.iter().any(|s| s.id == id && s.used);
    let model_sigma_m = |el_rad: f64| model.sigma::<f32>(el_rad as f32).to_f64();
    let v = raim_gnss::ranging::solve_velocity(&e.sats, sats, used, rx_m, model_sigma_m).ok()?;
    Some(GroundVelocity {
        speed_m_s: v.speed_over_ground_m_s(),
        course_rad: v.course_over_ground_rad(),
    })
}
