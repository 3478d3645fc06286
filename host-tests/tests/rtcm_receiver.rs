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
    frames, gmsd7_moved_bare, gmsd7_moved_to, host_epochs, in_window_week, msg1013, GMSD7,
    GMSD7_NOW_WEEK, GMSD7_PIVOT_WEEK, GMSD7_WEEK, MASK_RAD,
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
    let model = raim_nav::ranging::StreamSigmas::Snapshot(Config::default().sigma_model);
    let (host, host_counts) = host_epochs(bytes, now_week);
    let mut dev = Box::new(StreamReceiver::<64, 256>::new(pivot_week));
    let mut formed = FormedEpoch::<64> {
        time_gps_s: 0.0,
        reference_m: None,
        sats: heapless::Vec::new(),
        cn0_dbhz: heapless::Vec::new(),
        rates: heapless::Vec::new(),
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
                // The C/N0 of each satellite (GSV), from the MSM's CNR.
                let host_cn0: Vec<u8> = h.prepared.sats.iter().map(|s| s.cn0_dbhz).collect();
                assert_eq!(
                    host_cn0,
                    formed.cn0_dbhz.to_vec(),
                    "C/N0 at {} s",
                    formed.time_gps_s
                );
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
    let model = raim_nav::ranging::StreamSigmas::Snapshot(Config::default().sigma_model);
    let mut dev = Box::new(StreamReceiver::<64, 8>::new(GMSD7_PIVOT_WEEK));
    let mut formed = FormedEpoch::<64> {
        time_gps_s: 0.0,
        reference_m: None,
        sats: heapless::Vec::new(),
        cn0_dbhz: heapless::Vec::new(),
        rates: heapless::Vec::new(),
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
            Some(Err(e @ FormError::LeapSecondsUnknown { .. })) => panic!("{e}"),
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

/// `bytes` without its GLONASS MSM frames (1081-1087).
fn without_glonass_msm(bytes: &[u8]) -> Vec<u8> {
    frames(bytes)
        .into_iter()
        .filter(|f| {
            let n = rtcm_rs::MessageFrame::new(f)
                .ok()
                .and_then(|m| m.message_number());
            !matches!(n, Some(1081..=1087))
        })
        .flatten()
        .copied()
        .collect()
}

/// Every epoch of `bytes` through a device receiver with pivot `pivot`:
/// the formed epochs (time and satellites, with their positions) and the
/// refusals, and the receiver's leap-second state at the end.
#[allow(clippy::type_complexity)]
fn device_epochs(
    bytes: &[u8],
    pivot: i64,
) -> (
    Vec<(f64, Vec<raim_core::RangeObservation>)>,
    Vec<FormError>,
    raim_nav::rtcm::RtcmCounts,
    raim_nav::rtcm::LeapSeconds,
) {
    let model = raim_nav::ranging::StreamSigmas::Snapshot(Config::default().sigma_model);
    let mut dev = Box::new(StreamReceiver::<64, 256>::new(pivot));
    let mut formed = FormedEpoch::<64> {
        time_gps_s: 0.0,
        reference_m: None,
        sats: heapless::Vec::new(),
        cn0_dbhz: heapless::Vec::new(),
        rates: heapless::Vec::new(),
        rejected: 0,
    };
    let (mut ok, mut refused) = (Vec::new(), Vec::new());
    for f in frames(bytes) {
        match dev.on_frame(f, &model, MASK_RAD, &mut formed) {
            None => {}
            Some(Ok(())) => ok.push((formed.time_gps_s, formed.sats.to_vec())),
            Some(Err(e)) => refused.push(e),
        }
    }
    (ok, refused, dev.counts(), dev.leap_seconds())
}

/// GPS - UTC from the stream moves the GLONASS alignment by exactly its
/// difference from the table. GMSD7 (2012: the table says 16 s) re-sent
/// as a receiver would if GPS - UTC were 17 s (`move_stream_weeks` with
/// 16 -> 17: every GLONASS MSM time of day 1,000 ms earlier, every 1020
/// state vector propagated 1 s so that its unchanged t_b is the same
/// instant of the orbit):
/// - with a 1013 carrying 17 first, every epoch joins its GLONASS data
///   (the time of day is checked to the millisecond, so only a shift of
///   exactly 1 s passes), with the original's satellites, and each
///   GLONASS position is within 1 m of the original's (the 1020 fields'
///   re-encoding; a t_b 1 s off would move it ~3.9 km);
/// - without the 1013 (the table's 16) every epoch's GLONASS data is 1 s
///   off and dropped;
/// - the original with a 1013 carrying the table's own 16 gives the
///   original's epochs to the bit, and says `Stream(16)` where the table
///   says `Table(16)`.
///
/// The host's reader (`raim_recv::rtcm::Rtcm3`) takes the count from the
/// 1013 the same way: each of these streams, the 1013 first or after the
/// last 1020, is formed by the host epoch by epoch as the unit forms it,
/// to the bit, GLONASS data joined where the unit joins it.
///
/// Verifies: RX-LEAP
#[test]
fn a_1013_leap_count_moves_the_glonass_alignment_by_its_difference() {
    use raim_nav::rtcm::LeapSeconds;
    let bytes = std::fs::read(GMSD7).expect("GMSD7 stream (../shared/data)");
    let shifted = rtcm_common::move_stream_weeks(&bytes, 0, 16, 17);
    let (orig, orig_refused, orig_counts, orig_leap) = device_epochs(&bytes, GMSD7_PIVOT_WEEK);
    assert_eq!(orig_leap, LeapSeconds::Table(16));
    assert_eq!(orig_counts.glonass_dropped, 0);
    let glonass_epochs = orig
        .iter()
        .filter(|(_, s)| s.iter().any(|o| o.id.system == raim_core::System::Glonass))
        .count();
    assert!(glonass_epochs >= 50, "{glonass_epochs}");

    let with_1013 = [msg1013(17), shifted.clone()].concat();
    let (got, refused, counts, leap) = device_epochs(&with_1013, GMSD7_PIVOT_WEEK);
    assert_eq!(leap, LeapSeconds::Stream(17));
    assert_eq!(counts.system_parameters, 1);
    assert_eq!(counts.glonass_dropped, 0);
    assert_eq!(refused, orig_refused);
    assert_eq!(got.len(), orig.len());
    let mut worst_m: f64 = 0.0;
    for ((t, a), (t0, b)) in got.iter().zip(&orig) {
        assert_eq!(t, t0);
        assert_eq!(
            a.iter().map(|o| o.id).collect::<Vec<_>>(),
            b.iter().map(|o| o.id).collect::<Vec<_>>()
        );
        for (x, y) in a.iter().zip(b) {
            if x.id.system == raim_core::System::Glonass {
                let d = (0..3)
                    .map(|i| (x.position_m[i] - y.position_m[i]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                worst_m = worst_m.max(d);
            }
        }
    }
    println!(
        "1013 with 17 s on GMSD7 moved to 17 s: {} epochs, GLONASS positions within {worst_m:.3} m of the original's",
        got.len()
    );
    assert!(worst_m < 1.0, "{worst_m} m");
    let glonass_formed = |r: &Run| {
        r.sats
            .iter()
            .filter(|s| s.iter().any(|id| id.system == raim_core::System::Glonass))
            .count()
    };
    let host_alike = device_against_host(&with_1013, GMSD7_PIVOT_WEEK, GMSD7_NOW_WEEK);
    assert_eq!(host_alike.same, orig.len());
    assert_eq!(glonass_formed(&host_alike), glonass_epochs);

    let (no_1013, _, counts, leap) = device_epochs(&shifted, GMSD7_PIVOT_WEEK);
    assert_eq!(leap, LeapSeconds::Table(16));
    // Every dated epoch (the first, before the first 1019, is not).
    assert_eq!(counts.glonass_dropped as usize, no_1013.len());
    assert_eq!(no_1013.len(), orig.len());
    assert!(no_1013
        .iter()
        .all(|(_, s)| s.iter().all(|o| o.id.system != raim_core::System::Glonass)));

    // The 1013 after the stream's last 1020, followed by its 1020s again
    // (as a receiver resends them): the GLONASS sets placed before it with
    // the table's count are dropped at once, so no epoch after it joins
    // GLONASS data to a set a second off: every GLONASS position formed
    // is within 1 m of the original's (until the 1013 the GLONASS data is
    // 1 s off and dropped).
    let all = frames(&shifted);
    let is_1020 = |f: &[u8]| {
        rtcm_rs::MessageFrame::new(f)
            .ok()
            .and_then(|m| m.message_number())
            == Some(1020)
    };
    let last = all
        .iter()
        .rposition(|f| is_1020(f))
        .expect("GMSD7 has 1020s")
        + 1;
    let late_1013: Vec<u8> = all[..last]
        .iter()
        .flat_map(|f| f.iter().copied())
        .chain(msg1013(17))
        .chain(
            all.iter()
                .filter(|f| is_1020(f))
                .flat_map(|f| f.iter().copied()),
        )
        .chain(all[last..].iter().flat_map(|f| f.iter().copied()))
        .collect();
    let (late, _, _, _) = device_epochs(&late_1013, GMSD7_PIVOT_WEEK);
    let mut joined = 0;
    for (t, a) in &late {
        let (_, b) = orig.iter().find(|(t0, _)| t0 == t).expect("same epochs");
        for x in a
            .iter()
            .filter(|o| o.id.system == raim_core::System::Glonass)
        {
            let y = b.iter().find(|o| o.id == x.id).expect("in the original");
            let d = (0..3)
                .map(|i| (x.position_m[i] - y.position_m[i]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(d < 1.0, "{:?} at {t} s: {d} m", x.id);
            joined += 1;
        }
    }
    assert!(joined > 0);
    let host_late = device_against_host(&late_1013, GMSD7_PIVOT_WEEK, GMSD7_NOW_WEEK);
    assert_eq!(host_late.same, late.len());
    assert!(glonass_formed(&host_late) > 0);
    let host_none = device_against_host(&shifted, GMSD7_PIVOT_WEEK, GMSD7_NOW_WEEK);
    assert_eq!(host_none.same, no_1013.len());
    assert_eq!(glonass_formed(&host_none), 0);

    let same = [msg1013(16), bytes.clone()].concat();
    let (again, _, _, leap) = device_epochs(&same, GMSD7_PIVOT_WEEK);
    assert_eq!(leap, LeapSeconds::Stream(16));
    assert_eq!(again, orig);
}

/// The leap-second table expires on 2027-06-28 (`raim_nav::time`). GMSD7
/// re-sent in GPS week 2480 (2027-07-18, past the expiry), into a unit
/// whose pivot dates it there:
/// - with no 1013, every epoch (each has GLONASS MSM) is refused
///   `LeapSecondsUnknown`, none is formed, and the receiver says
///   `TableExpired`;
/// - the same stream without its GLONASS MSM is formed epoch by epoch as
///   the host forms it (GPS only);
/// - with a 1013 carrying 18 s, every epoch is formed with its GLONASS
///   data, as the host (which dates by its table) forms it.
///
/// Sent in week 2470 (2027-05-09, before the expiry) with no 1013, the
/// table is used: every epoch is formed with GLONASS, as on the host, and
/// the receiver says `Table(18)`.
///
/// Verifies: RX-LEAP, RX-STREAM
#[test]
fn past_the_table_expiry_glonass_epochs_are_refused_and_gps_formed() {
    use raim_nav::rtcm::LeapSeconds;
    use raim_nav::time::LEAP_TABLE_EXPIRES_GPS_S;
    let bytes = std::fs::read(GMSD7).expect("GMSD7 stream (../shared/data)");
    let week_s = raim_nav::ephemeris::WEEK_S;
    let (after, before) = (2480, 2470);
    assert!(after as f64 * week_s > LEAP_TABLE_EXPIRES_GPS_S);
    assert!(((before + 1) as f64) * week_s < LEAP_TABLE_EXPIRES_GPS_S);

    let late = gmsd7_moved_bare(&bytes, after);
    // As the tests' moved streams are sent past the expiry: led by a 1013.
    assert_eq!(
        gmsd7_moved_to(&bytes, after),
        [msg1013(18), late.clone()].concat()
    );
    let (ok, refused, counts, leap) = device_epochs(&late, after - 26);
    assert_eq!(leap, LeapSeconds::TableExpired);
    assert!(ok.is_empty(), "{} formed", ok.len());
    let unknown = refused
        .iter()
        .filter(|e| matches!(e, FormError::LeapSecondsUnknown { .. }))
        .count();
    assert_eq!(unknown + 1, counts.epochs as usize, "{refused:?}");

    let gps_only = device_against_host(&without_glonass_msm(&late), after - 26, after + 1);
    assert!(gps_only.same >= 250, "{}", gps_only.same);
    assert!(gps_only
        .sats
        .iter()
        .flatten()
        .all(|s| s.system == raim_core::System::Gps));

    let told = [msg1013(18), late.clone()].concat();
    let run = device_against_host(&told, after - 26, after + 1);
    assert!(run.same >= 250, "{}", run.same);
    assert_eq!(run.counts.glonass_dropped, 0);
    let with_glonass = |r: &Run| {
        r.sats
            .iter()
            .filter(|s| s.iter().any(|id| id.system == raim_core::System::Glonass))
            .count()
    };
    let told_glonass = with_glonass(&run);
    assert_eq!(device_epochs(&told, after - 26).3, LeapSeconds::Stream(18));

    let early = gmsd7_moved_to(&bytes, before);
    let run = device_against_host(&early, before - 26, before + 1);
    assert!(run.same >= 250, "{}", run.same);
    assert_eq!(run.counts.glonass_dropped, 0);
    assert_eq!(device_epochs(&early, before - 26).3, LeapSeconds::Table(18));
    // The GLONASS satellites above the mask: as many epochs with them
    // either way (GMSD7's 1020s cover 3 of its 6 GLONASS satellites).
    assert!(told_glonass >= 50, "{told_glonass}");
    assert_eq!(told_glonass, with_glonass(&run));
    println!(
        "week {after}: {unknown} epochs with GLONASS MSM refused, {} GPS-only formed; with a 1013 {told_glonass} formed with GLONASS satellites; week {before}: {} formed with the table, {} with GLONASS satellites",
        gps_only.same,
        run.same,
        with_glonass(&run)
    );
}

/// A byte sink for the host server's link and NMEA outputs.
struct Sink(Vec<u8>);
impl embedded_io::ErrorType for Sink {
    type Error = core::convert::Infallible;
}
impl embedded_io::Write for Sink {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.0.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// `bytes` then a `Status` request through raim-server's `Server` (the
/// firmware's protocol loop, on the host, with this build's pivot): the
/// unasked stream answers and the `Status`.
fn server_run(
    bytes: &[u8],
) -> (
    Vec<raim_proto::message::ResponseBody>,
    raim_proto::message::Status,
) {
    let (answers, status, _) = server_run_nmea(bytes);
    (answers, status)
}

/// [`server_run`], with the NMEA the unit wrote.
fn server_run_nmea(
    bytes: &[u8],
) -> (
    Vec<raim_proto::message::ResponseBody>,
    raim_proto::message::Status,
    String,
) {
    use raim_proto::message::{CommandRef, RequestRef, Response, ResponseBody};
    let mut server = raim_server::Server::new();
    server.take_runtime_config(Config::default()).unwrap();
    let (mut link, mut nmea) = (Sink(Vec::new()), Sink(Vec::new()));
    let status = raim_qemu::encode_request(&RequestRef {
        seq: 1,
        command: CommandRef::Status,
    })
    .unwrap();
    // A pause-free line: the request frame follows the stream's last frame.
    for &b in bytes.iter().chain(&status) {
        server
            .on_byte(b, &mut link, &mut nmea, &mut raim_server::NoPlatform)
            .unwrap();
    }
    let mut rx = raim_proto::frame::FrameReceiver::<{ raim_proto::MAX_RESPONSE_FRAME }>::new();
    let mut answers = Vec::new();
    let mut found = None;
    for &b in &link.0 {
        if let Some(Ok(p)) = rx.push(b) {
            let r: Response = postcard::from_bytes(p).expect("an answer");
            match (r.seq, r.body) {
                (Some(1), ResponseBody::Status(s)) => found = Some(s),
                (None, body) => answers.push(body),
                other => panic!("{other:?}"),
            }
        }
    }
    (
        answers,
        found.expect("Status answered"),
        String::from_utf8(nmea.0).expect("NMEA is text"),
    )
}

/// The unit says in `Status` where its GPS - UTC comes from, and refuses
/// GLONASS epochs on the wire once its table has expired: GMSD7's first
/// 30 kB re-sent 90 weeks after this build's pivot (38 after its date: past
/// the table's expiry for any build from 2026-10; its ephemerides first)
/// through raim-server's
/// `Server`: every epoch
/// with GLONASS data is answered `StreamLeapSecondsUnknown` and `Status`
/// says `TableExpired`; with a 1013 carrying 18 s first, the epochs are
/// answered with results and `Status` says `Stream { 18 }`. Before any
/// stream, `NotDated`.
///
/// Verifies: RX-LEAP, WIRE-StreamLeapSecondsUnknown
#[test]
fn status_says_the_leap_table_has_expired_and_glonass_epochs_are_refused() {
    use raim_proto::error::WireError;
    use raim_proto::message::{ResponseBody, StreamLeapSeconds};
    let bytes = std::fs::read(GMSD7).expect("GMSD7 stream (../shared/data)");
    let week = raim_server::stream::PIVOT_WEEK + 90;
    assert!(week as f64 * raim_nav::ephemeris::WEEK_S > raim_nav::time::LEAP_TABLE_EXPIRES_GPS_S);
    let moved = gmsd7_moved_bare(&bytes, week);
    let all = frames(&moved);
    // The stream's ephemerides first, as a receiver sends its stored
    // ones at start-up, then its first 30 kB.
    let number = |f: &&[u8]| {
        rtcm_rs::MessageFrame::new(f)
            .ok()
            .and_then(|m| m.message_number())
    };
    let part: Vec<u8> = all
        .iter()
        .filter(|f| matches!(number(f), Some(1019 | 1020)))
        .chain(
            all.iter()
                .take_while(|f| f.as_ptr() as usize - moved.as_ptr() as usize + f.len() <= 30_000),
        )
        .flat_map(|f| f.iter().copied())
        .collect();

    let (_, s) = server_run(&[]);
    assert_eq!(s.stream_leap_seconds, StreamLeapSeconds::NotDated);

    let (answers, s) = server_run(&part);
    let epochs = answers.len();
    assert_eq!(s.stream_leap_seconds, StreamLeapSeconds::TableExpired);
    let refused = answers
        .iter()
        .filter(|a| {
            matches!(
                a,
                ResponseBody::Error(WireError::StreamLeapSecondsUnknown { .. })
            )
        })
        .count();
    assert!(refused >= 25, "{answers:?}");
    assert!(
        answers.iter().all(|a| matches!(
            a,
            ResponseBody::Error(
                WireError::StreamLeapSecondsUnknown { .. } | WireError::StreamNotDated { .. }
            )
        )),
        "{answers:?}"
    );

    let told = [msg1013(18), part].concat();
    let (answers, s) = server_run(&told);
    assert_eq!(
        s.stream_leap_seconds,
        StreamLeapSeconds::Stream {
            gps_minus_utc_s: 18
        }
    );
    // Each epoch answered as without GLONASS trouble: a result, or the
    // core's refusal (the stream's first epochs have too few satellites
    // with an ephemeris), never `StreamLeapSecondsUnknown`.
    assert_eq!(answers.len(), epochs);
    assert!(!answers.iter().any(|a| matches!(
        a,
        ResponseBody::Error(WireError::StreamLeapSecondsUnknown { .. })
    )));
    let results = answers
        .iter()
        .filter(|a| matches!(a, ResponseBody::Result(_)))
        .count();
    assert!(results > 0, "{answers:?}");
    println!(
        "{refused} stream epochs refused StreamLeapSecondsUnknown past the table's expiry; with a 1013, {} answered ({results} results)",
        answers.len()
    );
}

/// The UTC time and date of the unit's RMC and ZDA sentences use the leap
/// seconds in force: GMSD7 re-sent past the table's expiry (8 weeks after
/// this build), its ephemerides first, with a 1013 carrying 18 s, then
/// the same with 17 s: every RMC and ZDA time of the second run is one
/// second later than the first's, dates included (the GPS epochs are the same; with 17 s
/// the stream's GLONASS times are a second off and dropped, so only the
/// sentences' times are compared).
///
/// Verifies: RX-LEAP
#[test]
fn nmea_dates_use_the_leap_seconds_in_force() {
    let bytes = std::fs::read(GMSD7).expect("GMSD7 stream (../shared/data)");
    let moved = gmsd7_moved_bare(&bytes, raim_server::stream::PIVOT_WEEK + 60);
    let all = frames(&moved);
    let number = |f: &&[u8]| {
        rtcm_rs::MessageFrame::new(f)
            .ok()
            .and_then(|m| m.message_number())
    };
    let part: Vec<u8> = all
        .iter()
        .filter(|f| matches!(number(f), Some(1019 | 1020)))
        .chain(all.iter().take(400))
        .flat_map(|f| f.iter().copied())
        .collect();
    // hhmmss.ss of each RMC and ZDA sentence, as seconds of the day, and
    // their dates.
    let times = |nmea: &str, kind: &str| -> Vec<(f64, String)> {
        nmea.lines()
            .filter(|l| l.get(3..6) == Some(kind))
            .filter_map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                let t = f.get(1)?;
                let s = t.get(0..2)?.parse::<f64>().ok()? * 3600.0
                    + t.get(2..4)?.parse::<f64>().ok()? * 60.0
                    + t.get(4..)?.parse::<f64>().ok()?;
                let date = match kind {
                    "RMC" => f.get(9)?.to_string(),
                    _ => f.get(2..5)?.join("/"),
                };
                Some((s, date))
            })
            .collect()
    };
    let (_, s18, nmea18) = server_run_nmea(&[msg1013(18), part.clone()].concat());
    let (_, s17, nmea17) = server_run_nmea(&[msg1013(17), part].concat());
    assert_eq!(
        s18.stream_leap_seconds,
        raim_proto::message::StreamLeapSeconds::Stream {
            gps_minus_utc_s: 18
        }
    );
    assert_eq!(
        s17.stream_leap_seconds,
        raim_proto::message::StreamLeapSeconds::Stream {
            gps_minus_utc_s: 17
        }
    );
    for kind in ["RMC", "ZDA"] {
        let (a, b) = (times(&nmea18, kind), times(&nmea17, kind));
        assert!(a.len() >= 20, "{kind}: {} sentences", a.len());
        assert_eq!(a.len(), b.len(), "{kind}");
        for ((ta, da), (tb, db)) in a.iter().zip(&b) {
            // GMSD7 starts 18 s before UTC midnight: a sentence a second
            // later may be of the next day.
            let day_s = if da == db { 0.0 } else { 86_400.0 };
            assert!(
                (tb + day_s - ta - 1.0).abs() < 1e-6,
                "{kind}: {ta} {da} then {tb} {db}"
            );
        }
    }
}
