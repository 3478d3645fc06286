//! From raw pseudorange epochs to the core's input (SPEC §1, §11): per
//! satellite, the code to use and the broadcast ephemeris in force, then
//! raim-nav's corrections ([`raim_nav::ranging::correct`]: orbit and clock
//! at transmit time, Earth rotation, Klobuchar, Saastamoinen, group delay
//! or the iono-free combination, the elevation mask). The result is a list
//! of `raim_core::RangeObservation` whose pseudoranges are fully corrected
//! and whose positions are in the ECEF frame of the reception time, as the
//! core expects (docs/CORE.md).

use std::collections::BTreeMap;

use raim_core::{RangeObservation, SatId, System};
pub use raim_nav::ranging::{band_hz, iono_free_noise_factor, Rejection};
use raim_nav::ranging::{bootstrap_position, correct, split_pair, Corrections, SatInput};

use crate::rinex_io::{CodeObs, NavData, ObsEpoch};

/// Capacity used for the bootstrap position solve.
pub const BOOTSTRAP_CAPACITY: usize = 64;

/// What to use and which corrections to apply.
#[derive(Debug, Clone, PartialEq)]
pub struct RangingOptions {
    pub systems: Vec<System>,
    /// Pseudorange code per system, in order of preference ("C1C", "C1", ...).
    pub codes: BTreeMap<System, Vec<String>>,
    pub elevation_mask_rad: f64,
    pub iono: bool,
    pub tropo: bool,
    pub group_delay: bool,
    /// The sigma model of GLONASS satellites (SPEC §3's model with its own
    /// URA, [`crate::glonass::glonass_ura_m`]): each gets an explicit
    /// `sigma_m` = this model at its elevation. None: the core's model, as
    /// for every other system.
    pub glonass_sigma: Option<raim_core::sigma::SigmaModel>,
}

impl RangingOptions {
    /// The corrections part, as raim-nav takes it.
    pub fn corrections(&self) -> Corrections {
        Corrections {
            elevation_mask_rad: self.elevation_mask_rad,
            iono: self.iono,
            tropo: self.tropo,
            group_delay: self.group_delay,
            glonass_sigma: self.glonass_sigma,
        }
    }
}

/// Default code preferences: GPS and QZSS L1 C/A (RINEX 3 "C1C", RINEX 2
/// "C1"), Galileo E1 (C1C pilot+data as Septentrio logs it, C1X, C1B),
/// BeiDou B1I (C2I in RINEX 3.02+, C1I in 3.01), GLONASS L1 C/A (C1C, C1).
pub fn default_codes() -> BTreeMap<System, Vec<String>> {
    let v = |c: &[&str]| c.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    BTreeMap::from([
        (System::Gps, v(&["C1C", "C1"])),
        (System::Galileo, v(&["C1C", "C1X", "C1B"])),
        (System::Beidou, v(&["C2I", "C1I"])),
        (System::Qzss, v(&["C1C", "C1"])),
        (System::Glonass, v(&["C1C", "C1"])),
    ])
}

impl Default for RangingOptions {
    fn default() -> Self {
        RangingOptions {
            systems: vec![System::Gps, System::Galileo, System::Beidou],
            codes: default_codes(),
            elevation_mask_rad: 10f64.to_radians(),
            iono: true,
            tropo: true,
            group_delay: true,
            glonass_sigma: None,
        }
    }
}

/// One satellite ready for the core, with the terms that went into it.
#[derive(Debug, Clone, PartialEq)]
pub struct PreparedSat {
    /// Corrected pseudorange and rotated satellite position.
    pub obs: RangeObservation,
    pub code: String,
    /// C/N0 of the code's (first) signal, whole dB-Hz, 0 when unknown
    /// (`raim_nav::ranging::cn0_dbhz_u8`): GSV's.
    pub cn0_dbhz: u8,
    pub raw_pseudorange_m: f64,
    pub elevation_rad: f64,
    pub azimuth_rad: f64,
    /// c x satellite clock (polynomial + relativity), m; added.
    pub sat_clock_m: f64,
    /// c x group delay, m; subtracted.
    pub group_delay_m: f64,
    /// Klobuchar slant delay at the signal's frequency, m; subtracted.
    pub iono_m: f64,
    /// Saastamoinen slant delay, m; subtracted.
    pub tropo_m: f64,
}

/// One epoch ready for the core.
#[derive(Debug, Clone, PartialEq)]
pub struct PreparedEpoch {
    pub time_gps_s: f64,
    /// Linearisation point of the corrections (the bootstrap solution).
    pub reference_m: Option<[f64; 3]>,
    pub sats: Vec<PreparedSat>,
    pub rejected: Vec<(SatId, Rejection)>,
}

impl PreparedEpoch {
    /// The core's observations, in satellite order.
    pub fn observations(&self) -> Vec<RangeObservation> {
        self.sats.iter().map(|s| s.obs).collect()
    }
}

/// Pick the first preferred code present: a single code, or a pair
/// "C1W+C2W" (both present) for the iono-free combination; returns the
/// code name, its one or two pseudoranges and the C/N0 of its (first)
/// signal.
fn pick_code(codes: &[String], have: &[CodeObs]) -> Option<(String, f64, Option<f64>, u8)> {
    let find = |c: &str| have.iter().find(|o| o.code == c);
    let cn0 = |o: &CodeObs| raim_nav::ranging::cn0_dbhz_u8(o.cn0_dbhz);
    codes.iter().find_map(|c| match split_pair(c) {
        Some((a, b)) => {
            let first = find(a)?;
            Some((c.clone(), first.value_m, Some(find(b)?.value_m), cn0(first)))
        }
        None => find(c).map(|o| (c.clone(), o.value_m, None, cn0(o))),
    })
}

/// Corrected observations of one epoch, with every correction computed at
/// the receiver position `rx_m` (None: no atmosphere, no mask, and the
/// Earth rotation from the pseudorange's transit time).
fn build(
    nav: &NavData,
    epoch: &ObsEpoch,
    opts: &RangingOptions,
    rx_m: Option<[f64; 3]>,
    full: bool,
) -> PreparedEpoch {
    let corrections = opts.corrections();
    let mut sats = Vec::new();
    let mut rejected = Vec::new();
    for (&id, have) in &epoch.sats {
        if !opts.systems.contains(&id.system) {
            rejected.push((id, Rejection::SystemNotSelected));
            continue;
        }
        let Some((code, p1_m, p2_m, cn0_dbhz)) =
            opts.codes.get(&id.system).and_then(|c| pick_code(c, have))
        else {
            rejected.push((id, Rejection::NoCode));
            continue;
        };
        let Some(eph) = nav.select_broadcast(id, epoch.time_gps_s) else {
            rejected.push((id, Rejection::NoEphemeris));
            continue;
        };
        let input = SatInput {
            id,
            code: &code,
            p1_m,
            p2_m,
            eph,
            orbit_arc: nav.orbit_arcs,
        };
        match correct(
            &input,
            epoch.time_gps_s,
            rx_m,
            full,
            &corrections,
            nav.klobuchar.as_ref(),
        ) {
            Ok(c) => sats.push(PreparedSat {
                obs: c.obs,
                code,
                cn0_dbhz,
                raw_pseudorange_m: c.raw_pseudorange_m,
                elevation_rad: c.elevation_rad,
                azimuth_rad: c.azimuth_rad,
                sat_clock_m: c.sat_clock_m,
                group_delay_m: c.group_delay_m,
                iono_m: c.iono_m,
                tropo_m: c.tropo_m,
            }),
            Err(why) => rejected.push((id, why)),
        }
    }
    PreparedEpoch {
        time_gps_s: epoch.time_gps_s,
        reference_m: rx_m,
        sats,
        rejected,
    }
}

/// The bootstrap pass of [`prepare_epoch`]: each satellite's clock- and
/// rotation-corrected range, no atmosphere and no mask, at `apriori_m`
/// (the ranges the bootstrap position is solved from).
pub fn bootstrap_pass(
    nav: &NavData,
    epoch: &ObsEpoch,
    opts: &RangingOptions,
    apriori_m: Option<[f64; 3]>,
) -> PreparedEpoch {
    build(nav, epoch, opts, apriori_m, false)
}

/// Every correction and the mask of [`prepare_epoch`] at the receiver
/// position `rx_m`, whatever solved it.
pub fn prepare_at(
    nav: &NavData,
    epoch: &ObsEpoch,
    opts: &RangingOptions,
    rx_m: [f64; 3],
) -> PreparedEpoch {
    build(nav, epoch, opts, Some(rx_m), true)
}

/// Prepare one epoch: a bootstrap solution from the clock- and
/// rotation-corrected ranges (starting at `apriori_m`, e.g. the header's
/// approximate position), then every correction and the mask at that
/// position. If the bootstrap fails, `apriori_m` is used as the reference.
pub fn prepare_epoch(
    nav: &NavData,
    epoch: &ObsEpoch,
    opts: &RangingOptions,
    apriori_m: Option<[f64; 3]>,
) -> PreparedEpoch {
    let first = bootstrap_pass(nav, epoch, opts, apriori_m);
    let reference =
        bootstrap_position::<BOOTSTRAP_CAPACITY>(&first.observations(), apriori_m).or(apriori_m);
    match reference {
        Some(rx) => prepare_at(nav, epoch, opts, rx),
        None => first,
    }
}
