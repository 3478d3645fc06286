//! A multi-constellation receiver stream built from real data: ESBC's
//! RINEX 3 (G+E+C, dual frequency, 2020-06-25; ../shared/data) re-encoded
//! by `rtcm-rs`'s encoder as a receiver sends it: a station 1005 first,
//! each broadcast ephemeris (1019 GPS, 1046 Galileo I/NAV, 1042 BeiDou)
//! once, an hour before its toc, and at each epoch one MSM7 per system
//! (1077, 1097, 1127; DF393 set on all but the last), with the signals of
//! the stream's iono-free pairs (GPS C1C/C2W, Galileo C1C/C5Q, BeiDou
//! C2I/C6I).
//!
//! Checked: the host reader (`raim_recv::rtcm`) reads back every RINEX
//! pseudorange of those signals within half the MSM7 fine range's
//! resolution (2^-30 ms x c, 0.28 mm); and the device's receiver
//! (`raim_nav::rtcm::StreamReceiver`) forms the host's epochs to the bit:
//! times, references, satellites of the three systems, pseudoranges,
//! positions and sigmas.
//!
//!     cargo test --release -p host-tests --test rtcm_esbc -- --nocapture

mod rtcm_common;

use std::collections::BTreeMap;

use raim_core::{Config, System};
use raim_nav::rtcm::{FormError, FormedEpoch, StreamReceiver, LIGHT_MS_M};
use raim_recv::{Decoder, Item};
use rtcm_common::esbc::{esbc_stream, EPOCHS, ESBC_WEEK, FINE_MS, SIGNALS};
use rtcm_common::{frames, host_epochs, MASK_RAD};

/// What the device receiver gave against the host on a stream.
struct Run {
    host: Vec<rtcm_common::HostEpoch>,
    same: usize,
    sats_per_system: BTreeMap<System, usize>,
    counts: raim_nav::rtcm::RtcmCounts,
    times_gps_s: Vec<f64>,
    sats: Vec<Vec<raim_core::SatId>>,
}

/// The device receiver (pivot `pivot_week`) and the host's causal replay
/// (clock at `now_week`) on `bytes`: every epoch the device forms must be
/// the host's, to the bit.
fn device_against_host(bytes: &[u8], pivot_week: i64, now_week: i64) -> Run {
    let model = raim_nav::ranging::StreamSigmas::Snapshot(Config::default().sigma_model);
    let (host, _) = host_epochs(bytes, now_week);
    let mut dev = Box::new(StreamReceiver::<64, 256>::new(pivot_week));
    let mut formed = FormedEpoch::<64> {
        time_gps_s: 0.0,
        reference_m: None,
        sats: heapless::Vec::new(),
        cn0_dbhz: heapless::Vec::new(),
        rates: heapless::Vec::new(),
        rejected: 0,
    };
    let (mut same, mut sats_per_system) = (0, BTreeMap::<System, usize>::new());
    let (mut times_gps_s, mut sats) = (Vec::new(), Vec::new());
    for (n, f) in frames(bytes).into_iter().enumerate() {
        match dev.on_frame(f, &model, MASK_RAD, &mut formed) {
            None => {}
            Some(Err(e @ FormError::NotDated { .. })) => panic!("{e}: ephemerides come first"),
            Some(Err(e)) => panic!("{e}"),
            Some(Ok(())) => {
                let h = host
                    .iter()
                    .find(|h| h.prepared.time_gps_s == formed.time_gps_s)
                    .unwrap_or_else(|| {
                        panic!("device epoch {} s not on the host", formed.time_gps_s)
                    });
                assert_eq!(h.frame, n);
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
                    *sats_per_system.entry(d.id.system).or_default() += 1;
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
        host,
        same,
        sats_per_system,
        counts: dev.counts(),
        times_gps_s,
        sats,
    }
}

/// Verifies: RX-MULTI, RX-STREAM
#[test]
fn esbc_stream_round_trips_and_the_device_forms_the_host_epochs() {
    let (bytes, carried) = esbc_stream(0);
    // Round trip through the host's reader.
    let mut host = raim_recv::rtcm::Rtcm3::new(ESBC_WEEK + 1);
    let mut items = Vec::new();
    host.push(&bytes, &mut items);
    host.finish(&mut items);
    let epochs: Vec<raim_gnss::ObsEpoch> = items
        .into_iter()
        .filter_map(|i| match i {
            Item::Epoch(e) => Some(e),
            _ => None,
        })
        .collect();
    assert_eq!(epochs.len(), EPOCHS, "{:?}", host.counts());
    let tol_m = FINE_MS / 2.0 * LIGHT_MS_M + 1e-6;
    let (mut worst_m, mut values) = (0.0f64, 0usize);
    let mut per_system = BTreeMap::<System, usize>::new();
    for (e, (t, sent)) in epochs.iter().zip(&carried) {
        assert_eq!(e.time_gps_s, *t);
        let n: usize = e.sats.values().map(Vec::len).sum();
        assert_eq!(n, sent.len(), "epoch {t}");
        for (id, code, v) in sent {
            let got = e.sats[id].iter().find(|o| &o.code == code).unwrap().value_m;
            worst_m = worst_m.max((got - v).abs());
            values += 1;
            *per_system.entry(id.system).or_default() += 1;
        }
    }
    println!(
        "ESBC stream: {} bytes, {EPOCHS} epochs, {values} pseudoranges {per_system:?}, worst round trip {worst_m:.2e} m (bound {tol_m:.2e} m)",
        bytes.len()
    );
    assert!(worst_m <= tol_m, "{worst_m} m");
    assert_eq!(per_system.len(), 3);

    // The device receiver against the host's causal replay.
    let run = device_against_host(&bytes, ESBC_WEEK - 52, ESBC_WEEK + 1);
    let (host, same, sats_per_system) = (&run.host, run.same, &run.sats_per_system);
    // The iono-free pairs of the stream codes (GPS L1/L2, Galileo E1/E5a,
    // BeiDou B1I/B3I) on the host's (and so the device's) epochs, for
    // every satellite whose two signals were sent (some of ESBC's BeiDou
    // satellites have no C6I: single frequency).
    let mut codes = BTreeMap::<(System, String), usize>::new();
    for h in host {
        let (_, sent) = carried
            .iter()
            .find(|(t, _)| *t == h.prepared.time_gps_s)
            .unwrap();
        for s in &h.prepared.sats {
            let id = s.obs.id;
            *codes.entry((id.system, s.code.clone())).or_default() += 1;
            let signals = SIGNALS.iter().find(|(sys, _)| *sys == id.system).unwrap().1;
            let both = signals
                .iter()
                .all(|(c, _, _)| sent.iter().any(|(i, code, _)| *i == id && code == c));
            let pair = format!("{}+{}", signals[0].0, signals[1].0);
            assert_eq!(
                both,
                s.code == pair,
                "{id:?} at {} s: {}",
                h.prepared.time_gps_s,
                s.code
            );
        }
    }
    println!("codes used: {codes:?}");
    let c = run.counts;
    println!(
        "device: {same} epochs formed as the host's, satellites {sats_per_system:?}, counts {c:?}"
    );
    assert_eq!(same, EPOCHS);
    assert_eq!(host.len(), EPOCHS);
    assert_eq!(c.undecodable, 0);
    // Every system's satellites reach the epochs.
    for sys in [System::Gps, System::Galileo, System::Beidou] {
        assert!(
            sats_per_system.get(&sys).copied().unwrap_or(0) >= 4 * EPOCHS,
            "{sys:?}: {sats_per_system:?}"
        );
    }
}

/// The generator's stream sent today (in this build's dating window) and
/// in 2040 (GPS week 3160, past the 10-bit GPS rollover of 2038-11-21),
/// into a unit with this build's pivot (raim-server's `PIVOT_WEEK`): every
/// epoch dated in the moved week by GPS (1019), Galileo (1046: GST week
/// modulo 4096) and BeiDou (1042: BDT week modulo 8192) weeks alike, the
/// device and the host forming the same epochs as on the original stream,
/// with the same satellites.
///
/// Verifies: RX-DATING, RX-MULTI
#[test]
fn esbc_stream_sent_today_and_in_2040_is_dated_in_its_week() {
    let (bytes, _) = esbc_stream(0);
    let original = device_against_host(&bytes, ESBC_WEEK - 52, ESBC_WEEK + 1);
    for week in [rtcm_common::in_window_week(), 3160] {
        let delta = week - ESBC_WEEK;
        let (moved, _) = esbc_stream(delta);
        let run = device_against_host(&moved, raim_server::stream::PIVOT_WEEK, week + 1);
        println!(
            "ESBC moved {delta} weeks to week {week}: {} epochs formed alike",
            run.same
        );
        assert_eq!(run.same, EPOCHS);
        let shift_s = delta as f64 * raim_nav::ephemeris::WEEK_S;
        for (a, b) in run.times_gps_s.iter().zip(&original.times_gps_s) {
            assert_eq!(*a, b + shift_s, "week {week}");
        }
        assert_eq!(run.sats, original.sats, "week {week}");
    }
}

/// BeiDou MSM tagged with GPS time, as encoders before RTCM 3.2 wrote them:
/// both readers join them to the epoch whose GPS time of week they carry
/// (not 14 s later), and form the same epochs as from the BDT-tagged
/// stream, to the bit.
///
/// Verifies: RX-MULTI
#[test]
fn beidou_msm_in_gps_time_join_their_epoch() {
    use rtcm_common::esbc::{esbc_stream_with, BeidouTime};
    let (bdt, _) = esbc_stream_with(0, BeidouTime::Bdt, false);
    let (gps, _) = esbc_stream_with(0, BeidouTime::Gps, false);
    assert_ne!(bdt, gps);
    let a = device_against_host(&bdt, ESBC_WEEK - 52, ESBC_WEEK + 1);
    let b = device_against_host(&gps, ESBC_WEEK - 52, ESBC_WEEK + 1);
    assert_eq!(b.same, EPOCHS);
    assert_eq!(b.times_gps_s, a.times_gps_s);
    assert_eq!(b.sats, a.sats);
    assert_eq!(b.sats_per_system, a.sats_per_system);
}

/// Galileo on both navigation messages, as a receiver sends them: each set
/// as I/NAV (1046) and F/NAV (1045). The device stores and selects them as
/// the host does (same toe: the first received), and forms the host's
/// epochs to the bit with every Galileo satellite of the I/NAV-only
/// stream.
///
/// Verifies: RX-MULTI
#[test]
fn galileo_inav_and_fnav_both_sent() {
    use rtcm_common::esbc::{esbc_stream_with, BeidouTime};
    let (inav, _) = esbc_stream_with(0, BeidouTime::Bdt, false);
    let (both, _) = esbc_stream_with(0, BeidouTime::Bdt, true);
    let fnav = frames(&both)
        .iter()
        .filter(|f| {
            rtcm_rs::MessageFrame::new(f)
                .ok()
                .and_then(|m| m.message_number())
                == Some(1045)
        })
        .count();
    let a = device_against_host(&inav, ESBC_WEEK - 52, ESBC_WEEK + 1);
    let b = device_against_host(&both, ESBC_WEEK - 52, ESBC_WEEK + 1);
    println!(
        "{fnav} F/NAV 1045 beside the I/NAV sets; device counts {:?}",
        b.counts
    );
    assert!(fnav > 20, "{fnav}");
    assert_eq!(b.counts.ephemerides, a.counts.ephemerides + fnav as u32);
    assert_eq!(b.same, EPOCHS);
    assert_eq!(b.sats, a.sats);
}
