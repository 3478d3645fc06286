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
