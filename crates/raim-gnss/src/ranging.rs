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
use raim_nav::glonass::{l1_hz, l2_hz};
pub use raim_nav::ranging::{band_hz, iono_free_noise_factor, Rejection};
use raim_nav::ranging::{
    bootstrap_position, correct, split_pair, transmit_state_motion, transmit_time_s, Broadcast,
    Corrections, SatInput,
};
use raim_nav::velocity::{
    glonass_motion, range_rate, solve, RangeRate, RateObservation, ReceiverVelocity, SatMotion,
    VelocityError,
};

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
    /// The satellite's range rate and motion for the velocity solution
    /// ([`satellite_rate`]), when the source gives a Doppler for it and
    /// the epoch has a reference position.
    pub rate: Option<RangeRate>,
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

/// The carrier frequency of a signal (RINEX code "C1C", "D1", "P2"), Hz,
/// for its Doppler: a GLONASS FDMA L1 or L2 signal on the satellite's
/// frequency channel `k` (from its navigation message), every other
/// signal its band's ([`band_hz`]); None for a band not known (GLONASS
/// CDMA L3 among them) or a GLONASS signal without its channel.
pub fn signal_carrier_hz(system: System, code: &str, k: Option<i8>) -> Option<f64> {
    match (system, code.get(1..2)) {
        (System::Glonass, Some("1")) => k.map(l1_hz),
        (System::Glonass, Some("2")) => k.map(l2_hz),
        (System::Glonass, _) => None,
        _ => band_hz(system, code),
    }
}

/// The range rate (m/s, positive receding) a satellite ranged with `code`
/// (one code or a pair) takes, by the unit's rule (raim-nav's stream
/// receiver, docs/RECEIVERS.md "Speed and course"): the rate of its code's
/// signal (the pair's first), else of the pair's second, else of the
/// first of its other signals, in code order, that has one (a range rate
/// is the same on every carrier but for the ionosphere's rate, a few
/// mm/s). A Doppler in Hz is turned into a rate on its own signal's
/// carrier ([`signal_carrier_hz`]; GLONASS by the channel `k`).
pub fn code_rate_m_s(system: System, code: &str, have: &[CodeObs], k: Option<i8>) -> Option<f64> {
    let rate = |o: &CodeObs| {
        let carrier = signal_carrier_hz(system, &o.code, k);
        o.rate?.range_rate_m_s(carrier)
    };
    let of = |c: &str| have.iter().find(|o| o.code == c).and_then(rate);
    let (first, second) = split_pair(code).map_or((code, None), |(a, b)| (a, Some(b)));
    of(first).or_else(|| second.and_then(of)).or_else(|| {
        let mut others: Vec<&CodeObs> = have.iter().collect();
        others.sort_by(|a, b| a.code.cmp(&b.code));
        others.into_iter().find_map(rate)
    })
}

/// A satellite's velocity and clock drift at the transmit time of its
/// signal received at `t_rx_gps_s`, as the unit's stream receiver takes
/// them: a Keplerian orbit's from the same evaluation as its transmit
/// state ([`raim_nav::ranging::transmit_state_motion`]: on its arc when
/// the navigation data came from a stream, else exact); a GLONASS orbit
/// integrated to [`transmit_time_s`] (the velocity of the ICD's
/// integration). None when the transmit time cannot be formed.
pub fn satellite_motion(s: &SatInput<'_>, t_rx_gps_s: f64) -> Option<SatMotion> {
    match s.eph {
        Broadcast::Kepler(_) | Broadcast::Orbit(_) => {
            transmit_state_motion(s, t_rx_gps_s, true).ok()?.1
        }
        Broadcast::Glonass(g) => {
            let t = transmit_time_s(s, t_rx_gps_s).ok()?;
            let (_, v) = g.propagate_pz90(t);
            Some(glonass_motion(v, g.gamma_n))
        }
    }
}

/// The [`RangeRate`] of one satellite of an epoch: its rate
/// ([`code_rate_m_s`]) with its motion at the transmit time
/// ([`satellite_motion`]), the velocity turned into the frame of the
/// reception instant over the transit from `sat_position_m` (already
/// turned) to the reference position `rx_m`
/// ([`raim_nav::velocity::range_rate`]). None without a rate.
pub fn satellite_rate(
    s: &SatInput<'_>,
    have: &[CodeObs],
    t_rx_gps_s: f64,
    sat_position_m: [f64; 3],
    rx_m: [f64; 3],
) -> Option<RangeRate> {
    let rate_m_s = code_rate_m_s(s.id.system, s.code, have, s.eph.frequency_channel())?;
    let motion = satellite_motion(s, t_rx_gps_s)?;
    Some(range_rate(rate_m_s, &motion, sat_position_m, rx_m))
}

/// The receiver's velocity and clock drift at `rx_m` (the monitor's
/// solved position) from the Doppler of an epoch's satellites
/// ([`raim_nav::velocity::solve`], the unit's solution): the satellites of
/// `sats` with a rate for which `used` holds, their positions from `obs`
/// (the observations the monitor was given, in the same order), each
/// weighted by its range sigma: the observation's own, else
/// `model_sigma_m` at its elevation.
pub fn solve_velocity(
    sats: &[PreparedSat],
    obs: &[RangeObservation],
    used: impl Fn(SatId) -> bool,
    rx_m: [f64; 3],
    model_sigma_m: impl Fn(f64) -> f64,
) -> Result<ReceiverVelocity, VelocityError> {
    let mut rows = sats.iter().zip(obs).filter_map(|(s, o)| {
        let rate = s.rate?;
        used(o.id).then(|| RateObservation {
            sat_position_m: o.position_m,
            rate,
            sigma_m: o.sigma_m.unwrap_or_else(|| model_sigma_m(s.elevation_rad)),
        })
    });
    solve(rx_m, &mut rows)
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
                rate: rx_m.filter(|_| full).and_then(|rx| {
                    satellite_rate(&input, have, epoch.time_gps_s, c.obs.position_m, rx)
                }),
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

#[cfg(test)]
mod rate_tests {
    use super::*;
    use crate::rinex_io::{doppler_matches, SignalRate};

    fn obs(code: &str, rate: Option<SignalRate>) -> CodeObs {
        CodeObs {
            code: code.into(),
            value_m: 2.2e7,
            cn0_dbhz: None,
            rate,
        }
    }

    /// A RINEX 3 D observable serves the code of its band and attribute
    /// only; a RINEX 2 one (no attribute) every code of its band.
    #[test]
    fn doppler_observables_match_their_codes() {
        assert!(doppler_matches("1C", "C1C"));
        assert!(!doppler_matches("1C", "C1W"));
        assert!(!doppler_matches("1C", "C2C"));
        assert!(doppler_matches("5Q", "C5Q"));
        assert!(doppler_matches("1", "C1"));
        assert!(doppler_matches("1", "P1"));
        assert!(!doppler_matches("1", "P2"));
        assert!(doppler_matches("2", "P2"));
        assert!(!doppler_matches("1", ""));
    }

    /// The carriers: a GLONASS FDMA signal on its channel (L1 1602 +
    /// 0.5625 k MHz, L2 1246 + 0.4375 k MHz, GLONASS ICD 5.1 §3.3.1.1),
    /// none without the channel or on a CDMA band; the other systems
    /// their band's.
    #[test]
    fn carriers_of_the_signals() {
        let close = |a: Option<f64>, b: f64| a.is_some_and(|a| (a - b).abs() < 1e-3);
        assert!(close(
            signal_carrier_hz(System::Glonass, "C1C", Some(-7)),
            1598.0625e6
        ));
        assert!(close(
            signal_carrier_hz(System::Glonass, "C2P", Some(6)),
            1248.625e6
        ));
        assert_eq!(signal_carrier_hz(System::Glonass, "C1C", None), None);
        assert_eq!(signal_carrier_hz(System::Glonass, "C3Q", Some(0)), None);
        assert!(close(
            signal_carrier_hz(System::Gps, "C5Q", None),
            1176.45e6
        ));
        assert!(close(
            signal_carrier_hz(System::Galileo, "C7Q", None),
            1207.14e6
        ));
        assert!(close(
            signal_carrier_hz(System::Beidou, "C2I", None),
            1561.098e6
        ));
    }

    /// The unit's rule for the rate a satellite takes: its code's
    /// signal's, else the pair's second's, else the first of its other
    /// signals in code order; a Doppler as -D c / f on its own carrier;
    /// none when no signal has one.
    #[test]
    fn the_rate_of_the_ranging_code_first() {
        let d = |hz| Some(SignalRate::Doppler { hz });
        let r = |m_s| Some(SignalRate::RangeRate { m_s });
        let l1 = 1575.42e6;
        let have = [obs("C1C", d(1000.0)), obs("C2W", r(7.0))];
        let got = code_rate_m_s(System::Gps, "C1C+C2W", &have, None).unwrap();
        assert!(
            (got + 1000.0 * raim_nav::ephemeris::C_M_S / l1).abs() < 1e-9,
            "{got}"
        );
        let have = [obs("C1C", None), obs("C2W", r(7.0)), obs("C1W", r(9.0))];
        assert_eq!(
            code_rate_m_s(System::Gps, "C1C+C2W", &have, None),
            Some(7.0)
        );
        // Another signal: the first in code order with a rate.
        let have = [obs("C5Q", r(5.0)), obs("C1W", r(9.0)), obs("C1C", None)];
        assert_eq!(code_rate_m_s(System::Gps, "C1C", &have, None), Some(9.0));
        let have = [obs("C1C", None), obs("C2W", None)];
        assert_eq!(code_rate_m_s(System::Gps, "C1C+C2W", &have, None), None);
        // A GLONASS Doppler needs its channel.
        let have = [obs("C1C", d(1000.0))];
        assert_eq!(code_rate_m_s(System::Glonass, "C1C", &have, None), None);
        let got = code_rate_m_s(System::Glonass, "C1C", &have, Some(1)).unwrap();
        assert!(
            (got + 1000.0 * raim_nav::ephemeris::C_M_S / 1602.5625e6).abs() < 1e-9,
            "{got}"
        );
        // A non-finite Doppler is none.
        let have = [obs("C1C", d(f64::NAN))];
        assert_eq!(code_rate_m_s(System::Gps, "C1C", &have, None), None);
    }
}
