//! Reading RINEX 2/3 observation and navigation files (plain or gzip)
//! through the `rinex` crate, into the plain structures this crate uses:
//! epochs of raw pseudoranges, and Keplerian broadcast ephemerides.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use raim_core::{SatId, System};
use rinex::navigation::NavMessageType;
use rinex::prelude::{Constellation, Observable, Rinex, TimeScale};

use crate::ephemeris::Kepler;
use crate::error::GnssError;
use crate::glonass::{GlonassEphemeris, GlonassIcdFields};
use crate::iono::Klobuchar;

/// Open a RINEX file: gzip by its `.gz` suffix. `Rinex::from_file` panics
/// on a missing file, so existence is checked first.
pub fn open(path: &Path) -> Result<Rinex, GnssError> {
    if !path.is_file() {
        return Err(GnssError::FileNotFound(path.to_path_buf()));
    }
    let gz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"));
    let r = if gz {
        Rinex::from_gzip_file(path)
    } else {
        Rinex::from_file(path)
    };
    r.map_err(|e| GnssError::Parse {
        path: path.to_path_buf(),
        detail: e.to_string(),
    })
}

/// The system of a `rinex` constellation, for the systems we model.
pub fn system_of(c: Constellation) -> Option<System> {
    match c {
        Constellation::GPS => Some(System::Gps),
        Constellation::Galileo => Some(System::Galileo),
        Constellation::BeiDou => Some(System::Beidou),
        Constellation::QZSS => Some(System::Qzss),
        Constellation::Glonass => Some(System::Glonass),
        _ => None,
    }
}

/// One pseudorange code of one satellite.
#[derive(Debug, Clone, PartialEq)]
pub struct CodeObs {
    /// RINEX observable name: "C1" (RINEX 2), "C1C", "C2I", ...
    pub code: String,
    pub value_m: f64,
    /// The signal's C/N0, dB-Hz, when the source gives it: the RINEX 3
    /// S observable of the same band and attribute ("S1C" for "C1C"; RINEX
    /// 2's S1/S2 are in receiver units and not read), an MSM's DF403 or
    /// DF408, a UBX RXM-RAWX cno.
    pub cn0_dbhz: Option<f64>,
    /// The signal's Doppler measurement, when the source gives it: a
    /// RINEX D observable of the same band ([`doppler_matches`]), an
    /// MSM5/MSM7 phase-range rate, a UBX doMes.
    pub rate: Option<SignalRate>,
}

/// A signal's Doppler measurement, in the form its source gives it
/// (docs/REPLAY.md "Speed and course"); the replay turns it into a range
/// rate (`crate::ranging`, [`SignalRate::range_rate_m_s`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SignalRate {
    /// A Doppler shift, Hz, positive for an approaching satellite (RINEX
    /// 3.05 §5.9: D observables; u-blox RXM-RAWX/RXM-RAW doMes).
    Doppler { hz: f64 },
    /// A phase-range rate, m/s, positive for a receding satellite (RTCM
    /// 10403.3 MSM5/MSM7 DF399 + DF404), as the unit keeps it: whole mm/s
    /// (`raim_recv::rtcm`).
    RangeRate { m_s: f64 },
}

impl SignalRate {
    /// The range rate, m/s (positive receding): a Doppler shift D on a
    /// carrier of `carrier_hz` is -D c / f (RINEX 3.05 §5.9); None when
    /// the carrier is unknown or the result is not finite.
    pub fn range_rate_m_s(self, carrier_hz: Option<f64>) -> Option<f64> {
        let r = match self {
            SignalRate::RangeRate { m_s } => m_s,
            SignalRate::Doppler { hz } => -hz * crate::ephemeris::C_M_S / carrier_hz?,
        };
        r.is_finite().then_some(r)
    }
}

/// Whether the RINEX Doppler observable `doppler` ("D1C" in RINEX 3, "D1"
/// in RINEX 2, without its "D") is the Doppler of the pseudorange code
/// `code` ("C1C", "C1", "P1"): the same band and attribute in RINEX 3; in
/// RINEX 2 (no attribute) the same band, so that D1 serves C1 and P1.
pub fn doppler_matches(doppler: &str, code: &str) -> bool {
    let Some(signal) = code.get(1..) else {
        return false;
    };
    match doppler.len() {
        1 => signal.get(..1) == Some(doppler),
        _ => signal == doppler,
    }
}

/// One observation epoch: receiver time and every satellite's pseudoranges.
#[derive(Debug, Clone, PartialEq)]
pub struct ObsEpoch {
    /// Receiver time tag, GPS seconds since 1980-01-06.
    pub time_gps_s: f64,
    pub sats: BTreeMap<SatId, Vec<CodeObs>>,
}

/// An observation file reduced to what single-point positioning needs.
#[derive(Debug, Clone)]
pub struct ObsData {
    pub path: PathBuf,
    /// APPROX POSITION XYZ from the header, if present and non-zero.
    pub approx_position_m: Option<[f64; 3]>,
    pub epochs: Vec<ObsEpoch>,
}

impl ObsData {
    /// Load an observation file. A corrupt epoch record is refused with
    /// `GnssError::BadEpoch` naming the line, and a panic inside the
    /// `rinex` crate becomes `GnssError::Parse` (`rinex_guard`).
    pub fn load(path: &Path) -> Result<Self, GnssError> {
        if !path.is_file() {
            return Err(GnssError::FileNotFound(path.to_path_buf()));
        }
        crate::rinex_guard::check_observation_epochs(path)?;
        crate::rinex_guard::no_panic(path, || Self::load_unguarded(path))
    }

    fn load_unguarded(path: &Path) -> Result<Self, GnssError> {
        let r = open(path)?;
        if !r.is_observation_rinex() {
            return Err(GnssError::WrongKind {
                path: path.to_path_buf(),
                expected: "observation",
            });
        }
        let approx_position_m = r
            .header
            .rx_position
            .map(|(x, y, z)| [x, y, z])
            .filter(|p| p.iter().map(|v| v * v).sum::<f64>() > 1e12);
        let mut epochs = Vec::new();
        for (key, obs) in r.observations_iter() {
            // Event records (power failure, antenna moved, ...) carry no ranges.
            if !key.flag.is_ok() {
                continue;
            }
            let t = key.epoch.to_time_scale(TimeScale::GPST).to_gpst_seconds();
            let mut sats: BTreeMap<SatId, Vec<CodeObs>> = BTreeMap::new();
            for s in &obs.signals {
                let Observable::PseudoRange(code) = &s.observable else {
                    continue;
                };
                let Some(system) = system_of(s.sv.constellation) else {
                    continue;
                };
                if !(s.value.is_finite() && s.value > 1e6) {
                    continue;
                }
                let id = SatId::new(system, s.sv.prn);
                sats.entry(id).or_default().push(CodeObs {
                    code: code.clone(),
                    value_m: s.value,
                    cn0_dbhz: None,
                    rate: None,
                });
            }
            // Each code's C/N0: the RINEX 3 S observable of its signal.
            for s in &obs.signals {
                let Observable::SSI(name) = &s.observable else {
                    continue;
                };
                let (Some(system), Some(signal)) =
                    (system_of(s.sv.constellation), name.strip_prefix('S'))
                else {
                    continue;
                };
                if signal.len() != 2 || !s.value.is_finite() {
                    continue;
                }
                let Some(codes) = sats.get_mut(&SatId::new(system, s.sv.prn)) else {
                    continue;
                };
                if let Some(c) = codes
                    .iter_mut()
                    .find(|c| c.code.strip_prefix('C') == Some(signal))
                {
                    c.cn0_dbhz = Some(s.value);
                }
            }
            // Each code's Doppler: the D observable of its signal.
            for s in &obs.signals {
                let Observable::Doppler(name) = &s.observable else {
                    continue;
                };
                let (Some(system), Some(signal)) =
                    (system_of(s.sv.constellation), name.strip_prefix('D'))
                else {
                    continue;
                };
                if !(1..=2).contains(&signal.len()) || !s.value.is_finite() {
                    continue;
                }
                let Some(codes) = sats.get_mut(&SatId::new(system, s.sv.prn)) else {
                    continue;
                };
                for c in codes
                    .iter_mut()
                    .filter(|c| doppler_matches(signal, &c.code))
                {
                    c.rate = Some(SignalRate::Doppler { hz: s.value });
                }
            }
            epochs.push(ObsEpoch {
                time_gps_s: t,
                sats,
            });
        }
        Ok(ObsData {
            path: path.to_path_buf(),
            approx_position_m,
            epochs,
        })
    }
}

/// A navigation file: Keplerian ephemerides per satellite, GLONASS state
/// vectors per slot, and the GPS Klobuchar coefficients of the header.
#[derive(Debug, Clone, Default)]
pub struct NavData {
    pub ephemerides: BTreeMap<SatId, Vec<Kepler>>,
    /// GLONASS FDMA ephemerides per slot, in t_b order.
    pub glonass: BTreeMap<SatId, Vec<GlonassEphemeris>>,
    pub klobuchar: Option<Klobuchar>,
    /// The Keplerian orbits are evaluated on their orbit arcs
    /// (`raim_nav::arc`, `raim_nav::ranging::SatInput::orbit_arc`), as the
    /// unit's stream receiver evaluates them: set by a receiver stream's
    /// reader (`raim_recv`), so that its epochs are the unit's to the bit;
    /// false for a RINEX navigation file (the exact orbit).
    pub orbit_arcs: bool,
}

pub use raim_nav::ranging::Broadcast;

/// A GLONASS record of a RINEX 2/3 navigation file: the epoch is t_b in
/// UTC (RINEX 3 §A; the `rinex` crate reads it on the UTC scale), the
/// clock bias -tau_n, the drift +gamma_n, the state vector in km, km/s and
/// km/s^2. None (the record is skipped) when a field is missing or out of
/// the ICD's range.
fn glonass_record(
    prn: u8,
    tb_gps_s: f64,
    eph: &rinex::navigation::Ephemeris,
) -> Option<GlonassEphemeris> {
    let get = |f: &str| eph.get_orbit_f64(f);
    let health = health_word(get("health"));
    let f = GlonassIcdFields {
        slot: prn,
        frequency_channel: eph.glonass_freq_channel()?,
        tb_gps_s,
        x_km: get("satPosX")?,
        y_km: get("satPosY")?,
        z_km: get("satPosZ")?,
        vx_km_s: get("velX")?,
        vy_km_s: get("velY")?,
        vz_km_s: get("velZ")?,
        ax_km_s2: get("accelX").unwrap_or(0.0),
        ay_km_s2: get("accelY").unwrap_or(0.0),
        az_km_s2: get("accelZ").unwrap_or(0.0),
        tau_n_s: -eph.clock_bias,
        gamma_n: eph.clock_drift,
        unhealthy: health != 0,
    };
    GlonassEphemeris::from_icd(&f).ok()
}

/// The health word of a navigation record. A missing, negative,
/// non-integer, NaN or too large value is unhealthy (`u32::MAX`), never
/// healthy (`NaN as u32` and `0.5 as u32` are 0, "healthy").
pub fn health_word(v: Option<f64>) -> u32 {
    match v {
        Some(h) if h >= 0.0 && h <= f64::from(u32::MAX) && h.fract() == 0.0 => h as u32,
        _ => u32::MAX,
    }
}

pub use raim_nav::store::max_ephemeris_age_s;

impl NavData {
    /// Load a navigation file; a panic inside the `rinex` crate becomes
    /// `GnssError::Parse` (`rinex_guard`).
    pub fn load(path: &Path) -> Result<Self, GnssError> {
        crate::rinex_guard::no_panic(path, || Self::load_unguarded(path))
    }

    fn load_unguarded(path: &Path) -> Result<Self, GnssError> {
        let r = open(path)?;
        if !r.is_navigation_rinex() {
            return Err(GnssError::WrongKind {
                path: path.to_path_buf(),
                expected: "navigation",
            });
        }
        let klobuchar = r
            .header
            .ionod_corrections
            .get(&Constellation::GPS)
            .and_then(|m| m.as_klobuchar())
            .map(|kb| Klobuchar {
                alpha: [kb.alpha.0, kb.alpha.1, kb.alpha.2, kb.alpha.3],
                beta: [kb.beta.0, kb.beta.1, kb.beta.2, kb.beta.3],
            })
            .filter(|k| k.beta[0] > 0.0);
        let mut ephemerides: BTreeMap<SatId, Vec<Kepler>> = BTreeMap::new();
        let mut glonass: BTreeMap<SatId, Vec<GlonassEphemeris>> = BTreeMap::new();
        for (key, eph) in r.nav_ephemeris_frames_iter() {
            let Some(system) = system_of(key.sv.constellation) else {
                continue;
            };
            if system == System::Glonass {
                let tb_gps_s = key.epoch.to_time_scale(TimeScale::GPST).to_gpst_seconds();
                if let Some(g) = glonass_record(key.sv.prn, tb_gps_s, eph) {
                    glonass
                        .entry(SatId::new(system, key.sv.prn))
                        .or_default()
                        .push(g);
                }
                continue;
            }
            let get = |f: &str| eph.get_orbit_f64(f);
            let group_delay_s = match (system, key.msgtype) {
                (System::Galileo, NavMessageType::FNAV) => get("bgdE5aE1"),
                (System::Galileo, _) => get("bgdE5bE1"),
                (System::Beidou, _) => get("tgd1b1b3").or_else(|| get("tgdb1b3")),
                _ => get("tgd"),
            }
            .unwrap_or(0.0);
            let group_delay_e5a_s = match (system, key.msgtype) {
                (System::Galileo, NavMessageType::FNAV) => None,
                (System::Galileo, _) => get("bgdE5aE1"),
                _ => None,
            }
            .unwrap_or(0.0);
            let fields = (
                get("toe"),
                get("sqrta"),
                get("e"),
                get("i0"),
                get("omega0"),
                get("omega"),
                get("m0"),
            );
            let (Some(toe), Some(sqrt_a), Some(e), Some(i0), Some(omega0), Some(omega), Some(m0)) =
                fields
            else {
                continue;
            };
            let toc_gps_s = key.epoch.to_time_scale(TimeScale::GPST).to_gpst_seconds();
            let k = Kepler {
                system,
                prn: key.sv.prn,
                toc_gps_s,
                toe_sow_s: toe,
                af0_s: eph.clock_bias,
                af1_s_s: eph.clock_drift,
                af2_s_s2: eph.clock_drift_rate,
                sqrt_a_m05: sqrt_a,
                e,
                i0_rad: i0,
                omega0_rad: omega0,
                omega_rad: omega,
                m0_rad: m0,
                delta_n_rad_s: get("deltaN").unwrap_or(0.0),
                omega_dot_rad_s: get("omegaDot").unwrap_or(0.0),
                idot_rad_s: get("idot").unwrap_or(0.0),
                cuc_rad: get("cuc").unwrap_or(0.0),
                cus_rad: get("cus").unwrap_or(0.0),
                crc_m: get("crc").unwrap_or(0.0),
                crs_m: get("crs").unwrap_or(0.0),
                cic_rad: get("cic").unwrap_or(0.0),
                cis_rad: get("cis").unwrap_or(0.0),
                group_delay_s,
                group_delay_e5a_s,
                health: health_word(get("health")),
                iod: ["iode", "iodnav", "aode"]
                    .iter()
                    .find_map(|f| get(f))
                    .unwrap_or(0.0) as u32,
            };
            // Galileo: I/NAV only (E1-B, the message single-frequency E1
            // users decode, with BGD(E1,E5b)); F/NAV records are skipped.
            let is_fnav = system == System::Galileo && key.msgtype == NavMessageType::FNAV;
            if is_fnav {
                continue;
            }
            ephemerides
                .entry(SatId::new(system, key.sv.prn))
                .or_default()
                .push(k);
        }
        for v in ephemerides.values_mut() {
            v.sort_by(|a, b| a.toc_gps_s.total_cmp(&b.toc_gps_s));
        }
        for v in glonass.values_mut() {
            v.sort_by(|a, b| a.tb_gps_s.total_cmp(&b.tb_gps_s));
            // Mixed files repeat a message once per contributing station.
            v.dedup_by(|a, b| a == b);
        }
        Ok(NavData {
            ephemerides,
            glonass,
            klobuchar,
            orbit_arcs: false,
        })
    }

    /// The healthy ephemeris of `id` whose toe is closest to `t_gps_s`,
    /// within [`max_ephemeris_age_s`] and of `t_gps_s`'s week
    /// (`raim_nav::store::kepler_age_s`).
    pub fn select(&self, id: SatId, t_gps_s: f64) -> Option<&Kepler> {
        let max_age = max_ephemeris_age_s(id.system);
        self.ephemerides
            .get(&id)?
            .iter()
            .filter(|k| k.health == 0)
            .filter_map(|k| Some((raim_nav::store::kepler_age_s(k, t_gps_s)?, k)))
            .filter(|(age, _)| *age <= max_age)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, k)| k)
    }

    /// The healthy GLONASS ephemeris of `id` whose t_b is closest to
    /// `t_gps_s`, within [`max_ephemeris_age_s`] (30 min: t_b comes every
    /// 30 min and the ICD fits each for +-15 min).
    pub fn select_glonass(&self, id: SatId, t_gps_s: f64) -> Option<&GlonassEphemeris> {
        let max_age = max_ephemeris_age_s(System::Glonass);
        self.glonass
            .get(&id)?
            .iter()
            .filter(|g| g.health == 0)
            .map(|g| (g.age_s(t_gps_s).abs(), g))
            .filter(|(age, _)| *age <= max_age)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, g)| g)
    }

    /// The broadcast ephemeris of `id` at `t_gps_s`, whatever its kind.
    pub fn select_broadcast(&self, id: SatId, t_gps_s: f64) -> Option<Broadcast<'_>> {
        match id.system {
            System::Glonass => self.select_glonass(id, t_gps_s).map(Broadcast::Glonass),
            _ => self.select(id, t_gps_s).map(Broadcast::Kepler),
        }
    }
}

#[cfg(test)]
mod health_tests {
    use super::health_word;

    #[test]
    fn only_a_non_negative_integer_is_a_health_word() {
        assert_eq!(health_word(Some(0.0)), 0);
        assert_eq!(health_word(Some(63.0)), 63);
        for bad in [
            None,
            Some(f64::NAN),
            Some(0.5),
            Some(-1.0),
            Some(f64::INFINITY),
            Some(1e10),
        ] {
            assert_eq!(health_word(bad), u32::MAX, "{bad:?}");
        }
    }
}
