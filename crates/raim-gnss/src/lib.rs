//! raim-gnss: the host-side GNSS front end of the integrity monitor.
//!
//! It turns recorded receiver data (RINEX 2/3 observation + broadcast
//! navigation files) into the core's input (`raim_core::RangeObservation`,
//! SPEC §1 and §11): broadcast orbits and clocks for GPS, Galileo and
//! BeiDou (GEO included) and GLONASS (state vectors integrated by RK4,
//! `glonass`), the Earth-rotation correction, Klobuchar and
//! Saastamoinen, group delays and an elevation mask. It also injects
//! deterministic, seeded faults (steps, ramps, constellation biases, clock
//! jumps, heavy-tailed noise) for replay tests (docs/REPLAY.md).

pub mod error;
pub mod faults;
pub mod ranging;
pub mod rinex_guard;
pub mod rinex_io;
pub mod time;

// The broadcast-navigation layer is raim-nav's (no_std, shared with the
// firmware); its modules keep their paths here.
pub use raim_nav::{ephemeris, geometry, glonass, iono, tropo};

pub use error::GnssError;
pub use faults::{Fault, FaultKind, FaultPlan, Noise, Scenario};
pub use ranging::{prepare_epoch, PreparedEpoch, PreparedSat, RangingOptions};
pub use rinex_io::{NavData, ObsData, ObsEpoch};

/// Parse a satellite name such as "G24", "E11", "C07".
pub fn parse_sat(s: &str) -> Result<raim_core::SatId, GnssError> {
    let mut chars = s.trim().chars();
    let letter = chars
        .next()
        .ok_or_else(|| GnssError::BadSatellite(s.into()))?;
    let system = raim_core::System::from_letter(letter.to_ascii_uppercase())
        .ok_or_else(|| GnssError::BadSatellite(s.into()))?;
    let prn: u8 = chars
        .as_str()
        .parse()
        .map_err(|_| GnssError::BadSatellite(s.into()))?;
    Ok(raim_core::SatId::new(system, prn))
}

/// Parse a system letter.
pub fn parse_system(c: char) -> Result<raim_core::System, GnssError> {
    raim_core::System::from_letter(c.to_ascii_uppercase()).ok_or(GnssError::UnknownSystem(c))
}
