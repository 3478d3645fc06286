//! The same linearised epochs for raim-core and for the peer
//! `sidereon-core` 3.0.6 (`quality::raim_fde_design`), for the side-by-side
//! criterion bench (`benches/peer.rs`) and the callgrind counts
//! (`examples/peer_cost.rs`). Issue 10; BENCHMARKS.md.

use raim_core::{LinearObservation, SatId, System};

/// n satellites on raim-core's bench sky (benches/epoch.rs): golden-angle
/// azimuths, elevations 10..85 deg, unit sigma, deterministic noise,
/// GPS and Galileo alternating; `fault_m` on satellite 2.
pub fn sky(n: usize, fault_m: f64) -> Vec<LinearObservation> {
    (0..n)
        .map(|i| {
            let az = (i as f64 * 137.507_764_f64).rem_euclid(360.0);
            let el = 10.0 + 75.0 * ((i * 7) % n) as f64 / n as f64;
            let noise = ((i as f64 * 12.9898).sin() * 43758.5453).fract() - 0.5;
            let r = noise + if i == 2 { fault_m } else { 0.0 };
            let sys = if i.is_multiple_of(2) {
                System::Gps
            } else {
                System::Galileo
            };
            let mut o = LinearObservation::from_az_el(
                SatId::new(sys, i as u8 + 1),
                az.to_radians(),
                el.to_radians(),
                r,
            );
            o.sigma_m = Some(1.0);
            o
        })
        .collect()
}

/// The peer's rows for the same model: design row [-e, -n, -u, clock_G,
/// clock_E] (the partials of the range in ENU and the two receiver clocks),
/// the residual, weight 1 / sigma^2 = 1.
pub fn peer_rows(sats: &[LinearObservation]) -> Vec<sidereon_core::quality::RangeFdeRow> {
    sats.iter()
        .map(|s| {
            let norm = s.los_enu.iter().map(|v| v * v).sum::<f64>().sqrt();
            let gps = s.id.system == System::Gps;
            sidereon_core::quality::RangeFdeRow {
                id: s.id.to_string(),
                residual_m: s.residual_m,
                design_row: vec![
                    -s.los_enu[0] / norm,
                    -s.los_enu[1] / norm,
                    -s.los_enu[2] / norm,
                    if gps { 1.0 } else { 0.0 },
                    if gps { 0.0 } else { 1.0 },
                ],
                weight: 1.0,
            }
        })
        .collect()
}

/// The peer's options at the project's Pfa (3.3333e-7), one exclusion
/// (its default, RTKLIB's).
pub fn peer_options() -> sidereon_core::quality::RangeFdeOptions {
    let mut o = sidereon_core::quality::RangeFdeOptions::default();
    o.p_fa = raim_core::Config::default().pfa;
    o
}
