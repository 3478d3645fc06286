//! The firmware's RTCM 3 receiver (`raim_nav::rtcm::StreamReceiver`, no_std,
//! fixed capacity) against the host's stream reader (`raim_recv::rtcm`, a
//! separate decoder, dating and ephemeris store) on the real GMSD7 stream
//! (GPS + GLONASS MSM7, 1019 and 1020; ../shared/data/README.md).
//!
//! The host is run causally, as its live mode runs (`rtcm_common`). Both
//! sides use raim-nav's ranging kernel, so an epoch both form must be the
//! same to the bit: time, reference, satellites, pseudoranges, positions
//! and sigmas.

mod rtcm_common;

use raim_core::Config;
use raim_nav::rtcm::{FormError, FormedEpoch, StreamReceiver};
use rtcm_common::{
    frames, gmsd7_moved_to, host_epochs, in_window_week, GMSD7, GMSD7_NOW_WEEK, GMSD7_PIVOT_WEEK,
    GMSD7_WEEK, MASK_RAD,
};

/// What one run of the device receiver against the host gave.
struct Run {
    same: usize,
    not_dated: usize,
    /// The time of every epoch formed alike, GPS s.
    times_gps_s: Vec<f64>,
    /// The satellites of every epoch formed alike.
    sats: Vec<Vec<raim_core::SatId>>,
    counts: raim_nav::rtcm::RtcmCounts,
    host_counts: raim_recv::Counts,
}

/// The device receiver (pivot `pivot_week`) and the host's causal replay
/// (clock at `now_week`) on `bytes`: every epoch the device forms must be
/// the host's, to the bit.
fn device_against_host(bytes: &[u8], pivot_week: i64, now_week: i64) -> Run {
    let model = Config::default().sigma_model;
    let (host, host_counts) = host_epochs(bytes, now_week);
    let mut dev = Box::new(StreamReceiver::<64, 256>::new(pivot_week));
    let mut formed = FormedEpoch::<64> {
        time_gps_s: 0.0,
        reference_m: None,
        sats: heapless::Vec::new(),
        rejected: 0,
    };
    let (mut same, mut not_dated, mut times_gps_s, mut sats) = (0, 0, Vec::new(), Vec::new());
    for (n, f) in frames(bytes).into_iter().enumerate() {
        match dev.on_frame(f, &model, MASK_RAD, &mut formed) {
            None => {}
            Some(Err(FormError::NotDated { .. })) => not_dated += 1,
            Some(Err(e)) => panic!("{e}"),
            Some(Ok(())) => {
                let h = host
                    .iter()
                    .find(|h| h.prepared.time_gps_s == formed.time_gps_s)
                    .unwrap_or_else(|| {
                        panic!("device epoch at {} s, none on the host", formed.time_gps_s)
                    });
                assert_eq!(h.frame, n, "epoch {} s", formed.time_gps_s);
                assert_eq!(h.prepared.reference_m, formed.reference_m);
                assert_eq!(
                    h.obs.len(),
                    formed.sats.len(),
                    "epoch {} s",
                    formed.time_gps_s
                );
                for (h, d) in h.obs.iter().zip(formed.sats.iter()) {
                    assert_eq!(h.id, d.id);
                    assert_eq!(
                        h.pseudorange_m.to_bits(),
                        d.pseudorange_m.to_bits(),
                        "{:?}",
                        h.id
                    );
                    assert_eq!(h.position_m, d.position_m, "{:?}", h.id);
                    assert_eq!(h.sigma_m, d.sigma_m, "{:?}", h.id);
                }
                times_gps_s.push(formed.time_gps_s);
                sats.push(formed.sats.iter().map(|s| s.id).collect());
                same += 1;
            }
        }
    }
    Run {
        same,
        not_dated,
        times_gps_s,
        sats,
        counts: dev.counts(),
        host_counts,
    }
}

/// GMSD7 re-sent as in a week of this build's dating window
/// (`rtcm_common::gmsd7_moved_to`: 1019 weeks moved on, the GLONASS times
/// moved by the leap seconds between 2012 and the moved date, CRC
/// recomputed), into a unit whose pivot is this build's (raim-server's
/// `PIVOT_WEEK`, from the build date): every epoch is dated in the moved
/// week, none in 2007 or 2032; the device and the host (clock a week
/// later) form the same epochs, with the original's GPS times of week and
/// its satellites, GLONASS included (joined at the right second, none
/// dropped).
///
/// Verifies: RX-DATING, RX-STREAM
#[test]
fn a_stream_sent_today_is_dated_today() {
    let bytes = std::fs::read(GMSD7).expect("GMSD7 stream (../shared/data)");
    let week = in_window_week();
    let delta = week - GMSD7_WEEK;
    let moved = gmsd7_moved_to(&bytes, week);
    let run = device_against_host(&moved, raim_server::stream::PIVOT_WEEK, week + 1);
    let original = device_against_host(&bytes, GMSD7_PIVOT_WEEK, GMSD7_NOW_WEEK);
    println!(
        "GMSD7 moved {delta} weeks to week {week}: {} epochs formed alike, {} not dated; counts {:?}",
        run.same, run.not_dated, run.counts
    );
    assert_eq!(run.counts.epochs, original.counts.epochs);
    assert_eq!(run.same + run.not_dated, run.counts.epochs as usize);
    assert!(run.same >= 250, "{}", run.same);
    let week_s = raim_nav::ephemeris::WEEK_S;
    for t in &run.times_gps_s {
        let w = (t / week_s).floor() as i64;
        assert!(
            w == week || w == week + 1,
            "epoch at {t} s dated in week {w}"
        );
    }
    // The same GPS times of week as the original.
    let shift_s = delta as f64 * week_s;
    for (a, b) in run.times_gps_s.iter().zip(&original.times_gps_s) {
        assert_eq!(*a, b + shift_s);
    }
    assert_eq!(run.counts.glonass_dropped, 0);
    assert_eq!(run.sats, original.sats);
}

/// Verifies: RX-STREAM
#[test]
fn device_receiver_forms_the_host_epochs_bit_for_bit() {
    let bytes = std::fs::read(GMSD7).expect("GMSD7 stream (../shared/data)");
    // A unit built when the stream was recorded.
    let Run {
        same,
        not_dated,
        counts: c,
        host_counts,
        ..
    } = device_against_host(&bytes, GMSD7_PIVOT_WEEK, GMSD7_NOW_WEEK);
    println!(
        "GMSD7: {same} epochs formed alike, {not_dated} before the first 1019; host counts {host_counts:?}; device counts {c:?}"
    );
    // 257 epochs in the stream; the one before the first GPS ephemeris
    // cannot be dated on the device (the host holds it back until then).
    assert_eq!(same + not_dated, c.epochs as usize);
    assert_eq!(c.epochs as u64, host_counts.epochs);
    assert!(same >= 250, "{same}");
    // Neither rtcm-rs nor the device's decoder reads this stream's QZSS
    // MSM7 (1117: a signal ID outside Table 3.5-105): both count it
    // undecodable. The device reads its GPS, GLONASS and BeiDou MSM7 and
    // its 1019/1020 (no BeiDou ephemeris: its BeiDou satellites are
    // rejected on both sides); every other message is counted ignored.
    let number = |f: &&[u8]| {
        rtcm_rs::MessageFrame::new(f)
            .ok()
            .and_then(|x| x.message_number())
    };
    let all = frames(&bytes);
    let qzss = all.iter().filter(|f| number(f) == Some(1117)).count();
    let other = all
        .iter()
        .filter(|f| !matches!(number(f), Some(1077 | 1087 | 1127 | 1019 | 1020 | 1117)))
        .count();
    assert_eq!(c.undecodable as usize, qzss);
    assert_eq!(host_counts.undecodable, qzss as u64);
    assert_eq!(c.ignored as usize, other);
    assert_eq!(c.glonass_dropped, 0);
}

/// A receiver that holds fewer signals than an epoch carries refuses that
/// epoch with `TooManySignals` and its capacity (the unit answers it
/// `StreamCapacity`), and forms none of it; the next epochs are refused
/// alike, and nothing else is lost (every epoch is counted).
///
/// Verifies: WIRE-StreamCapacity
#[test]
fn an_epoch_beyond_the_signal_capacity_is_refused_whole() {
    let bytes = std::fs::read(GMSD7).expect("GMSD7 stream (../shared/data)");
    let model = Config::default().sigma_model;
    let mut dev = Box::new(StreamReceiver::<64, 8>::new(GMSD7_PIVOT_WEEK));
    let mut formed = FormedEpoch::<64> {
        time_gps_s: 0.0,
        reference_m: None,
        sats: heapless::Vec::new(),
        rejected: 0,
    };
    let (mut refused, mut closed) = (0, 0);
    for f in frames(&bytes) {
        match dev.on_frame(f, &model, MASK_RAD, &mut formed) {
            None => {}
            Some(Err(FormError::TooManySignals { capacity })) => {
                assert_eq!(capacity, 8);
                assert!(formed.sats.is_empty());
                refused += 1;
                closed += 1;
            }
            Some(Err(FormError::NotDated { .. })) => closed += 1,
            Some(Ok(())) => panic!("an epoch of more than 8 signals was formed"),
        }
    }
    assert!(refused >= 250, "{refused}");
    assert_eq!(closed, dev.counts().epochs);
}

/// The device receiver integrates each GLONASS orbit once per epoch, from
/// the RK4 node its previous epoch reached (`raim_nav::glonass::GlonassArc`),
/// instead of from t_b for every evaluation. On real broadcast state
/// vectors, every 1020 of GMSD7 (decoded by the device's decoder) and the
/// first 120 GLONASS records of ESBC's navigation file, evaluated as a
/// 1 Hz receiver asks (transmit times about 70 ms before each second,
/// every 3rd second from t_b - 30 min to t_b + 30 min, then back to t_b -
/// 10 min and across t_b), the arc's position and velocity are the ICD
/// integration's from t_b to the bit: the tolerance is 0 m.
///
/// Verifies: RX-GLONASS-ARC
#[test]
fn glonass_arcs_give_the_icd_integration_on_real_ephemerides() {
    use raim_nav::glonass::{glonass_time_of_day_to_gps_s, GlonassArc, GlonassEphemeris};
    use raim_nav::rtcm::decode::{Frame, Message};
    let bytes = std::fs::read(GMSD7).expect("GMSD7 stream (../shared/data)");
    // GMSD7 is 2012-10-14, 00:00 GPS of week 1709's first day.
    let near_gps_s = GMSD7_WEEK as f64 * raim_nav::ephemeris::WEEK_S;
    let mut ephs: Vec<GlonassEphemeris> = Vec::new();
    for f in frames(&bytes) {
        if let Ok(Message::Glo1020 { fields, tb_tod_s }) = Frame::new(f).unwrap().message() {
            let fields = raim_nav::glonass::GlonassIcdFields {
                tb_gps_s: glonass_time_of_day_to_gps_s(tb_tod_s, near_gps_s),
                ..fields
            };
            if let Ok(g) = GlonassEphemeris::from_icd(&fields) {
                ephs.push(g);
            }
        }
    }
    let from_stream = ephs.len();
    let nav = raim_gnss::NavData::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/data/ESBC00DNK_R_20201770000_01D_MN.rnx.gz"
    )))
    .expect("ESBC navigation file (../shared/data)");
    ephs.extend(nav.glonass.values().flatten().take(120).copied());
    assert!(from_stream >= 16 && ephs.len() >= from_stream + 120);
    let mut evaluations = 0;
    let mut max_m: f64 = 0.0;
    for g in &ephs {
        let mut arc = GlonassArc::new(g);
        let forward = (-1800..=1800).step_by(3).map(|k| f64::from(k) - 0.071_3);
        let back = (-600..=600).step_by(7).map(|k| f64::from(k) - 0.068_9);
        for dt in forward.chain(back) {
            let t = g.tb_gps_s + dt;
            let (p, v) = arc.propagate_pz90(t);
            let (p0, v0) = g.propagate_pz90(t);
            assert_eq!(
                p.map(f64::to_bits),
                p0.map(f64::to_bits),
                "R{:02} at t_b {dt:+} s",
                g.slot
            );
            assert_eq!(
                v.map(f64::to_bits),
                v0.map(f64::to_bits),
                "R{:02} at t_b {dt:+} s",
                g.slot
            );
            let d = (0..3).map(|i| (p[i] - p0[i]).powi(2)).sum::<f64>().sqrt();
            max_m = max_m.max(d);
            evaluations += 1;
        }
    }
    println!(
        "GLONASS arcs: {} ephemerides ({from_stream} from GMSD7's 1020, {} from ESBC), {evaluations} evaluations, largest position difference from the ICD integration {max_m} m",
        ephs.len(),
        ephs.len() - from_stream
    );
}
