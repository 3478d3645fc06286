//! GLONASS over RTCM 3 on the GMSD7 stream (../shared/data): the 1020
//! ephemerides against the RINEX reader on the same state vectors, the
//! MSM frequency channels against the 1020's, the GLONASS MSM time of day
//! against the epochs' GPS time, and the GLONASS pseudoranges against a
//! GPS-only position.

use std::path::{Path, PathBuf};

use raim_core::{SatId, System};
use raim_gnss::geometry::distance_m;
use raim_gnss::glonass::GlonassEphemeris;
use raim_gnss::ranging::{prepare_epoch, RangingOptions};
use raim_gnss::NavData;
use raim_recv::rtcm::{Rtcm3, GLONASS_TIME_MISMATCH};
use raim_recv::{read_all, Decoder, Format};
use rtcm_rs::msg::message::Message;
use rtcm_rs::{MessageBuilder, MessageFrame};

fn gmsd7() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/GMSD7_20121014.rtcm3")
}

/// Every frame of a stream, decoded by `rtcm-rs` alone.
fn messages(bytes: &[u8]) -> Vec<(usize, usize, Message)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        match MessageFrame::new(&bytes[i..]) {
            Ok(f) => {
                let len = f.frame_len();
                out.push((i, len, f.get_message()));
                i += len;
            }
            Err(_) => i += 1,
        }
    }
    out
}

/// A RINEX 3.05 GLONASS navigation record written from a 1020's fields
/// (RINEX 3.05 §A.11: epoch t_b in UTC, clock bias -tau_n, relative
/// frequency bias +gamma_n; km, km/s, km/s^2), with t_b in UTC given by
/// hand, so that the RINEX reader's time path (UTC to GPS with hifitime)
/// checks the RTCM path's (Moscow time of day to GPS).
fn rinex_record(m: &rtcm_rs::msg::Msg1020T, tb_utc: &str) -> String {
    let e = |v: f64| format!("{v:19.12E}");
    format!(
        "R{:02} {tb_utc}{}{}{}\n    {}{}{}{}\n    {}{}{}{}\n    {}{}{}{}\n",
        m.glo_satellite_id,
        e(-m.tau_n_s),
        e(f64::from(m.gamma_n)),
        e(0.0),
        e(m.xn_km),
        e(m.xn_first_deriv_km_s),
        e(f64::from(m.xn_second_deriv_km_s2)),
        e(f64::from(m.glo_eph_health_flag)),
        e(m.yn_km),
        e(m.yn_first_deriv_km_s),
        e(f64::from(m.yn_second_deriv_km_s2)),
        e(f64::from(m.glo_satellite_freq_chan_number)),
        e(m.zn_km),
        e(m.zn_first_deriv_km_s),
        e(f64::from(m.zn_second_deriv_km_s2)),
        e(0.0),
    )
}

/// Each 1020 of slots 13-15 (the observed satellites that have one; t_b
/// 03:15 Moscow time = 00:15:00 UTC on 2012-10-14), through the RTCM path
/// and through a RINEX navigation file holding the same state vector: the
/// same t_b in GPS time, and the same satellite position and clock over
/// the stream's four minutes.
#[test]
fn rtcm_1020_matches_the_rinex_path() {
    /// Both paths integrate the same state with the same code; what can
    /// differ is the RINEX text's 12-digit mantissa (1e-8 km): 1 mm.
    const POSITION_TOL_M: f64 = 1e-3;
    /// Clock: the same -tau_n + gamma_n (t - t_b), to 1e-15 s.
    const CLOCK_TOL_S: f64 = 1e-15;
    let p = gmsd7();
    let rec = read_all(Format::Rtcm3, std::fs::File::open(&p).unwrap(), p.clone()).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    let mut text = String::from(
        "     3.05           NAVIGATION DATA     R: GLONASS          RINEX VERSION / TYPE\n\
         test                raim                20121014 000000 UTC PGM / RUN BY / DATE \n\
         \x20   16                                                      LEAP SECONDS        \n\
         \x20                                                           END OF HEADER       \n",
    );
    let mut slots = Vec::new();
    for (_, _, m) in messages(&bytes) {
        if let Message::Msg1020(m) = m {
            if (13..=15).contains(&m.glo_satellite_id) {
                assert_eq!(m.tb_min, 195, "t_b of R{}", m.glo_satellite_id);
                text.push_str(&rinex_record(&m, "2012 10 14 00 15 00"));
                slots.push(m.glo_satellite_id);
            }
        }
    }
    assert_eq!(slots, [13, 14, 15]);
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim_glo.rnx");
    std::fs::write(&path, &text).unwrap();
    let rinex = NavData::load(&path);
    let _ = std::fs::remove_file(&path);
    let rinex = rinex.unwrap();
    let t0 = rec.obs.epochs.first().unwrap().time_gps_s;
    let t1 = rec.obs.epochs.last().unwrap().time_gps_s;
    for slot in slots {
        let id = SatId::new(System::Glonass, slot);
        let a: &GlonassEphemeris = &rec.nav.glonass[&id][0];
        let b: &GlonassEphemeris = &rinex.glonass[&id][0];
        assert_eq!(a.tb_gps_s, b.tb_gps_s, "{id} t_b");
        assert_eq!(a.frequency_channel, b.frequency_channel, "{id}");
        assert_eq!(a.health, 0, "{id}");
        for t in [t0, (t0 + t1) / 2.0, t1] {
            let (sa, sb) = (a.state(t), b.state(t));
            let d = distance_m(sa.position_m, sb.position_m);
            assert!(d < POSITION_TOL_M, "{id} at {t}: {d} m");
            assert!((sa.clock_s - sb.clock_s).abs() < CLOCK_TOL_S, "{id}");
            // A GLONASS orbit: radius 25,510 km +- 100 km.
            let r = distance_m(sa.position_m, [0.0; 3]);
            assert!((r - 25_510e3).abs() < 100e3, "{id}: r = {r} m");
        }
    }
}

/// The frequency channel each MSM7 gives (DF419) is the one of the
/// satellite's 1020 (DF040), for every observed slot that has a 1020.
#[test]
fn msm_frequency_channels_match_the_1020() {
    let p = gmsd7();
    let bytes = std::fs::read(&p).unwrap();
    let mut dec = Rtcm3::default();
    let mut items = Vec::new();
    dec.push(&bytes, &mut items);
    dec.finish(&mut items);
    let rec = read_all(Format::Rtcm3, bytes.as_slice(), p).unwrap();
    let msm = dec.msm_frequency_channels();
    assert_eq!(msm.len(), 6, "{msm:?}");
    let mut compared = 0;
    for (slot, k) in msm {
        if let Some(v) = rec.nav.glonass.get(&SatId::new(System::Glonass, *slot)) {
            assert!(v.iter().all(|g| g.frequency_channel == *k), "R{slot}");
            compared += 1;
        }
    }
    assert_eq!(compared, 3);
}

/// Every epoch of GMSD7 keeps its six GLONASS satellites (their MSM time of
/// day is the epoch's: 2012 has GPS - UTC = 16 s); the same stream with
/// each 1087's DF034 one second late has none, each counted.
///
/// Verifies: RX-GLONASS-TIME
#[test]
fn glonass_msm_time_is_checked() {
    let p = gmsd7();
    let bytes = std::fs::read(&p).unwrap();
    let glo = |e: &raim_gnss::ObsEpoch| {
        e.sats
            .keys()
            .filter(|id| id.system == System::Glonass)
            .count()
    };
    let rec = read_all(Format::Rtcm3, bytes.as_slice(), p.clone()).unwrap();
    assert_eq!(rec.obs.epochs.len(), 257);
    assert!(rec.obs.epochs.iter().all(|e| glo(e) == 6));
    assert!(!rec.counts.ignored.contains_key(GLONASS_TIME_MISMATCH));

    let mut shifted = Vec::new();
    let mut builder = MessageBuilder::new();
    let mut n1087 = 0;
    for (at, len, m) in messages(&bytes) {
        match m {
            Message::Msg1087(mut m) => {
                m.glo_epoch_time_ms = (m.glo_epoch_time_ms + 1000) % 86_400_000;
                shifted.extend_from_slice(builder.build_message(&Message::Msg1087(m)).unwrap());
                n1087 += 1;
            }
            _ => shifted.extend_from_slice(&bytes[at..at + len]),
        }
    }
    assert_eq!(n1087, 257);
    let rec = read_all(Format::Rtcm3, shifted.as_slice(), p).unwrap();
    assert_eq!(rec.obs.epochs.len(), 257);
    assert!(rec.obs.epochs.iter().all(|e| glo(e) == 0));
    assert_eq!(rec.counts.ignored.get(GLONASS_TIME_MISMATCH), Some(&257));
}

/// The GLONASS iono-free pseudoranges (C1C+C2P), corrected, against the
/// position solved from GPS alone at each epoch: after the GPS receiver
/// clock (median GPS residual) and the common GLONASS offset (median over
/// the GLONASS satellites) are removed, each residual is within 20 m. This
/// is a gross-error check: a t_b off by one second moves a GLONASS
/// satellite by ~3.9 km along its orbit, a t_b off by the leap seconds or
/// a scaling error by far more. What remains is metre-level: the broadcast
/// orbit and clock (SISRE 1.9 m), the receiver's per-channel code biases
/// (not modelled, docs/GLONASS.md), the iono-free noise and the error of
/// an unweighted GPS-only position with satellites down to 6 degrees.
/// (Measured: 11.9 m at worst; R15 sits 9-10 m from R13 and R14 at every
/// epoch, a constant offset, not noise.)
#[test]
fn glonass_ranges_fit_the_gps_position() {
    /// A gross error is kilometres; metre-level terms above add to ~12 m.
    const RESIDUAL_TOL_M: f64 = 20.0;
    let p = gmsd7();
    let rec = read_all(Format::Rtcm3, std::fs::File::open(&p).unwrap(), p.clone()).unwrap();
    let mut gps = RangingOptions {
        systems: vec![System::Gps],
        elevation_mask_rad: 0.0,
        ..RangingOptions::default()
    };
    gps.codes.insert(System::Gps, vec!["C1C+C2W".into()]);
    let mut both = gps.clone();
    both.systems = vec![System::Gps, System::Glonass];
    both.codes.insert(System::Glonass, vec!["C1C+C2P".into()]);
    let mut checked = 0;
    let mut worst_m: f64 = 0.0;
    for e in &rec.obs.epochs {
        let g = prepare_epoch(&rec.nav, e, &gps, None);
        let Some(rx) = g.reference_m.filter(|_| g.sats.len() >= 5) else {
            continue;
        };
        let res = |s: &raim_gnss::ranging::PreparedSat| {
            s.obs.pseudorange_m - distance_m(s.obs.position_m, rx)
        };
        let mut gclk: Vec<f64> = g.sats.iter().map(res).collect();
        gclk.sort_by(f64::total_cmp);
        let clock_m = gclk[gclk.len() / 2];
        let b = prepare_epoch(&rec.nav, e, &both, Some(rx));
        let mut r: Vec<f64> = b
            .sats
            .iter()
            .filter(|s| s.obs.id.system == System::Glonass)
            .map(|s| res(s) - clock_m)
            .collect();
        assert_eq!(r.len(), 3, "{}", e.time_gps_s);
        r.sort_by(f64::total_cmp);
        let isb = r[1];
        for v in &r {
            worst_m = worst_m.max((v - isb).abs());
            assert!((v - isb).abs() < RESIDUAL_TOL_M, "{}: {r:?}", e.time_gps_s);
        }
        checked += 1;
    }
    eprintln!("largest GLONASS residual from their median: {worst_m:.2} m");
    assert_eq!(checked, 241);
}

/// Legacy GLONASS 1012 against MSM7: every GLONASS MSM7 (1087) of GMSD7
/// rewritten as the 1012 a legacy station would send for the same
/// signals (L1 C/A as DF041 + DF044, L2 as DF047 from L1, the GLONASS time
/// of day and the multiple-message bit kept), encoded by `rtcm-rs`. The
/// reader's GLONASS ranges from the legacy stream equal the MSM ones to
/// the legacy fields' resolution: DF041 0.02 m (so 0.01 m once rounded),
/// and L2 through DF047's 0.02 m as well.
#[test]
fn legacy_1012_gives_the_msm_ranges() {
    /// Rounding of DF041 (0.02 m), m.
    const L1_TOL_M: f64 = 0.01 + 1e-6;
    /// Rounding of DF041 and DF047 (0.02 m each), m.
    const L2_TOL_M: f64 = 0.02 + 1e-6;
    /// DF044's unit: two light-milliseconds, m.
    const AMBIGUITY_M: f64 = 599_584.916;
    let bytes = std::fs::read(gmsd7()).unwrap();
    let mut legacy = Vec::new();
    let mut builder = MessageBuilder::new();
    let mut n1012 = 0;
    for (at, len, m) in messages(&bytes) {
        let Message::Msg1087(m) = m else {
            legacy.extend_from_slice(&bytes[at..at + len]);
            continue;
        };
        let mut out = rtcm_rs::msg::Msg1012T {
            reference_station_id: m.reference_station_id,
            glo_epoch_time_ms: m.glo_epoch_time_ms,
            synchronous_gnss_msg_flag: m.msm_multiple_message_flag,
            ..Default::default()
        };
        for s in m.data_segment.satellite_data.iter() {
            let Some(int_ms) = s.gnss_satellite_rough_range_integer_ms else {
                continue;
            };
            let rough = f64::from(int_ms) + s.gnss_satellite_rough_range_mod1ms_ms;
            let range = |band: u8, attr: char| {
                m.data_segment
                    .signal_data
                    .iter()
                    .find(|g| {
                        g.satellite_id == s.satellite_id
                            && g.signal_id.band() == band
                            && g.signal_id.attribute() == attr
                    })
                    .and_then(|g| g.gnss_signal_fine_pseudorange_ext_ms)
                    .map(|fine| (rough + fine) * raim_recv::rtcm::LIGHT_MS_M)
            };
            let Some(l1) = range(1, 'C') else { continue };
            let l2 = range(2, 'C')
                .map(|p| (0, p))
                .or(range(2, 'P').map(|p| (1, p)));
            let amb = (l1 / AMBIGUITY_M).floor() * AMBIGUITY_M;
            let sat = rtcm_rs::msg::Msg1012Sat {
                glo_satellite_id: s.satellite_id,
                glo_satellite_freq_chan_number: s
                    .glonass_satellite_frequency_channel_number
                    .unwrap_or(0),
                l1_pseudorange_m: Some(l1 - amb),
                l1_pseudorange_amb_m: amb,
                glo_l2_code_ind: l2.map_or(0, |(c, _)| c),
                l2_l1_pseudorange_diff_m: l2.map(|(_, p)| (p - l1) as f32),
                ..Default::default()
            };
            out.satellites.push(sat);
        }
        legacy.extend_from_slice(builder.build_message(&Message::Msg1012(out)).unwrap());
        n1012 += 1;
    }
    assert_eq!(n1012, 257);
    let msm = read_all(Format::Rtcm3, bytes.as_slice(), gmsd7()).unwrap();
    let leg = read_all(Format::Rtcm3, legacy.as_slice(), gmsd7()).unwrap();
    assert_eq!(msm.obs.epochs.len(), leg.obs.epochs.len());
    let (mut l1_n, mut l2_n) = (0, 0);
    for (a, b) in msm.obs.epochs.iter().zip(&leg.obs.epochs) {
        assert_eq!(a.time_gps_s, b.time_gps_s);
        let glo = |e: &raim_gnss::ObsEpoch| {
            e.sats
                .iter()
                .filter(|(id, _)| id.system == System::Glonass)
                .map(|(id, o)| (*id, o.clone()))
                .collect::<Vec<_>>()
        };
        let (ga, gb) = (glo(a), glo(b));
        assert_eq!(ga.len(), gb.len(), "GLONASS satellites at {}", a.time_gps_s);
        for ((ia, oa), (ib, ob)) in ga.iter().zip(&gb) {
            assert_eq!(ia, ib);
            for o in ob {
                let want = oa
                    .iter()
                    .find(|x| x.code == o.code)
                    .unwrap_or_else(|| panic!("{ia:?} {} not in the MSM epoch", o.code));
                let (tol, n) = if o.code.starts_with("C1") {
                    (L1_TOL_M, &mut l1_n)
                } else {
                    (L2_TOL_M, &mut l2_n)
                };
                assert!(
                    (o.value_m - want.value_m).abs() <= tol,
                    "{ia:?} {}: {} vs {}",
                    o.code,
                    o.value_m,
                    want.value_m
                );
                *n += 1;
            }
        }
    }
    assert!(l1_n > 1000 && l2_n > 1000, "{l1_n} L1, {l2_n} L2 ranges");
    // The GPS part is the same stream's.
    assert_eq!(
        leg.counts
            .ignored
            .keys()
            .filter(|k| k.contains("legacy"))
            .count(),
        0
    );
}
