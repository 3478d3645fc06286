//! The stream receiver on a real station stream, inside the crate (its
//! own unit tests, which `scripts/coverage.sh` measures): GMSD7 (2012-10-14,
//! `/work/shared/data/GMSD7_20121014.rtcm3`; GPS, GLONASS and BeiDou MSM7,
//! 1019, 1020 and the station's 1005/1006). The host tests hold the same
//! receiver to the host reader bit for bit (host-tests/tests/rtcm_receiver.rs);
//! these check it against numbers from outside the receiver: the fixes'
//! scatter and residuals (the antenna is static), and the file's own
//! message counts.

use std::boxed::Box;
use std::vec::Vec;

use raim_core::solve::solve;
use raim_core::stats::dist::chi2_quantile_upper;
use raim_core::{Config, Epoch, System};

use super::{FormError, FormedEpoch, LeapSeconds, StreamReceiver};
use crate::ranging::StreamSigmas;

/// The GPS week GMSD7 starts in: its first epoch is 15 s before the end of
/// week 1709 (2012-10-13 23:59:45 GPS time), the rest in week 1710.
const GMSD7_WEEK: i64 = 1709;
/// The pivot of a unit built when the stream was recorded (a year before).
const PIVOT_WEEK: i64 = GMSD7_WEEK - 52;
/// The firmware's stream elevation mask (raim-server's `STREAM_MASK_RAD`).
const MASK_RAD: f64 = 10.0 * core::f64::consts::PI / 180.0;

fn gmsd7() -> Vec<u8> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/GMSD7_20121014.rtcm3"
    );
    std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The frames of `bytes` by the RTCM 10403.3 framing alone (preamble 0xD3,
/// 6 reserved bits, a 10-bit length, the payload and 3 CRC bytes), without
/// the decoder under test; the CRC is left to the receiver.
fn frames(bytes: &[u8]) -> Vec<&[u8]> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 3 <= bytes.len() {
        if bytes[i] != 0xD3 {
            i += 1;
            continue;
        }
        let len = (usize::from(bytes[i + 1] & 0x03) << 8) | usize::from(bytes[i + 2]);
        let end = i + 3 + len + 3;
        if end > bytes.len() {
            break;
        }
        out.push(&bytes[i..end]);
        i = end;
    }
    out
}

/// The message number (DF002) of a frame.
fn number(frame: &[u8]) -> u16 {
    (u16::from(frame[3]) << 4) | (u16::from(frame[4]) >> 4)
}

fn empty<const N: usize>() -> FormedEpoch<N> {
    FormedEpoch {
        time_gps_s: 0.0,
        reference_m: None,
        sats: heapless::Vec::new(),
        cn0_dbhz: heapless::Vec::new(),
        rates: heapless::Vec::new(),
        rejected: 0,
    }
}

/// The epochs the receiver forms from GMSD7 are a real receiver's at a
/// static antenna: every epoch with 6 satellites or more (GPS and
/// GLONASS; BeiDou and QZSS have no ephemeris in this stream) solves
/// (raim-core's weighted Gauss-Newton, SPEC §1) with a weighted residual
/// under the chi-square quantile at 1e-3 (SPEC §3) in 95 % of the epochs
/// at least, and every fix is within 25 m of the stream's median fix (the
/// stream sigmas' scale; a wrong week, time of week, clock or ephemeris
/// field moves a fix or a residual by kilometres). The GPS times increase
/// from the end of week 1709 into week 1710, half the solved epochs at
/// least use GLONASS, and the counts are the file's own: every frame
/// counted, every closed epoch formed but the one before the first 1019,
/// every 1117 (a QZSS signal ID outside Table 3.5-105) undecodable, every
/// 1019/1020 taken; the leap seconds come from the built-in table (2012:
/// 16 s).
///
/// Verifies: RX-STREAM, RX-STREAM-FIX
#[test]
fn gmsd7_epochs_solve_as_a_static_receiver() {
    let bytes = gmsd7();
    let all = frames(&bytes);
    let config = Config::default();
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(PIVOT_WEEK));
    assert_eq!(rx.leap_seconds(), LeapSeconds::NotDated);
    let mut out = Box::new(empty::<64>());
    let (mut formed, mut not_dated, mut with_glonass, mut worst_m) = (0u32, 0u32, 0u32, 0.0f64);
    let mut solvable: Vec<(
        f64,
        Option<[f64; 3]>,
        heapless::Vec<raim_core::RangeObservation, 64>,
    )> = Vec::new();
    let mut last_t = f64::NEG_INFINITY;
    let mut first_t = None;
    for f in &all {
        match rx.on_frame(
            f,
            &StreamSigmas::Snapshot(config.sigma_model),
            MASK_RAD,
            &mut out,
        ) {
            None => {}
            Some(Err(FormError::NotDated { .. })) => not_dated += 1,
            Some(Err(e)) => panic!("{e}"),
            Some(Ok(())) => {
                formed += 1;
                let week = (out.time_gps_s / crate::ephemeris::WEEK_S).floor() as i64;
                assert!(
                    week == GMSD7_WEEK || week == GMSD7_WEEK + 1,
                    "epoch at {} s",
                    out.time_gps_s
                );
                assert!(last_t < out.time_gps_s, "{last_t} then {}", out.time_gps_s);
                last_t = out.time_gps_s;
                first_t.get_or_insert(out.time_gps_s);
                let systems = |s: System| out.sats.iter().filter(|o| o.id.system == s).count();
                assert_eq!(systems(System::Beidou), 0);
                if systems(System::Gps) + systems(System::Glonass) >= 6 {
                    with_glonass += u32::from(systems(System::Glonass) > 0);
                    solvable.push((out.time_gps_s, out.reference_m, out.sats.clone()));
                }
            }
        }
    }
    // Every epoch solved (SPEC §1), its weighted residual against the
    // chi-square quantile at 1e-3 (SPEC §3) and its fix against the
    // median fix of the stream (a static antenna).
    let mut fixes = Vec::new();
    let mut consistent = 0usize;
    for (t, reference_m, sats) in &solvable {
        let epoch = Epoch::ranges(*t, sats, *reference_m);
        let sol = solve::<64>(&config, &epoch, &[true; 64]).expect("solvable");
        fixes.push(sol.position_ecef_m.expect("pseudorange input"));
        let dof = sol.parity.dof() as u32;
        let t2 = chi2_quantile_upper(1e-3, dof).expect("dof >= 1");
        consistent += usize::from(sol.parity.sse() <= t2);
    }
    let median = |k: usize| {
        let mut v: Vec<f64> = fixes.iter().map(|p| p[k]).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let centre = [median(0), median(1), median(2)];
    for p in &fixes {
        let d = libm::sqrt((0..3).map(|k| (p[k] - centre[k]).powi(2)).sum::<f64>());
        worst_m = worst_m.max(d);
    }
    let geo = raim_core::frames::ecef_to_geodetic(centre);
    std::println!(
        "centre {centre:?} lat {} lon {} h {}; consistent {consistent} of {}",
        geo.lat_rad.to_degrees(),
        geo.lon_rad.to_degrees(),
        geo.height_m,
        fixes.len()
    );
    std::println!(
        "GMSD7: {} frames, {formed} epochs formed, {not_dated} not dated; worst distance to the median fix {worst_m:.2} m; {:?}",
        all.len(),
        rx.counts()
    );
    assert!(worst_m < 25.0, "{worst_m} m");
    assert!(
        consistent * 20 >= fixes.len() * 19,
        "{consistent} of {}",
        fixes.len()
    );
    assert!(solvable.len() >= 40, "{}", solvable.len());
    assert!(
        with_glonass as usize >= solvable.len() / 2,
        "{with_glonass}"
    );
    let c = rx.counts();
    assert_eq!(c.frames as usize, all.len());
    // One GPS MSM7 per epoch in this stream.
    assert_eq!(
        c.epochs as usize,
        all.iter().filter(|f| number(f) == 1077).count()
    );
    assert_eq!(formed + not_dated, c.epochs);
    assert!(formed >= 250, "{formed}");
    assert!(not_dated <= 1, "{not_dated}");
    assert_eq!(
        c.undecodable as usize,
        all.iter().filter(|f| number(f) == 1117).count()
    );
    assert_eq!(
        c.ephemerides as usize,
        all.iter()
            .filter(|f| matches!(number(f), 1019 | 1020))
            .count()
    );
    assert_eq!(c.glonass_dropped, 0);
    assert_eq!(rx.leap_seconds(), LeapSeconds::Table(16));
    let t = first_t.expect("an epoch");
    assert_eq!(rx.utc_offset_s(t), 16.0);
    let (kepler, glonass) = rx.ephemerides();
    assert!(kepler > 0 && glonass > 0, "{kepler} {glonass}");
}

/// A receiver whose signal capacity is below one epoch's refuses every
/// epoch whole with `TooManySignals` and that capacity (the unit's
/// `StreamCapacity`), and its message names the capacity.
///
/// Verifies: WIRE-StreamCapacity
#[test]
fn an_epoch_over_the_signal_capacity_is_refused_with_the_capacity() {
    let bytes = gmsd7();
    let config = Config::default();
    let mut rx = Box::new(StreamReceiver::<64, 4>::new(PIVOT_WEEK));
    let mut out = Box::new(empty::<64>());
    let mut refused = 0;
    for f in frames(&bytes) {
        match rx.on_frame(
            f,
            &StreamSigmas::Snapshot(config.sigma_model),
            MASK_RAD,
            &mut out,
        ) {
            Some(Err(e @ FormError::TooManySignals { capacity })) => {
                assert_eq!(capacity, 4);
                assert!(out.sats.is_empty());
                assert_eq!(std::format!("{e}"), "more than 4 signals in one epoch");
                refused += 1;
            }
            Some(Ok(())) => panic!("an epoch of more than 4 signals was formed"),
            _ => {}
        }
    }
    assert!(refused >= 250, "{refused}");
}

/// The refusals' messages carry their time of week: an epoch before any
/// ephemeris, and GLONASS data with GPS - UTC unknown.
///
/// Verifies: WIRE-StreamNotDated, WIRE-StreamLeapSecondsUnknown
#[test]
fn the_refusals_name_their_epoch() {
    let e = FormError::NotDated {
        tow_ms: 345_600_000,
    };
    assert!(
        std::format!("{e}").contains("345600000 ms not dated"),
        "{e}"
    );
    let e = FormError::LeapSecondsUnknown { tow_ms: 7 };
    assert!(std::format!("{e}").contains("7 ms has GLONASS data"), "{e}");
}
