//! The peer's ARAIM inputs from raim-core's (shared by the araim_peer
//! bench and the araim_peer_cost example). The receiver is put at latitude
//! 0, longitude 0, and each ENU geometry row (minus the line of sight) is
//! rotated into ECEF, as the peer's own App. D test does; C_int and C_acc
//! are given as effective sigmas, so the peer applies no elevation model.

use raim_core::araim::AraimSat;
use raim_core::System;
use sidereon_core::araim as peer;
use sidereon_core::dop::{ecef_to_enu_rotation, LineOfSight};
use sidereon_core::frame::Wgs84Geodetic;
use sidereon_core::{GnssSatelliteId, GnssSystem};

fn peer_system(s: System) -> GnssSystem {
    match s {
        System::Gps => GnssSystem::Gps,
        System::Galileo => GnssSystem::Galileo,
        System::Beidou => GnssSystem::BeiDou,
        System::Glonass => GnssSystem::Glonass,
        System::Qzss => GnssSystem::Qzss,
    }
}

pub fn peer_inputs(sats: &[AraimSat<f64>], p_const: f64) -> (peer::AraimGeometry, peer::Ism) {
    let receiver = Wgs84Geodetic::new(0.0, 0.0, 0.0).unwrap();
    let r = ecef_to_enu_rotation(receiver.lat_rad, receiver.lon_rad);
    let mut rows = Vec::new();
    let mut ism_sats = Vec::new();
    let mut systems: Vec<GnssSystem> = Vec::new();
    for s in sats {
        let system = peer_system(s.id.system);
        if !systems.contains(&system) {
            systems.push(system);
        }
        let id = GnssSatelliteId::new(system, s.id.prn).unwrap();
        let [e, n, u] = s.g_enu.map(|x| -x);
        rows.push(peer::AraimRow {
            id,
            line_of_sight: LineOfSight::new(
                r[0][0] * e + r[1][0] * n + r[2][0] * u,
                r[0][1] * e + r[1][1] * n + r[2][1] * u,
                r[0][2] * e + r[1][2] * n + r[2][2] * u,
            ),
            system,
            elevation_rad: u.clamp(-1.0, 1.0).asin(),
        });
        ism_sats.push(peer::SatelliteIsm::new_with_effective_sigmas(
            id,
            0.75,
            0.5,
            s.b_nom_m,
            s.p_sat,
            s.c_int_m2.sqrt(),
            s.c_acc_m2.sqrt(),
        ));
    }
    let constellations = systems
        .iter()
        .map(|&system| {
            peer::ConstellationIsm::new(
                system,
                p_const,
                peer::SatelliteIsmModel::new(0.75, 0.5, 0.5, sats[0].p_sat),
            )
        })
        .collect();
    let geometry = peer::AraimGeometry {
        rows,
        receiver,
        clock_systems: systems,
        ut1_degraded: None,
    };
    (geometry, peer::Ism::new(constellations, ism_sats))
}

