//! From raw pseudoranges to the core's input (SPEC §1, §11): per satellite,
//! the broadcast orbit and clock at transmit time, the Earth-rotation
//! correction, Klobuchar, Saastamoinen and the group delay; then the
//! elevation mask. The result is a list of `raim_core::RangeObservation`
//! whose pseudoranges are fully corrected and whose positions are in the
//! ECEF frame of the reception time, as the core expects (docs/CORE.md).

use std::collections::BTreeMap;

use raim_core::solve::solve;
use raim_core::{Config, Epoch, RangeObservation, SatId, System};

use crate::ephemeris::{Kepler, C_M_S, WEEK_S};
use crate::geometry::{az_el, distance_m, rotate_earth};
use crate::iono::{scale_to_frequency, F_B1I_HZ, F_L1_HZ};
use crate::rinex_io::{CodeObs, NavData, ObsEpoch};
use crate::tropo::saastamoinen_m;

/// Capacity used for the bootstrap position solve.
const BOOTSTRAP_CAPACITY: usize = 64;
/// A solved position is trusted as the linearisation point for the
/// corrections only if it is within this of the Earth's surface, m.
const SURFACE_BAND_M: f64 = 100_000.0;

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
}

/// Default code preferences: GPS and QZSS L1 C/A (RINEX 3 "C1C", RINEX 2
/// "C1"), Galileo E1 (C1C pilot+data as Septentrio logs it, C1X, C1B),
/// BeiDou B1I (C2I in RINEX 3.02+, C1I in 3.01).
pub fn default_codes() -> BTreeMap<System, Vec<String>> {
    let v = |c: &[&str]| c.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    BTreeMap::from([
        (System::Gps, v(&["C1C", "C1"])),
        (System::Galileo, v(&["C1C", "C1X", "C1B"])),
        (System::Beidou, v(&["C2I", "C1I"])),
        (System::Qzss, v(&["C1C", "C1"])),
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
        }
    }
}

/// Why a satellite of the epoch was not used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rejection {
    SystemNotSelected,
    NoCode,
    NoEphemeris,
    BelowMask { elevation_rad: f64 },
}

/// One satellite ready for the core, with the terms that went into it.
#[derive(Debug, Clone, PartialEq)]
pub struct PreparedSat {
    /// Corrected pseudorange and rotated satellite position.
    pub obs: RangeObservation,
    pub code: String,
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

/// Carrier frequency of a code, for the ionospheric scaling.
fn carrier_hz(system: System, code: &str) -> f64 {
    match (system, code.get(1..2)) {
        (System::Beidou, Some("2")) | (System::Beidou, Some("1")) if code.ends_with('I') => {
            F_B1I_HZ
        }
        _ => F_L1_HZ,
    }
}

/// Group delay applies to the codes the broadcast value is defined for:
/// GPS/QZSS L1 C/A (TGD), Galileo E1 (BGD E1/E5b), BeiDou B1I (TGD1).
fn group_delay_applies(system: System, code: &str) -> bool {
    match system {
        System::Gps | System::Qzss => code == "C1C" || code == "C1",
        System::Galileo => code.starts_with("C1"),
        System::Beidou => code == "C2I" || code == "C1I",
        System::Glonass => false,
    }
}

/// Pick the first preferred code present.
fn pick_code<'a>(codes: &[String], have: &'a [CodeObs]) -> Option<&'a CodeObs> {
    codes
        .iter()
        .find_map(|c| have.iter().find(|o| &o.code == c))
}

/// Satellite position (ECEF at transmit time, not yet rotated) and clock,
/// from the receiver time tag and the pseudorange: the transmit time in
/// GPS time is t_rx - P/c - dt_sv (exact whatever the receiver clock).
fn transmit_state(k: &Kepler, t_rx_gps_s: f64, pseudorange_m: f64) -> ([f64; 3], f64) {
    let t_sv = t_rx_gps_s - pseudorange_m / C_M_S;
    let dts = k.state(t_sv).clock_s;
    let st = k.state(t_sv - dts);
    (st.position_m, st.clock_s)
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
    let mut sats = Vec::new();
    let mut rejected = Vec::new();
    for (&id, have) in &epoch.sats {
        if !opts.systems.contains(&id.system) {
            rejected.push((id, Rejection::SystemNotSelected));
            continue;
        }
        let Some(code) = opts.codes.get(&id.system).and_then(|c| pick_code(c, have)) else {
            rejected.push((id, Rejection::NoCode));
            continue;
        };
        let Some(k) = nav.select(id, epoch.time_gps_s) else {
            rejected.push((id, Rejection::NoEphemeris));
            continue;
        };
        let p = code.value_m;
        let (pos_tx, clock_s) = transmit_state(k, epoch.time_gps_s, p);
        let transit_s = match rx_m {
            Some(rx) => {
                // Two fixed-point steps: the rotation moves the satellite by
                // < 150 m, changing the transit by < 0.5 us.
                let t0 = distance_m(pos_tx, rx) / C_M_S;
                distance_m(rotate_earth(pos_tx, t0), rx) / C_M_S
            }
            None => p / C_M_S,
        };
        let pos = rotate_earth(pos_tx, transit_s);
        let group_delay_m = if opts.group_delay && group_delay_applies(id.system, &code.code) {
            C_M_S * k.group_delay_s
        } else {
            0.0
        };
        let (mut az, mut el, mut iono_m, mut tropo_m) =
            (0.0, std::f64::consts::FRAC_PI_2, 0.0, 0.0);
        if let (Some(rx), true) = (rx_m, full) {
            let (a, e, g) = az_el(rx, pos);
            az = a;
            el = e;
            if el < opts.elevation_mask_rad {
                rejected.push((id, Rejection::BelowMask { elevation_rad: el }));
                continue;
            }
            if opts.iono {
                if let Some(kb) = &nav.klobuchar {
                    let tow = epoch.time_gps_s.rem_euclid(WEEK_S);
                    let l1 = kb.delay_l1_m(g.lat_rad, g.lon_rad, az, el, tow);
                    iono_m = scale_to_frequency(l1, carrier_hz(id.system, &code.code));
                }
            }
            if opts.tropo {
                tropo_m = saastamoinen_m(g.lat_rad, g.height_m, el);
            }
        }
        let sat_clock_m = C_M_S * clock_s;
        let corrected = p + sat_clock_m - group_delay_m - iono_m - tropo_m;
        sats.push(PreparedSat {
            obs: RangeObservation {
                id,
                pseudorange_m: corrected,
                position_m: pos,
                sigma_m: None,
            },
            code: code.code.clone(),
            raw_pseudorange_m: p,
            elevation_rad: el,
            azimuth_rad: az,
            sat_clock_m,
            group_delay_m,
            iono_m,
            tropo_m,
        });
    }
    PreparedEpoch {
        time_gps_s: epoch.time_gps_s,
        reference_m: rx_m,
        sats,
        rejected,
    }
}

/// A least-squares position from `sats` (unit weights until the position
/// is near the surface, then the core's default elevation model).
fn bootstrap_position(
    time_s: f64,
    sats: &[RangeObservation],
    apriori: Option<[f64; 3]>,
) -> Option<[f64; 3]> {
    if sats.len() > BOOTSTRAP_CAPACITY || sats.len() < 4 {
        return None;
    }
    let mut mask = [false; BOOTSTRAP_CAPACITY];
    for m in mask.iter_mut().take(sats.len()) {
        *m = true;
    }
    let cfg = Config::default();
    let sol =
        solve::<BOOTSTRAP_CAPACITY>(&cfg, &Epoch::ranges(time_s, sats, apriori), &mask).ok()?;
    let p = sol.position_ecef_m?;
    let r = distance_m(p, [0.0; 3]);
    ((r - raim_core::frames::WGS84_A_M).abs() < SURFACE_BAND_M).then_some(p)
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
    let first = build(nav, epoch, opts, apriori_m, false);
    let reference =
        bootstrap_position(epoch.time_gps_s, &first.observations(), apriori_m).or(apriori_m);
    match reference {
        Some(rx) => build(nav, epoch, opts, Some(rx), true),
        None => first,
    }
}
