//! ESBC's RINEX 3 (G+E+C, dual frequency, 2020-06-25; ../shared/data) as
//! a receiver's RTCM 3 stream, re-encoded by `rtcm-rs`'s encoder: a
//! station 1005 first, each broadcast ephemeris (1019 GPS, 1046 Galileo
//! I/NAV, 1042 BeiDou) once, an hour before its toc, and at each epoch one
//! MSM7 per system (1077, 1097, 1127; DF393 set on all but the last) with
//! the signals of the stream's iono-free pairs (GPS C1C/C2W, Galileo
//! C1C/C5Q, BeiDou C2I/C6I), each with its C/N0 from the RINEX S
//! observable (DF408) and its phase-range rate from the RINEX D observable
//! (DF399 + DF404: -D x lambda, the satellite's rough rate from its first
//! signal). The stream may be sent `delta_weeks` later:
//! every ephemeris week moved on, times of week as recorded (no GLONASS,
//! so no leap-second shift).

use std::collections::BTreeMap;

use raim_core::{SatId, System};
use raim_gnss::ephemeris::{Kepler, BDT_MINUS_GPST_S, WEEK_S};
use raim_gnss::{NavData, ObsData};
use raim_nav::rtcm::LIGHT_MS_M;
use rtcm_rs::msg::message::{Message, MessageBuilder};
use rtcm_rs::msg::{BdsSigId, GalSigId, GpsSigId};

pub const OBS: &str = "ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz";
pub const NAV: &str = "ESBC00DNK_R_20201770000_01D_MN.rnx.gz";
/// ESBC's GPS week (2020-06-25).
pub const ESBC_WEEK: i64 = 2111;
/// Epochs of the stream (30 s apart: the first 40 minutes).
pub const EPOCHS: usize = 80;
/// Ephemerides are sent this long before their toc, s.
const LEAD_S: f64 = 3600.0;
/// The MSM7 fine pseudorange (DF405) resolution, ms.
pub const FINE_MS: f64 = 1.0 / (512.0 * 1024.0 * 1024.0);
/// A signal sent: RINEX code and the MSM (band, attribute).
pub type SignalCode = (&'static str, u8, char);
/// The signals sent per system.
pub const SIGNALS: [(System, [SignalCode; 2]); 3] = [
    (System::Gps, [("C1C", 1, 'C'), ("C2W", 2, 'W')]),
    (System::Galileo, [("C1C", 1, 'C'), ("C5Q", 5, 'Q')]),
    (System::Beidou, [("C2I", 2, 'I'), ("C6I", 6, 'I')]),
];

/// A file of ../shared/data (beside the repository): found from the
/// including crate's directory (host-tests, or crates/raim-tool, whose
/// `stream_araim_replay` test includes this module).
pub fn data(name: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    dir.ancestors()
        .map(|p| p.join("shared/data"))
        .find(|p| p.is_dir())
        .unwrap_or_else(|| dir.join("../../shared/data"))
        .join(name)
}

/// Seconds of the week and the week of GPS time `t`.
fn week_sow(t_gps_s: f64) -> (i64, f64) {
    let w = (t_gps_s / WEEK_S).floor();
    (w as i64, t_gps_s - w * WEEK_S)
}

/// A Keplerian set as its RTCM message (angles back to semicircles).
fn ephemeris_message(k: &Kepler, delta_weeks: i64) -> Message {
    let sc = |rad: f64| rad / std::f64::consts::PI;
    let f32_ = |v: f64| v as f32;
    let unhealthy = u8::from(k.health != 0);
    match k.system {
        System::Gps => {
            let (week, toc_s) = week_sow(k.toc_gps_s);
            let week = week + delta_weeks;
            Message::Msg1019(rtcm_rs::msg::Msg1019T {
                gps_satellite_id: k.prn,
                gps_week_number: (week.rem_euclid(1024)) as u16,
                idot_sc_s: sc(k.idot_rad_s),
                iode: k.iod as u8,
                toc_s: f32_(toc_s),
                af2_s_s2: f32_(k.af2_s_s2),
                af1_s_s: f32_(k.af1_s_s),
                af0_s: k.af0_s,
                iodc: k.iod as u16,
                crs_m: f32_(k.crs_m),
                delta_n_sc_s: f32_(sc(k.delta_n_rad_s)),
                m0_sc: sc(k.m0_rad),
                cuc_rad: f32_(k.cuc_rad),
                eccentricity: k.e,
                cus_rad: f32_(k.cus_rad),
                sqrt_a_sqrt_m: k.sqrt_a_m05,
                toe_s: f32_(k.toe_sow_s),
                cic_rad: f32_(k.cic_rad),
                omega0_sc: sc(k.omega0_rad),
                cis_rad: f32_(k.cis_rad),
                i0_sc: sc(k.i0_rad),
                crc_m: f32_(k.crc_m),
                omega_sc: sc(k.omega_rad),
                omegadot_sc_s: sc(k.omega_dot_rad_s),
                tgd_s: f32_(k.group_delay_s),
                sv_health_ind: unhealthy,
                ..Default::default()
            })
        }
        System::Galileo => {
            let (week, toc_s) = week_sow(k.toc_gps_s);
            let week = week + delta_weeks;
            Message::Msg1046(rtcm_rs::msg::Msg1046T {
                gal_satellite_id: k.prn,
                gal_week_number: ((week - 1024).rem_euclid(4096)) as u16,
                iodnav: k.iod as u16,
                idot_sc_s: f32_(sc(k.idot_rad_s)),
                toc_s: f32_(toc_s),
                af2_s_s2: f32_(k.af2_s_s2),
                af1_s_s: k.af1_s_s,
                af0_s: k.af0_s,
                crs_m: f32_(k.crs_m),
                delta_n_sc_s: f32_(sc(k.delta_n_rad_s)),
                m0_sc: sc(k.m0_rad),
                cuc_rad: f32_(k.cuc_rad),
                eccentricity: k.e,
                cus_rad: f32_(k.cus_rad),
                sqrt_a_sqrt_m: k.sqrt_a_m05,
                toe_s: f32_(k.toe_sow_s),
                cic_rad: f32_(k.cic_rad),
                omega0_sc: sc(k.omega0_rad),
                cis_rad: f32_(k.cis_rad),
                i0_sc: sc(k.i0_rad),
                crc_m: f32_(k.crc_m),
                omega_sc: sc(k.omega_rad),
                omegadot_sc_s: sc(k.omega_dot_rad_s),
                bgd_e1_e5a_s: f32_(k.group_delay_e5a_s),
                bgd_e1_e5b_s: f32_(k.group_delay_s),
                e1_b_sig_health_ind: unhealthy,
                ..Default::default()
            })
        }
        System::Beidou => {
            // BDT: GPS - 14 s, weeks from GPS week 1356.
            let (week, toc_s) = week_sow(k.toc_gps_s + BDT_MINUS_GPST_S);
            let week = week + delta_weeks;
            Message::Msg1042(rtcm_rs::msg::Msg1042T {
                bds_satellite_id: k.prn,
                bds_week_number: ((week - 1356).rem_euclid(8192)) as u16,
                idot_sc_s: sc(k.idot_rad_s),
                aode: k.iod as u8,
                toc_s: f32_(toc_s),
                a2_s_s2: f32_(k.af2_s_s2),
                a1_s_s: k.af1_s_s,
                a0_s: k.af0_s,
                crs_m: f32_(k.crs_m),
                delta_n_sc_s: f32_(sc(k.delta_n_rad_s)),
                m0_sc: sc(k.m0_rad),
                cuc_rad: f32_(k.cuc_rad),
                eccentricity: k.e,
                cus_rad: f32_(k.cus_rad),
                sqrt_a_sqrt_m: k.sqrt_a_m05,
                toe_s: f32_(k.toe_sow_s),
                cic_rad: f32_(k.cic_rad),
                omega0_sc: sc(k.omega0_rad),
                cis_rad: f32_(k.cis_rad),
                i0_sc: sc(k.i0_rad),
                crc_m: f32_(k.crc_m),
                omega_sc: sc(k.omega_rad),
                omegadot_sc_s: sc(k.omega_dot_rad_s),
                tgd1_s: f32_(k.group_delay_s),
                sv_health_flag: unhealthy,
                ..Default::default()
            })
        }
        s => panic!("no Keplerian message for {s:?}"),
    }
}

/// A Galileo set as an F/NAV 1045 (angles back to semicircles).
fn fnav_message(k: &Kepler, delta_weeks: i64) -> Message {
    let sc = |rad: f64| rad / std::f64::consts::PI;
    let f32_ = |v: f64| v as f32;
    let (week, toc_s) = week_sow(k.toc_gps_s);
    let week = week + delta_weeks;
    Message::Msg1045(rtcm_rs::msg::Msg1045T {
        gal_satellite_id: k.prn,
        gal_week_number: ((week - 1024).rem_euclid(4096)) as u16,
        iodnav: k.iod as u16,
        idot_sc_s: f32_(sc(k.idot_rad_s)),
        toc_s: f32_(toc_s),
        af2_s_s2: f32_(k.af2_s_s2),
        af1_s_s: k.af1_s_s,
        af0_s: k.af0_s,
        crs_m: f32_(k.crs_m),
        delta_n_sc_s: f32_(sc(k.delta_n_rad_s)),
        m0_sc: sc(k.m0_rad),
        cuc_rad: f32_(k.cuc_rad),
        eccentricity: k.e,
        cus_rad: f32_(k.cus_rad),
        sqrt_a_sqrt_m: k.sqrt_a_m05,
        toe_s: f32_(k.toe_sow_s),
        cic_rad: f32_(k.cic_rad),
        omega0_sc: sc(k.omega0_rad),
        cis_rad: f32_(k.cis_rad),
        i0_sc: sc(k.i0_rad),
        crc_m: f32_(k.crc_m),
        omega_sc: sc(k.omega_rad),
        omegadot_sc_s: sc(k.omega_dot_rad_s),
        bgd_e1_e5a_s: f32_(k.group_delay_e5a_s),
        e5a_sig_health_ind: u8::from(k.health != 0),
        ..Default::default()
    })
}

/// One system's MSM7 at an epoch: (satellite, rough ms as DF397 + DF398,
/// rough rate m/s (DF399), [(band, attribute, fine ms, C/N0 dB-Hz, fine
/// rate m/s (DF404))]).
type Cells = Vec<(u8, u8, f64, Option<i16>, Vec<Cell>)>;
/// One signal of an MSM7 cell: (band, attribute, fine ms, C/N0 dB-Hz,
/// fine rate m/s).
type Cell = (u8, char, f64, Option<f64>, Option<f64>);

/// Each of the first `EPOCHS` epochs' Doppler observables (Hz) by
/// satellite and code ("D1C"), from the RINEX: its records as
/// `ObsData::load` takes them (flag ok), in order.
pub fn dopplers() -> Vec<BTreeMap<(SatId, String), f64>> {
    let r = raim_gnss::rinex_io::open(&data(OBS)).unwrap();
    let mut out = Vec::new();
    for (key, obs) in r.observations_iter() {
        if !key.flag.is_ok() {
            continue;
        }
        let mut m = BTreeMap::new();
        for s in &obs.signals {
            let Some(system) = raim_gnss::rinex_io::system_of(s.sv.constellation) else {
                continue;
            };
            if s.observable.is_doppler_observable() && s.value.is_finite() {
                m.insert(
                    (SatId::new(system, s.sv.prn), s.observable.to_string()),
                    s.value,
                );
            }
        }
        out.push(m);
        if out.len() == EPOCHS {
            break;
        }
    }
    out
}

/// The phase-range rate of a RINEX Doppler `d_hz` on `code`'s carrier,
/// m/s: -D x c / f (a receding satellite's Doppler is negative).
pub fn rate_m_s(system: System, code: &str, d_hz: f64) -> f64 {
    let f = raim_nav::ranging::band_hz(system, code).unwrap();
    -d_hz * raim_nav::ephemeris::C_M_S / f
}

/// The cells of `sys` in an ESBC epoch: the rough range (1/1024 ms) from
/// the first signal, each signal's remainder as the fine range (within
/// DF405's +-2^-10 ms, else the signal is left out); `pairs_only`: a
/// satellite is sent only with both signals of its system's pair.
fn cells(
    sats: &BTreeMap<SatId, Vec<raim_gnss::rinex_io::CodeObs>>,
    doppler: &BTreeMap<(SatId, String), f64>,
    sys: System,
    pairs_only: bool,
) -> Cells {
    let signals = SIGNALS.iter().find(|(s, _)| *s == sys).unwrap().1;
    let mut out = Cells::new();
    for (id, obs) in sats.iter().filter(|(id, _)| id.system == sys) {
        let ms = |code: &str| {
            obs.iter()
                .find(|o| o.code == code)
                .map(|o| o.value_m / LIGHT_MS_M)
        };
        let Some(first_ms) = signals.iter().find_map(|(c, _, _)| ms(c)) else {
            continue;
        };
        let rough_1024 = (first_ms * 1024.0).round() as i64;
        let (int_ms, mod_1024) = (rough_1024 / 1024, rough_1024 % 1024);
        let rough_ms = int_ms as f64 + mod_1024 as f64 / 1024.0;
        // The C/N0 of each signal: the RINEX S observable (DF408 holds it
        // to 2^-4 dB-Hz).
        let cn0 = |code: &str| obs.iter().find(|o| o.code == code).and_then(|o| o.cn0_dbhz);
        // Each signal's rate from its D observable; the rough rate (DF399,
        // whole m/s) from the first signal's, each fine rate (DF404,
        // within +-1.6383 m/s) the rest.
        let rate = |code: &str| {
            let d = doppler.get(&(*id, code.replacen('C', "D", 1)))?;
            Some(rate_m_s(sys, code, *d))
        };
        let rough_rate = signals
            .iter()
            .find_map(|(c, _, _)| ms(c).and(rate(c)))
            .map(|r| r.round() as i16)
            .filter(|r| r.abs() < 0x2000);
        let fine_rate = |code: &str| {
            let f = rate(code)? - f64::from(rough_rate?);
            (f.abs() < 1.6383).then_some(f)
        };
        let sigs: Vec<Cell> = signals
            .iter()
            .filter_map(|(c, band, attr)| {
                let fine = ms(c)? - rough_ms;
                (fine.abs() < 1.0 / 1024.0 - FINE_MS).then_some((
                    *band,
                    *attr,
                    fine,
                    cn0(c),
                    fine_rate(c),
                ))
            })
            .collect();
        let complete = !pairs_only || sigs.len() == signals.len();
        if !sigs.is_empty() && complete && (1..=254).contains(&int_ms) {
            out.push((
                id.prn,
                int_ms as u8,
                mod_1024 as f64 / 1024.0,
                rough_rate,
                sigs,
            ));
        }
    }
    out
}

macro_rules! msm7 {
    ($variant:ident, $t:ident, $sig_t:ident, $sig_id:ident, $time:ident, $time_ms:expr, $more:expr, $cells:expr) => {{
        let mut m = rtcm_rs::msg::$t {
            reference_station_id: 7,
            $time: $time_ms,
            msm_multiple_message_flag: $more,
            ..Default::default()
        };
        for (prn, int_ms, mod_ms, rough_rate, sigs) in $cells {
            m.data_segment.satellite_data.push(rtcm_rs::msg::Msm57Sat {
                satellite_id: *prn,
                gnss_satellite_rough_range_integer_ms: Some(*int_ms),
                gnss_satellite_rough_range_mod1ms_ms: *mod_ms,
                gnss_satellite_rough_phaserange_rates_m_s: *rough_rate,
                ..Default::default()
            });
            for (band, attr, fine, cn0, fine_rate) in sigs {
                m.data_segment.signal_data.push(rtcm_rs::msg::$sig_t {
                    satellite_id: *prn,
                    signal_id: $sig_id::new(*band, *attr),
                    gnss_signal_fine_pseudorange_ext_ms: Some(*fine),
                    gnss_signal_cnr_ext_dbhz: *cn0,
                    gnss_signal_fine_phaserange_rate_m_s: *fine_rate,
                    ..Default::default()
                });
            }
        }
        Message::$variant(m)
    }};
}

/// An epoch's GPS time and the (satellite, code, RINEX value m) it carries.
pub type Carried = (f64, Vec<(SatId, String, f64)>);

/// ESBC's first `EPOCHS` epochs as a receiver's RTCM 3 stream sent
/// `delta_weeks` after the recording, and the observations it carries
/// (GPS time as recorded, RINEX values of the signals sent).
pub fn esbc_stream(delta_weeks: i64) -> (Vec<u8>, Vec<Carried>) {
    esbc_stream_with(delta_weeks, BeidouTime::Bdt, false)
}

/// The time tag of the BeiDou MSM (DF427).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BeidouTime {
    /// BDT (RTCM 10403.3: GPS - 14 s).
    Bdt,
    /// GPS time, as encoders before RTCM 3.2 settled on BDT wrote it.
    Gps,
}

/// [`esbc_stream`] with the BeiDou MSM's time tag `bds_time`, and with
/// each Galileo set also sent as an F/NAV 1045 after its I/NAV 1046
/// (`fnav`: the same orbit and clock, BGD(E1,E5a), E5a health).
pub fn esbc_stream_with(
    delta_weeks: i64,
    bds_time: BeidouTime,
    fnav: bool,
) -> (Vec<u8>, Vec<Carried>) {
    esbc_stream_opts(delta_weeks, bds_time, fnav, false)
}

/// [`esbc_stream`] with only the satellites that carry both signals of
/// their system's pair (GPS C1C+C2W, Galileo C1C+C5Q, BeiDou C2I+C6I): the
/// satellites `raim replay --araim --code G=C1C+C2W --code E=C1C+C5Q
/// --code C=C2I+C6I` ranges on the RINEX (it drops ESBC's C2I-only BeiDou
/// satellites, which [`esbc_stream`] sends single-frequency).
pub fn esbc_stream_pairs_only(delta_weeks: i64) -> (Vec<u8>, Vec<Carried>) {
    esbc_stream_opts(delta_weeks, BeidouTime::Bdt, false, true)
}

fn esbc_stream_opts(
    delta_weeks: i64,
    bds_time: BeidouTime,
    fnav: bool,
    pairs_only: bool,
) -> (Vec<u8>, Vec<Carried>) {
    let obs = ObsData::load(&data(OBS)).unwrap();
    let nav = NavData::load(&data(NAV)).unwrap();
    let mut b = MessageBuilder::new();
    let mut out = Vec::new();
    let mut put = |b: &mut MessageBuilder, m: &Message| {
        out.extend_from_slice(b.build_message(m).expect("rtcm-rs encodes it"));
    };
    let station = obs.approx_position_m.unwrap();
    put(
        &mut b,
        &Message::Msg1005(rtcm_rs::msg::Msg1005T {
            reference_station_id: 7,
            gps_flag: 1,
            galileo_flag: 1,
            antenna_ref_point_ecef_x_m: station[0],
            antenna_ref_point_ecef_y_m: station[1],
            antenna_ref_point_ecef_z_m: station[2],
            ..Default::default()
        }),
    );
    let mut sets: Vec<&Kepler> = nav
        .ephemerides
        .iter()
        .filter(|(id, _)| matches!(id.system, System::Gps | System::Galileo | System::Beidou))
        .flat_map(|(_, v)| v.iter())
        .collect();
    sets.sort_by(|a, b| a.toc_gps_s.total_cmp(&b.toc_gps_s));
    let t0 = obs.epochs[0].time_gps_s;
    // Sets already in force at the start: those of the last 4 hours.
    sets.retain(|k| k.toc_gps_s >= t0 - 4.0 * 3600.0);
    let mut next = 0;
    let mut carried = Vec::new();
    let doppler = dopplers();
    for (e, d) in obs.epochs.iter().take(EPOCHS).zip(&doppler) {
        while next < sets.len() && sets[next].toc_gps_s - LEAD_S <= e.time_gps_s {
            put(&mut b, &ephemeris_message(sets[next], delta_weeks));
            if fnav && sets[next].system == System::Galileo {
                put(&mut b, &fnav_message(sets[next], delta_weeks));
            }
            next += 1;
        }
        let (_, sow) = week_sow(e.time_gps_s);
        let tow_ms = (sow * 1000.0).round() as u32;
        let bdt_ms = ((sow + BDT_MINUS_GPST_S) * 1000.0)
            .round()
            .rem_euclid(WEEK_S * 1000.0) as u32;
        let bdt_ms = match bds_time {
            BeidouTime::Bdt => bdt_ms,
            BeidouTime::Gps => tow_ms,
        };
        let (g, ga, c) = (
            cells(&e.sats, d, System::Gps, pairs_only),
            cells(&e.sats, d, System::Galileo, pairs_only),
            cells(&e.sats, d, System::Beidou, pairs_only),
        );
        put(
            &mut b,
            &msm7!(
                Msg1077,
                Msg1077T,
                Msg1077Sig,
                GpsSigId,
                gps_epoch_time_ms,
                tow_ms,
                1,
                &g
            ),
        );
        put(
            &mut b,
            &msm7!(
                Msg1097,
                Msg1097T,
                Msg1097Sig,
                GalSigId,
                gal_epoch_time_ms,
                tow_ms,
                1,
                &ga
            ),
        );
        put(
            &mut b,
            &msm7!(
                Msg1127,
                Msg1127T,
                Msg1127Sig,
                BdsSigId,
                bds_epoch_time_ms,
                bdt_ms,
                0,
                &c
            ),
        );
        let mut sent = Vec::new();
        for (sys, _) in SIGNALS {
            let cs = cells(&e.sats, d, sys, pairs_only);
            for (prn, _, _, _, sigs) in &cs {
                let id = SatId::new(sys, *prn);
                for (band, attr, _, _, _) in sigs {
                    let code = format!("C{band}{attr}");
                    let v = e.sats[&id].iter().find(|o| o.code == code).unwrap().value_m;
                    sent.push((id, code, v));
                }
            }
        }
        carried.push((e.time_gps_s, sent));
    }
    (out, carried)
}
