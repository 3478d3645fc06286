//! The stream receiver's paths the other tests do not reach (issue 37,
//! structural coverage, second pass), through its public API on GMSD7
//! (2012-10-14, `/work/shared/data/GMSD7_20121014.rtcm3`) edited frame by
//! frame: a Keplerian ephemeris too long to keep, a GLONASS ephemeris out
//! of the ICD's range, a last MSM of a system the receiver does not read
//! with no epoch open, and more 1020s waiting for the stream's date than
//! the receiver holds.

use std::boxed::Box;
use std::vec::Vec;

use raim_core::Config;

use super::{FormError, FormedEpoch, StreamReceiver};
use crate::ranging::StreamSigmas;

/// The GPS week GMSD7 starts in (its first epoch is the end of 1709); the
/// receiver's pivot a year earlier places it.
const GMSD7_WEEK: i64 = 1709;
const MASK_RAD: f64 = 10.0 * core::f64::consts::PI / 180.0;

/// GMSD7's frames by the RTCM 10403.3 framing alone.
fn gmsd7_frames() -> Vec<Vec<u8>> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/GMSD7_20121014.rtcm3"
    );
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut out = Vec::new();
    let mut i = 0;
    while i + 3 <= bytes.len() {
        if bytes[i] != 0xD3 {
            i += 1;
            continue;
        }
        let len = (usize::from(bytes[i + 1] & 0x03) << 8) | usize::from(bytes[i + 2]);
        let end = i + 6 + len;
        if end > bytes.len() {
            break;
        }
        out.push(bytes[i..end].to_vec());
        i = end;
    }
    out
}

/// DF002 of a frame.
fn number(f: &[u8]) -> u16 {
    (u16::from(f[3]) << 4) | (u16::from(f[4]) >> 4)
}

/// The frames of GMSD7's first `epochs` epochs (up to the next 1077).
fn first_epochs(epochs: usize) -> Vec<Vec<u8>> {
    let mut seen = 0;
    let mut out = Vec::new();
    for f in gmsd7_frames() {
        if number(&f) == 1077 {
            if seen == epochs {
                break;
            }
            seen += 1;
        }
        out.push(f);
    }
    out
}

/// A frame around `payload`: header and CRC-24Q (polynomial 0x864CFB,
/// initial value 0; written out here, not the decoder's).
fn frame(payload: &[u8]) -> Vec<u8> {
    let n = payload.len();
    let mut f = std::vec![0xD3, (n >> 8) as u8, n as u8];
    f.extend_from_slice(payload);
    let mut c = 0u32;
    for &b in &f {
        c ^= u32::from(b) << 16;
        for _ in 0..8 {
            c <<= 1;
            if c & 0x0100_0000 != 0 {
                c ^= 0x0186_4CFB;
            }
        }
    }
    f.extend_from_slice(&[(c >> 16) as u8, (c >> 8) as u8, c as u8]);
    f
}

/// The payload of a frame.
fn payload(f: &[u8]) -> &[u8] {
    &f[3..f.len() - 3]
}

/// Each closed epoch's outcome after `frames`.
fn feed(rx: &mut StreamReceiver<64, 256>, frames: &[Vec<u8>]) -> Vec<Result<(), FormError>> {
    let sigmas = StreamSigmas::Snapshot(Config::default().sigma_model);
    let mut out = Box::new(FormedEpoch::<64>::new());
    frames
        .iter()
        .filter_map(|f| rx.on_frame(f, &sigmas, MASK_RAD, &mut out))
        .collect()
}

fn receiver() -> Box<StreamReceiver<64, 256>> {
    Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52))
}

/// A 1019 whose payload is longer than the store keeps (64 bytes, the
/// longest Keplerian message's; a 1019 has 61): GMSD7's first 1019 with
/// eight zero bytes after its 488 bits decodes to the same set, which is
/// counted not kept; the store holds one set fewer than from the stream
/// as sent.
#[test]
fn a_keplerian_message_longer_than_the_store_keeps_is_counted() {
    let frames = first_epochs(25);
    let at = frames.iter().position(|f| number(f) == 1019).unwrap();
    let mut long = payload(&frames[at]).to_vec();
    assert_eq!(long.len(), 61);
    long.extend_from_slice(&[0; 8]);
    let mut edited = frames.clone();
    edited[at] = frame(&long);

    let mut plain = receiver();
    feed(&mut plain, &frames);
    let mut rx = receiver();
    feed(&mut rx, &edited);
    assert_eq!(plain.counts().ephemerides_not_kept, 0);
    assert_eq!(rx.counts().ephemerides_not_kept, 1);
    assert_eq!(rx.counts().ephemerides, plain.counts().ephemerides);
    assert_eq!(rx.ephemerides().0 + 1, plain.ephemerides().0);
}

/// A 1020 whose slot (DF038, payload bits 12..18) is 0, outside the ICD's
/// 1..=27 (slot 0 is not a satellite), is counted bad once the stream is
/// dated and placed; the same message with its slot is kept.
#[test]
fn a_glonass_ephemeris_out_of_range_is_counted_bad() {
    let frames = first_epochs(25);
    let g = frames.iter().find(|f| number(f) == 1020).unwrap();
    let mut p = payload(g).to_vec();
    // Bits 12..18: the low four bits of byte 1, the top two of byte 2.
    p[1] &= 0xF0;
    p[2] &= 0x3F;
    let mut rx = receiver();
    feed(&mut rx, &frames);
    let before = rx.counts().glonass_bad;
    feed(&mut rx, &[frame(&p)]);
    assert_eq!(rx.counts().glonass_bad, before + 1);
    feed(&mut rx, std::slice::from_ref(g));
    assert_eq!(rx.counts().glonass_bad, before + 1);
}

/// An SBAS MSM7 (1107, a system the receiver does not read) whose
/// multiple-message bit (DF393, payload bit 54) is 0 ends the open epoch;
/// with none open it ends nothing: the stream's epochs after it are
/// formed as without it.
#[test]
fn a_last_msm_of_another_system_with_no_epoch_open_ends_nothing() {
    let mut sbas = std::vec![0u8; 20];
    sbas[0] = (1107u16 >> 4) as u8;
    sbas[1] = ((1107u16 & 0x0F) << 4) as u8;
    let frames = first_epochs(25);
    let mut with = std::vec![frame(&sbas)];
    with.extend_from_slice(&frames);
    let mut plain = receiver();
    let want = feed(&mut plain, &frames);
    let mut rx = receiver();
    let got = feed(&mut rx, &with);
    assert_eq!(got, want);
    assert_eq!(rx.counts().epochs, plain.counts().epochs);
    assert_eq!(rx.counts().ignored, plain.counts().ignored + 1);
}

/// 1020s that arrive before the stream can be dated wait, at most 32 of
/// them (`PENDING_GLONASS`): GMSD7's 16 sent three times over (48), the
/// 16 oldest give way, and once dated the receiver holds what it holds
/// after the 32 latest alone.
#[test]
fn waiting_glonass_ephemerides_keep_the_latest() {
    let once: Vec<Vec<u8>> = gmsd7_frames()
        .into_iter()
        .filter(|f| number(f) == 1020)
        .collect();
    assert_eq!(once.len(), 16);
    let glo: Vec<Vec<u8>> = once.iter().cycle().take(48).cloned().collect();
    let epochs = first_epochs(25);
    let mut rx = receiver();
    feed(&mut rx, &glo);
    assert_eq!(rx.ephemerides(), (0, 0));
    feed(&mut rx, &epochs);
    let mut latest = receiver();
    feed(&mut latest, &glo[16..]);
    feed(&mut latest, &epochs);
    assert_eq!(rx.ephemerides(), latest.ephemerides());
    assert!(rx.ephemerides().1 > 0);
}

/// The times of the epochs `frames` close, formed or not.
fn epoch_times(rx: &mut StreamReceiver<64, 256>, frames: &[Vec<u8>]) -> Vec<f64> {
    let sigmas = StreamSigmas::Snapshot(Config::default().sigma_model);
    let mut out = Box::new(FormedEpoch::<64>::new());
    frames
        .iter()
        .filter_map(|f| {
            rx.on_frame(f, &sigmas, MASK_RAD, &mut out)
                .map(|_| out.time_gps_s)
        })
        .collect()
}

/// `payload` with the `width`-bit field at bit `at` set to `v`.
fn with_field(payload: &[u8], at: usize, width: usize, v: u64) -> Vec<u8> {
    let mut q = payload.to_vec();
    for (i, k) in (at..at + width).enumerate() {
        let bit = ((v >> (width - 1 - i)) & 1) as u8;
        q[k / 8] = (q[k / 8] & !(0x80 >> (k % 8))) | (bit << (7 - k % 8));
    }
    q
}

/// The stream is dated by its first Keplerian ephemeris: of the three
/// weeks around the ephemeris' own, the one that puts the latest epoch
/// nearest its toe. GMSD7's first 1019 (week 1709, toe 604,784 s) comes
/// with the epoch of that time, the last seconds of week 1709; the same
/// set with toc and toe (DF081 at payload bit 56, DF093 at bit 288, 16
/// bits of 16 s) at 1,008 s of its week puts those epochs 16 s before
/// it, at the end of the week before: every dated epoch comes exactly
/// one week (604,800 s) earlier.
#[test]
fn the_stream_is_dated_to_the_week_nearest_the_first_toe() {
    let frames = first_epochs(25);
    let at = frames.iter().position(|f| number(f) == 1019).unwrap();
    let early = 1_008 / 16;
    let q = with_field(
        &with_field(payload(&frames[at]), 56, 16, early),
        288,
        16,
        early,
    );
    let mut edited = frames.clone();
    edited[at] = frame(&q);
    let want = epoch_times(&mut receiver(), &frames);
    let got = epoch_times(&mut receiver(), &edited);
    assert_eq!(got.len(), want.len());
    let dated: Vec<(f64, f64)> = got
        .iter()
        .zip(&want)
        // An epoch before the dating has its time of week only.
        .filter(|(_, w)| **w >= 604_800.0)
        .map(|(g, w)| (*g, *w))
        .collect();
    assert!(dated.len() > 10, "{want:?}");
    for (g, w) in dated {
        assert_eq!(w - g, 604_800.0);
    }
}

/// RTCM 1013 (RTCM 10403.3 §3.5.5): DF002, DF003 0, DF051 MJD 56,214
/// (2012-10-14), DF052 0, DF053 no announcements, DF054 `leap_s`.
fn msg1013(leap_s: u64) -> Vec<u8> {
    let fields: [(u64, usize); 6] = [
        (1013, 12),
        (0, 12),
        (56_214, 16),
        (0, 17),
        (0, 5),
        (leap_s, 8),
    ];
    let mut p = std::vec![0u8; 9];
    let mut at = 0;
    for (v, w) in fields {
        p = with_field(&p, at, w, v);
        at += w;
    }
    frame(&p)
}

/// 1020s waiting for the stream's date wait on when the date is past the
/// leap-second table (a pivot 1,024 weeks late dates GMSD7 in 2032): the
/// receiver holds no GLONASS set until an RTCM 1013 gives GPS - UTC, and
/// then as many as a stream dated in 2012 by the table (16 s, the same
/// count) holds.
///
/// Verifies: RX-LEAP
#[test]
fn waiting_glonass_ephemerides_wait_for_the_leap_seconds() {
    let once: Vec<Vec<u8>> = gmsd7_frames()
        .into_iter()
        .filter(|f| number(f) == 1020)
        .collect();
    let epochs: Vec<Vec<u8>> = first_epochs(25)
        .into_iter()
        .filter(|f| number(f) != 1020)
        .collect();
    let mut late = Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52 + 1024));
    feed(&mut late, &once);
    feed(&mut late, &epochs);
    assert_eq!(late.ephemerides().1, 0);
    feed(&mut late, &[msg1013(16)]);
    let mut table = receiver();
    feed(&mut table, &once);
    feed(&mut table, &epochs);
    assert!(table.ephemerides().1 > 0);
    assert_eq!(late.ephemerides().1, table.ephemerides().1);
}

/// A frame that closes two epochs: epoch 10 left open (its last MSM,
/// the 1127, removed) and followed directly by epoch 11's last MSM (its
/// 1127, DF393 = 0, at a new time). The new time closes epoch 10, and the
/// message's own DF393 closes epoch 11 in the same frame: epoch 10 is
/// handed over, epoch 11 (one BeiDou MSM) is counted closed and dropped.
#[test]
fn a_frame_that_closes_two_epochs_hands_over_the_first() {
    let epochs: Vec<Vec<Vec<u8>>> = {
        let mut out: Vec<Vec<Vec<u8>>> = Vec::new();
        for f in first_epochs(12) {
            if number(&f) == 1077 || out.is_empty() {
                out.push(Vec::new());
            }
            out.last_mut().unwrap().push(f);
        }
        out
    };
    let mut frames: Vec<Vec<u8>> = epochs[..10].concat();
    frames.extend(epochs[10].iter().filter(|f| number(f) != 1127).cloned());
    let last_of_11 = epochs[11].iter().find(|f| number(f) == 1127).unwrap();
    let mut rx = receiver();
    let before = feed(&mut rx, &frames).len();
    let closed = rx.counts().epochs;
    let got = feed(&mut rx, std::slice::from_ref(last_of_11));
    assert_eq!(rx.counts().epochs, closed + 2);
    assert_eq!(got.len(), 1);
    assert!(before >= 9, "{before}");
}

/// The closed epochs' outcomes, times, satellites and satellites
/// rejected.
type Outcome = (Result<(), FormError>, f64, usize, u32);

fn outcomes(rx: &mut StreamReceiver<64, 256>, frames: &[Vec<u8>]) -> Vec<Outcome> {
    let sigmas = StreamSigmas::Snapshot(Config::default().sigma_model);
    let mut out = Box::new(FormedEpoch::<64>::new());
    frames
        .iter()
        .filter_map(|f| {
            rx.on_frame(f, &sigmas, MASK_RAD, &mut out)
                .map(|r| (r, out.time_gps_s, out.sats.len(), out.rejected))
        })
        .collect()
}

/// GMSD7's BeiDou MSMs (1127) carry the epoch's GPS time of week in
/// DF427; a receiver that sends BDT there (GPS - 14 s, RTCM 10403.3
/// DF427) gives the same epochs: each BeiDou MSM joins its epoch either
/// way (DF427 + 14 s is the epoch's time): the 25 epochs close at the
/// same times with the same satellites.
#[test]
fn beidou_msms_in_bdt_join_their_epoch() {
    let frames = first_epochs(25);
    let bdt: Vec<Vec<u8>> = frames
        .iter()
        .map(|f| {
            if number(f) != 1127 {
                return f.clone();
            }
            let p = payload(f);
            let mut tow = 0u64;
            for k in 24..54 {
                tow = (tow << 1) | u64::from((p[k / 8] >> (7 - k % 8)) & 1);
            }
            let bdt_ms = (tow + 604_800_000 - 14_000) % 604_800_000;
            frame(&with_field(p, 24, 30, bdt_ms))
        })
        .collect();
    assert_ne!(bdt, frames);
    let want = outcomes(&mut receiver(), &frames);
    let got = outcomes(&mut receiver(), &bdt);
    // A BeiDou MSM placed at another time would close its epoch early and
    // open one of its own: more epochs, each with fewer signals.
    assert_eq!(got, want);
    assert_eq!(want.len(), 25, "{want:?}");
    // Every dated epoch (all but the first, before the first ephemeris)
    // holds its satellites, taken or rejected.
    assert!(
        want.iter().skip(1).all(|o| o.2 + o.3 as usize > 0),
        "{want:?}"
    );
}
