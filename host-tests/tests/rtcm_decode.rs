//! The device's compact RTCM 3 decoder (`raim_nav::rtcm::decode`) against
//! `rtcm-rs` (the host's decoder), field by field and bit for bit: every
//! frame of the real GMSD7 stream (GPS + GLONASS MSM7, 1019, 1020, 1005/
//! 1006; other systems' MSM for their DF393), and random GPS, GLONASS,
//! Galileo, QZSS and BeiDou MSM4-MSM7, 1019, 1020, 1042, 1044, 1045,
//! 1046, 1005 and 1006 built by `rtcm-rs`'s own encoder
//! (`build_generated_message`), whole, with a byte overwritten, and cut
//! short. The ephemerides' fields are compared with the host reader's
//! conversion of `rtcm-rs`'s message (`raim_nav::rtcm::msg10xx_fields`).
//!
//! Values are compared through their `Debug` text: Rust prints an f64 as
//! the shortest decimal that reads back to the same bits (and -0.0 as
//! such), so equal text is equal bits.

mod rtcm_common;

use raim_nav::rtcm::decode::{msm_more_bit, DecodeError, Frame, Message as Dm, MsmSystem};
use raim_nav::rtcm::{
    fx, glonass_fields, msg1019_fields, msg1042_fields, msg1044_fields, msg1045_fields,
    msg1046_fields, LIGHT_MS_M,
};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rtcm_rs::msg::message::{Message, MessageBuilder};
use rtcm_rs::val_gen::ValGen;
use rtcm_rs::MessageFrame;

/// One MSM signal: (satellite, band, attribute, pseudorange m, C/N0 dB-Hz,
/// phase-range rate m/s).
type Signal = (u8, u8, u8, Option<f64>, Option<f64>, Option<f64>);

/// The phase-range rate of an MSM5/MSM7 signal as rtcm-rs reads it: the
/// satellite's rough rate DF399 (an integer, m/s) plus the signal's fine
/// rate DF404 (m/s), None when either is marked invalid; MSM4/MSM6 none.
macro_rules! msm_rate {
    ($m:expr, $sig:expr) => {
        None
    };
    ($m:expr, $sig:expr, rate) => {
        $m.data_segment
            .satellite_data
            .iter()
            .find(|s| s.satellite_id == $sig.satellite_id)
            .and_then(|s| s.gnss_satellite_rough_phaserange_rates_m_s)
            .zip($sig.gnss_signal_fine_phaserange_rate_m_s)
            .map(|(rough, fine)| f64::from(rough) + fine)
    };
}

/// What a frame decodes to, in one form for both decoders.
#[derive(Debug, PartialEq)]
enum Decoded {
    Msm {
        system: String,
        station_id: u16,
        epoch_ms: u32,
        /// GLONASS: DF416 (`None` = 7, unknown).
        glonass_day: Option<Option<u8>>,
        more: bool,
        signals: Vec<Signal>,
    },
    Kepler {
        number: u16,
        prn: u8,
        /// The week as sent (modulo 1024, 4096 or 8192).
        week: u16,
        fields: String,
    },
    Glo1020 {
        fields: String,
        tb_tod_s: String,
    },
    Station(String),
    /// 1013: (MJD, UTC seconds of day, GPS - UTC).
    SystemParameters(String),
    Corrupt,
    /// Not decoded by the compact decoder: another system's MSM with its
    /// DF393, or another message.
    Other(Option<bool>),
}

macro_rules! msm_ref {
    ($m:expr, $system:expr, $epoch:expr, $day:expr, $fine:ident, $cnr:ident $(, $rate:ident)?) => {{
        let m = &$m;
        let signals = m
            .data_segment
            .signal_data
            .iter()
            .map(|sig| {
                // The receiver's computation as it was with rtcm-rs.
                let rough = m
                    .data_segment
                    .satellite_data
                    .iter()
                    .find(|s| s.satellite_id == sig.satellite_id)
                    .and_then(|s| {
                        s.gnss_satellite_rough_range_integer_ms
                            .map(|i| fx(i) + s.gnss_satellite_rough_range_mod1ms_ms)
                    });
                let pr = match (rough, sig.$fine) {
                    (Some(r), Some(fine)) => Some((r + fine) * LIGHT_MS_M),
                    _ => None,
                };
                (
                    sig.satellite_id,
                    sig.signal_id.band(),
                    sig.signal_id.attribute() as u8,
                    pr,
                    // DF403 (u8, 1 dB-Hz) or DF408 (2^-4 dB-Hz); 0 is None.
                    sig.$cnr.map(f64::from),
                    msm_rate!(m, sig $(, $rate)?),
                )
            })
            .collect();
        Decoded::Msm {
            system: $system.into(),
            station_id: m.reference_station_id,
            epoch_ms: $epoch,
            glonass_day: $day,
            more: m.msm_multiple_message_flag == 1,
            signals,
        }
    }};
}

/// DF393 of the MSM types the compact decoder does not read.
macro_rules! other_msm_more {
    ($msg:expr, $($v:ident),+) => {
        match $msg {
            $(Message::$v(m) => Some(m.msm_multiple_message_flag == 1),)+
            _ => None,
        }
    };
}

/// rtcm-rs's reading of a frame.
fn reference(frame: &[u8]) -> Decoded {
    let f = MessageFrame::new(frame).expect("a checked frame");
    let msg = f.get_message();
    match msg {
        Message::Msg1074(m) => msm_ref!(
            m,
            "Gps",
            m.gps_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ms,
            gnss_signal_cnr_dbhz
        ),
        Message::Msg1075(m) => msm_ref!(
            m,
            "Gps",
            m.gps_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ms,
            gnss_signal_cnr_dbhz,
            rate
        ),
        Message::Msg1076(m) => msm_ref!(
            m,
            "Gps",
            m.gps_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ext_ms,
            gnss_signal_cnr_ext_dbhz
        ),
        Message::Msg1077(m) => msm_ref!(
            m,
            "Gps",
            m.gps_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ext_ms,
            gnss_signal_cnr_ext_dbhz,
            rate
        ),
        Message::Msg1084(m) => msm_ref!(
            m,
            "Glonass",
            m.glo_epoch_time_ms,
            Some(m.glo_day_of_week),
            gnss_signal_fine_pseudorange_ms,
            gnss_signal_cnr_dbhz
        ),
        Message::Msg1085(m) => msm_ref!(
            m,
            "Glonass",
            m.glo_epoch_time_ms,
            Some(m.glo_day_of_week),
            gnss_signal_fine_pseudorange_ms,
            gnss_signal_cnr_dbhz,
            rate
        ),
        Message::Msg1086(m) => msm_ref!(
            m,
            "Glonass",
            m.glo_epoch_time_ms,
            Some(m.glo_day_of_week),
            gnss_signal_fine_pseudorange_ext_ms,
            gnss_signal_cnr_ext_dbhz
        ),
        Message::Msg1087(m) => msm_ref!(
            m,
            "Glonass",
            m.glo_epoch_time_ms,
            Some(m.glo_day_of_week),
            gnss_signal_fine_pseudorange_ext_ms,
            gnss_signal_cnr_ext_dbhz,
            rate
        ),
        Message::Msg1094(m) => msm_ref!(
            m,
            "Galileo",
            m.gal_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ms,
            gnss_signal_cnr_dbhz
        ),
        Message::Msg1095(m) => msm_ref!(
            m,
            "Galileo",
            m.gal_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ms,
            gnss_signal_cnr_dbhz,
            rate
        ),
        Message::Msg1096(m) => msm_ref!(
            m,
            "Galileo",
            m.gal_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ext_ms,
            gnss_signal_cnr_ext_dbhz
        ),
        Message::Msg1097(m) => msm_ref!(
            m,
            "Galileo",
            m.gal_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ext_ms,
            gnss_signal_cnr_ext_dbhz,
            rate
        ),
        Message::Msg1114(m) => msm_ref!(
            m,
            "Qzss",
            m.qzss_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ms,
            gnss_signal_cnr_dbhz
        ),
        Message::Msg1115(m) => msm_ref!(
            m,
            "Qzss",
            m.qzss_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ms,
            gnss_signal_cnr_dbhz,
            rate
        ),
        Message::Msg1116(m) => msm_ref!(
            m,
            "Qzss",
            m.qzss_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ext_ms,
            gnss_signal_cnr_ext_dbhz
        ),
        Message::Msg1117(m) => msm_ref!(
            m,
            "Qzss",
            m.qzss_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ext_ms,
            gnss_signal_cnr_ext_dbhz,
            rate
        ),
        Message::Msg1124(m) => msm_ref!(
            m,
            "Beidou",
            m.bds_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ms,
            gnss_signal_cnr_dbhz
        ),
        Message::Msg1125(m) => msm_ref!(
            m,
            "Beidou",
            m.bds_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ms,
            gnss_signal_cnr_dbhz,
            rate
        ),
        Message::Msg1126(m) => msm_ref!(
            m,
            "Beidou",
            m.bds_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ext_ms,
            gnss_signal_cnr_ext_dbhz
        ),
        Message::Msg1127(m) => msm_ref!(
            m,
            "Beidou",
            m.bds_epoch_time_ms,
            None,
            gnss_signal_fine_pseudorange_ext_ms,
            gnss_signal_cnr_ext_dbhz,
            rate
        ),
        Message::Msg1019(m) => Decoded::Kepler {
            number: 1019,
            prn: m.gps_satellite_id,
            week: m.gps_week_number,
            fields: format!("{:?}", msg1019_fields(&m)),
        },
        Message::Msg1042(m) => Decoded::Kepler {
            number: 1042,
            prn: m.bds_satellite_id,
            week: m.bds_week_number,
            fields: format!("{:?}", msg1042_fields(&m)),
        },
        Message::Msg1044(m) => Decoded::Kepler {
            number: 1044,
            prn: m.qzss_satellite_id,
            week: m.qzss_week_number,
            fields: format!("{:?}", msg1044_fields(&m)),
        },
        Message::Msg1045(m) => Decoded::Kepler {
            number: 1045,
            prn: m.gal_satellite_id,
            week: m.gal_week_number,
            fields: format!("{:?}", msg1045_fields(&m)),
        },
        Message::Msg1046(m) => Decoded::Kepler {
            number: 1046,
            prn: m.gal_satellite_id,
            week: m.gal_week_number,
            fields: format!("{:?}", msg1046_fields(&m)),
        },
        Message::Msg1020(m) => {
            let (fields, tb_tod_s) = glonass_fields(&m);
            Decoded::Glo1020 {
                fields: format!("{fields:?}"),
                tb_tod_s: format!("{tb_tod_s:?}"),
            }
        }
        Message::Msg1005(m) => Decoded::Station(format!(
            "{:?}",
            [
                m.antenna_ref_point_ecef_x_m,
                m.antenna_ref_point_ecef_y_m,
                m.antenna_ref_point_ecef_z_m
            ]
        )),
        Message::Msg1006(m) => Decoded::Station(format!(
            "{:?}",
            [
                m.antenna_ref_point_ecef_x_m,
                m.antenna_ref_point_ecef_y_m,
                m.antenna_ref_point_ecef_z_m
            ]
        )),
        Message::Msg1013(m) => Decoded::SystemParameters(format!(
            "{:?}",
            (
                m.modified_julian_day_number,
                m.seconds_of_day_s,
                m.leap_seconds_gps_utc_s
            )
        )),
        Message::Corrupt
            if f.message_number().is_some_and(|n| {
                matches!(
                    n,
                    1005 | 1006
                        | 1013
                        | 1019
                        | 1020
                        | 1042
                        | 1044
                        | 1045
                        | 1046
                        | 1074..=1077
                        | 1084..=1087
                        | 1094..=1097
                        | 1114..=1117
                        | 1124..=1127
                )
            }) =>
        {
            Decoded::Corrupt
        }
        other => Decoded::Other(other_msm_more!(
            other, Msg1071, Msg1072, Msg1073, Msg1081, Msg1082, Msg1083, Msg1091, Msg1092, Msg1093,
            Msg1101, Msg1102, Msg1103, Msg1104, Msg1105, Msg1106, Msg1107, Msg1111, Msg1112,
            Msg1113, Msg1121, Msg1122, Msg1123, Msg1131, Msg1132, Msg1133, Msg1134, Msg1135,
            Msg1136, Msg1137
        )),
    }
}

/// The compact decoder's reading of a frame; for a message it does not
/// read, the DF393 the receiver takes from an MSM frame when `rtcm-rs`
/// decodes that MSM (`more_known`).
fn compact(frame: &[u8], more_known: bool) -> Decoded {
    let f = Frame::new(frame).expect("a checked frame");
    match f.message() {
        Ok(Dm::Msm(m)) => Decoded::Msm {
            system: format!("{:?}", m.system),
            station_id: m.station_id,
            epoch_ms: m.epoch_ms,
            glonass_day: (m.system == MsmSystem::Glonass)
                .then_some((m.glonass_day != 7).then_some(m.glonass_day)),
            more: m.more,
            signals: m
                .signals()
                .map(|s| {
                    (
                        s.sat_id,
                        s.band,
                        s.attribute,
                        s.pseudorange_m,
                        s.cnr_dbhz,
                        s.phase_range_rate_m_s,
                    )
                })
                .collect(),
        },
        Ok(Dm::Kepler(e)) => Decoded::Kepler {
            number: e.number,
            prn: e.prn,
            week: e.week_sent,
            fields: format!("{:?}", e.fields),
        },
        Ok(Dm::Glo1020 { fields, tb_tod_s }) => Decoded::Glo1020 {
            fields: format!("{fields:?}"),
            tb_tod_s: format!("{tb_tod_s:?}"),
        },
        Ok(Dm::Station { ecef_m }) => Decoded::Station(format!("{ecef_m:?}")),
        Ok(Dm::SystemParameters {
            mjd,
            utc_sod_s,
            gps_minus_utc_s,
        }) => Decoded::SystemParameters(format!("{:?}", (mjd, utc_sod_s, gps_minus_utc_s))),
        Err(_) => Decoded::Corrupt,
        Ok(Dm::Other(_)) => Decoded::Other(if more_known {
            msm_more_bit(frame)
        } else {
            None
        }),
    }
}

/// Both readings of a frame, asserted equal; the reading.
fn both(frame: &[u8]) -> Decoded {
    let r = reference(frame);
    let c = compact(frame, matches!(r, Decoded::Other(Some(_))));
    // The pseudoranges to the bit (the Debug text of an f64 is its bits).
    assert_eq!(format!("{r:?}"), format!("{c:?}"), "frame {frame:02x?}");
    r
}

/// Verifies: RX-DECODE, RX-DOPPLER
#[test]
fn gmsd7_every_frame_alike() {
    let bytes = std::fs::read(rtcm_common::GMSD7).expect("GMSD7 stream (../shared/data)");
    let mut n = std::collections::BTreeMap::<String, u32>::new();
    let (mut signals, mut rates) = (0usize, 0usize);
    for f in rtcm_common::frames(&bytes) {
        let number = MessageFrame::new(f).ok().and_then(|x| x.message_number());
        let d = both(f);
        let kind = match &d {
            Decoded::Msm { signals: s, .. } => {
                signals += s.len();
                rates += s.iter().filter(|x| x.5.is_some()).count();
                "msm"
            }
            Decoded::Other(Some(_)) => "other MSM (DF393 compared)",
            Decoded::Other(None) => "other",
            Decoded::Corrupt => "corrupt",
            _ => "",
        };
        *n.entry(format!("{} {kind}", number.unwrap_or(0)))
            .or_default() += 1;
    }
    println!("GMSD7 frames by type: {n:?}; {signals} MSM signals, {rates} with a phase-range rate");
    let count = |k: &str| n.get(k).copied().unwrap_or(0);
    // The stream's GPS and GLONASS MSM7 and ephemerides (README: 257
    // epochs), all decoded alike, none corrupt.
    assert!(count("1077 msm") >= 257, "{n:?}");
    assert!(count("1087 msm") >= 257, "{n:?}");
    assert!(count("1019 ") > 0 && count("1020 ") > 0, "{n:?}");
    // Its BeiDou MSM7 too.
    assert!(count("1127 msm") >= 257, "{n:?}");
    // GMSD7 has no 1005/1006 (its station is in 1007/1008/1033): they
    // are compared on random messages below. Its QZSS MSM7 (1117) is
    // refused by both decoders (`both` holds them equal): a cell's signal
    // ID is not in Table 3.5-105; nothing else is corrupt.
    assert!(
        n.iter()
            .all(|(k, v)| !k.ends_with("corrupt") || (k == "1117 corrupt" && *v >= 257)),
        "{n:?}"
    );
    let qzss_refused = rtcm_common::frames(&bytes)
        .into_iter()
        .filter(|f| MessageFrame::new(f).ok().and_then(|x| x.message_number()) == Some(1117))
        .map(|f| Frame::new(f).map(|x| x.message().map(|_| ())))
        .find(|r| !matches!(r, Ok(Err(DecodeError::SignalId { message: 1117, .. }))));
    assert_eq!(qzss_refused, None, "a 1117 refused for another reason");
    assert!(signals > 10_000, "{signals}");
    // The MSM7's rates (GPS L1 C/A, GLONASS L1 C/A, BeiDou B1I carry
    // them in this stream), compared to the bit above.
    assert!(rates > 6_000, "{rates}");
}

/// A frame around `payload` (header and CRC-24Q).
fn reframe(payload: &[u8]) -> Vec<u8> {
    let crc = crc::Crc::<u32>::new(&crc::CRC_24_LTE_A);
    let n = payload.len();
    let mut f = vec![0xD3, (n >> 8) as u8, n as u8];
    f.extend_from_slice(payload);
    let c = crc.checksum(&f);
    f.extend_from_slice(&[(c >> 16) as u8, (c >> 8) as u8, c as u8]);
    f
}

/// The compact decoder refuses an MSM of more than 64 cells before
/// `rtcm-rs` is asked: its decoder shifts a 64-bit word by the mask's
/// length, which overflows (a panic in a debug build) for such a mask.
fn too_many_cells(frame: &[u8]) -> bool {
    matches!(
        Frame::new(frame).map(|f| f.message()),
        Ok(Err(DecodeError::CellCount { satellites, signals })) if satellites * signals > 64
    )
}

/// Verifies: RX-DECODE, RX-DOPPLER
#[test]
fn random_messages_alike() {
    const PER_TYPE: usize = 600;
    let mut rng = StdRng::seed_from_u64(0x5254_434d);
    let mut val_gen = ValGen::new(
        StdRng::seed_from_u64(1),
        StdRng::seed_from_u64(2),
        StdRng::seed_from_u64(3),
    );
    let mut builder = MessageBuilder::new();
    let (mut whole, mut mutated, mut corrupt, mut invalid, mut skipped) = (0, 0, 0, 0, 0);
    // Signals of MSM5/MSM7 with a rate, and with it marked invalid.
    let (mut rates, mut no_rate) = (0, 0);
    let types = [
        1074u16, 1075, 1076, 1077, 1084, 1085, 1086, 1087, 1094, 1095, 1096, 1097, 1114, 1115,
        1116, 1117, 1124, 1125, 1126, 1127, 1019, 1020, 1042, 1044, 1045, 1046, 1005, 1006, 1013,
    ];
    for number in types {
        for _ in 0..PER_TYPE {
            let frame = builder
                .build_generated_message(&mut val_gen, number)
                .expect("rtcm-rs generates a valid message")
                .to_vec();
            match both(&frame) {
                Decoded::Msm { signals, .. } => {
                    invalid += signals.iter().filter(|s| s.3.is_none()).count();
                    if number % 2 == 1 {
                        rates += signals.iter().filter(|s| s.5.is_some()).count();
                        no_rate += signals.iter().filter(|s| s.5.is_none()).count();
                    }
                    whole += 1;
                }
                Decoded::Kepler { .. }
                | Decoded::Glo1020 { .. }
                | Decoded::Station(_)
                | Decoded::SystemParameters(_) => whole += 1,
                d => panic!("{number}: generated message read as {d:?}"),
            }
            let payload = &frame[3..frame.len() - 3];
            // A byte overwritten (masks, data, invalid markers).
            let mut p = payload.to_vec();
            let at = rng.gen_range(2..p.len());
            p[at] = [0x00, 0xFF, 0x80, 0x7F, rng.gen()][rng.gen_range(0..5)];
            // Cut short.
            let cut = payload[..rng.gen_range(2..payload.len())].to_vec();
            for m in [reframe(&p), reframe(&cut)] {
                if too_many_cells(&m) {
                    skipped += 1;
                    continue;
                }
                if both(&m) == Decoded::Corrupt {
                    corrupt += 1;
                }
                mutated += 1;
            }
        }
    }
    println!(
        "{whole} random MSM4-7 (G, R, E, J, C), 1019, 1020, 1042, 1044, 1045, 1046, 1005, 1006, 1013 alike ({invalid} invalid ranges), {mutated} altered alike ({corrupt} corrupt on both), {skipped} over 64 cells refused"
    );
    assert_eq!(whole, types.len() * PER_TYPE);
    assert!(corrupt > PER_TYPE, "{corrupt}");
    assert!(invalid > 0);
    println!("MSM5/MSM7 phase-range rates: {rates} read alike, {no_rate} invalid on both");
    assert!(rates > 1000 && no_rate > 0, "{rates} {no_rate}");
}
