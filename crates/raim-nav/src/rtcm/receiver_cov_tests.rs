//! The stream receiver's paths GMSD7 read straight through does not
//! reach (issue 37, structural coverage): a frame that fails its CRC, the
//! leap seconds from an RTCM 1013 (and a count that changes), GLONASS a
//! second off, a leap-second table past its expiry, GLONASS data with no
//! epoch to join, a satellite capacity below the epoch's, and the station
//! position of a 1005. The stream is GMSD7 (2012-10-14, GPS - UTC = 16 s,
//! `/work/shared/data/GMSD7_20121014.rtcm3`; per epoch a 1077, 1087,
//! 1117 and 1127, the last with DF393 = 0), edited frame by frame here;
//! the expectations are the file's own counts and the ICDs' arithmetic.

use std::boxed::Box;
use std::vec::Vec;

use raim_core::{Config, System};

use super::{FormError, FormedEpoch, LeapSeconds, StreamReceiver};
use crate::ranging::StreamSigmas;

/// The GPS week GMSD7 starts in (its first epoch is the end of 1709).
const GMSD7_WEEK: i64 = 1709;
const MASK_RAD: f64 = 10.0 * core::f64::consts::PI / 180.0;

fn gmsd7() -> Vec<u8> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/GMSD7_20121014.rtcm3"
    );
    std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The frames by the RTCM 10403.3 framing alone.
fn frames(bytes: &[u8]) -> Vec<Vec<u8>> {
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

/// The GPS time of week of a GPS MSM, ms (DF004: payload bits 24..54).
fn gps_tow_ms(f: &[u8]) -> i64 {
    let p = &f[3..];
    let mut v = 0i64;
    for bit in 24..54 {
        v = (v << 1) | i64::from((p[bit / 8] >> (7 - bit % 8)) & 1);
    }
    v
}

/// Fields packed most significant bit first.
#[derive(Default)]
struct Bits(Vec<u8>, usize);

impl Bits {
    fn put(&mut self, v: i64, width: u32) -> &mut Self {
        for b in (0..width).rev() {
            if self.1.is_multiple_of(8) {
                self.0.push(0);
            }
            if (v >> b) & 1 == 1 {
                if let Some(last) = self.0.last_mut() {
                    *last |= 0x80 >> (self.1 % 8);
                }
            }
            self.1 += 1;
        }
        self
    }
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

/// RTCM 1013 (§3.5.5): DF002, DF003, DF051 MJD, DF052, DF053 = 0, DF054.
fn msg1013(leap_s: i64) -> Vec<u8> {
    let mut b = Bits::default();
    b.put(1013, 12)
        .put(0, 12)
        .put(56_214, 16)
        .put(0, 17)
        .put(0, 5)
        .put(leap_s, 8);
    frame(&b.0)
}

fn empty() -> Box<FormedEpoch<64>> {
    Box::new(FormedEpoch {
        time_gps_s: 0.0,
        reference_m: None,
        sats: heapless::Vec::new(),
        cn0_dbhz: heapless::Vec::new(),
        rates: heapless::Vec::new(),
        rejected: 0,
    })
}

/// What `rx` makes of `frames`: each closed epoch's result and its
/// GLONASS satellites.
fn feed<const N: usize>(
    rx: &mut StreamReceiver<N, 256>,
    frames: &[Vec<u8>],
) -> Vec<(Result<(), FormError>, usize)> {
    let sigmas = StreamSigmas::Snapshot(Config::default().sigma_model);
    let mut out = Box::new(FormedEpoch::<N> {
        time_gps_s: 0.0,
        reference_m: None,
        sats: heapless::Vec::new(),
        cn0_dbhz: heapless::Vec::new(),
        rates: heapless::Vec::new(),
        rejected: 0,
    });
    let mut got = Vec::new();
    for f in frames {
        if let Some(r) = rx.on_frame(f, &sigmas, MASK_RAD, &mut out) {
            let glo = out
                .sats
                .iter()
                .filter(|s| s.id.system == System::Glonass)
                .count();
            got.push((r, glo));
        }
    }
    got
}

/// The frames of GMSD7's first `epochs` epochs (up to the next 1077).
fn first_epochs(epochs: usize) -> Vec<Vec<u8>> {
    let all = frames(&gmsd7());
    let mut seen = 0;
    let mut out = Vec::new();
    for f in all {
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

/// A frame whose CRC fails is counted undecodable and not as a frame.
#[test]
fn a_frame_that_fails_its_crc_is_counted_undecodable() {
    let mut f = first_epochs(1);
    let n = f[0].len();
    f[0][n - 1] ^= 0x01;
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52));
    feed(&mut rx, &f[..1]);
    let c = rx.counts();
    assert_eq!((c.undecodable, c.frames), (1, 0));
}

/// A 1013 puts its GPS - UTC in force (`Stream`); the same count again
/// keeps the GLONASS sets placed with it, another count drops them (each
/// may be a second, 3.9 km, off); 255 (unknown) changes nothing.
///
/// Verifies: RX-LEAP
#[test]
fn a_1013_sets_the_leap_seconds_and_a_new_count_drops_placed_glonass() {
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52));
    assert_eq!(rx.leap_seconds(), LeapSeconds::NotDated);
    feed(&mut rx, &first_epochs(25));
    assert_eq!(rx.leap_seconds(), LeapSeconds::Table(16));
    let (_, glonass) = rx.ephemerides();
    assert!(glonass > 0);
    feed(&mut rx, &[msg1013(16)]);
    assert_eq!(rx.leap_seconds(), LeapSeconds::Stream(16));
    assert_eq!(rx.ephemerides().1, glonass);
    feed(&mut rx, &[msg1013(17)]);
    assert_eq!(rx.leap_seconds(), LeapSeconds::Stream(17));
    assert_eq!(rx.ephemerides().1, 0);
    feed(&mut rx, &[msg1013(255)]);
    assert_eq!(rx.leap_seconds(), LeapSeconds::Stream(17));
    assert_eq!(rx.utc_offset_s(1e9), 17.0);
    assert_eq!(rx.counts().system_parameters, 3);
}

/// With GPS - UTC a second off (a 1013 of 17 s in 2012), the GLONASS
/// time of day of each epoch does not match its GPS time: the GLONASS
/// data leaves the epoch (counted), the GPS data stays. With the true
/// count (16 s) the same epochs carry GLONASS satellites.
///
/// Verifies: RX-GLONASS-TIME
#[test]
fn glonass_a_second_off_leaves_the_epoch() {
    let epochs = first_epochs(usize::MAX);
    let mut with = std::vec![msg1013(16)];
    with.extend(epochs.iter().cloned());
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52));
    let good = feed(&mut rx, &with);
    assert!(good.iter().any(|(r, g)| r.is_ok() && *g > 0), "{good:?}");
    assert_eq!(rx.counts().glonass_dropped, 0);

    let mut off = std::vec![msg1013(17)];
    off.extend(epochs.iter().cloned());
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52));
    let got = feed(&mut rx, &off);
    let formed = got.iter().filter(|(r, _)| r.is_ok()).count();
    assert!(formed >= 250, "{got:?}");
    assert!(got.iter().all(|(_, g)| *g == 0), "{got:?}");
    // Every formed epoch held a GLONASS MSM (1087) but possibly one.
    let dropped = rx.counts().glonass_dropped as usize;
    assert!(
        dropped + 1 >= formed && dropped <= formed,
        "{dropped} {formed}"
    );
}

/// A unit built 14 years after the recording (pivot 2025) dates GMSD7
/// 1024 weeks late, past the leap-second table's expiry: the 1020s wait
/// (GPS - UTC unknown), every epoch with GLONASS data is refused
/// `LeapSecondsUnknown` with its GPS time of week (the 1077's DF004),
/// and `TableExpired` is reported; a 1013 then places the waiting 1020s.
///
/// Verifies: WIRE-StreamLeapSecondsUnknown, RX-LEAP
#[test]
fn an_expired_table_refuses_glonass_until_a_1013() {
    let epochs = first_epochs(12);
    let tows: Vec<i64> = epochs
        .iter()
        .filter(|f| number(f) == 1077)
        .map(|f| gps_tow_ms(f))
        .collect();
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(2_400 - 52));
    let got = feed(&mut rx, &epochs);
    assert_eq!(got.len(), tows.len());
    for ((r, _), tow) in got.iter().zip(&tows).skip(1) {
        assert_eq!(*r, Err(FormError::LeapSecondsUnknown { tow_ms: *tow }));
    }
    assert_eq!(rx.leap_seconds(), LeapSeconds::TableExpired);
    // GMSD7's first 1020 is in its sixth epoch: it waits.
    assert_eq!(rx.ephemerides().1, 0);
    feed(&mut rx, &[msg1013(16)]);
    assert_eq!(rx.ephemerides().1, 1);
    assert_eq!(rx.leap_seconds(), LeapSeconds::Stream(16));
}

/// GLONASS MSMs with no GPS, Galileo, QZSS or BeiDou MSM to join (the
/// 1077s and 1127s left out): each epoch's GLONASS data waits, and is
/// dropped (counted) when the next epoch's GLONASS time of day arrives;
/// no epoch is formed.
#[test]
fn glonass_with_no_epoch_to_join_is_dropped() {
    let only: Vec<Vec<u8>> = first_epochs(10)
        .into_iter()
        .filter(|f| !matches!(number(f), 1077 | 1127))
        .collect();
    let glonass_msm = only.iter().filter(|f| number(f) == 1087).count();
    assert_eq!(glonass_msm, 10);
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52));
    let got = feed(&mut rx, &only);
    assert!(got.is_empty(), "{got:?}");
    let c = rx.counts();
    assert_eq!(c.epochs, 0);
    assert_eq!(c.glonass_dropped as usize, glonass_msm - 1);
}

/// A receiver of capacity 4 satellites refuses every epoch that has more
/// usable satellites, `TooManySignals` with that capacity; the epochs it
/// forms have at most 4.
#[test]
fn more_satellites_than_the_capacity_refuse_the_epoch() {
    let mut rx = Box::new(StreamReceiver::<4, 256>::new(GMSD7_WEEK - 52));
    let got = feed(&mut rx, &first_epochs(usize::MAX));
    let refused = got
        .iter()
        .filter(|(r, _)| *r == Err(FormError::TooManySignals { capacity: 4 }))
        .count();
    assert!(refused > 0, "{got:?}");
    assert!(
        got.iter().all(|(r, _)| matches!(
            r,
            Ok(())
                | Err(FormError::TooManySignals { capacity: 4 })
                | Err(FormError::NotDated { .. })
        )),
        "{got:?}"
    );
}

/// The station position of a 1005 and a 1006 (§3.5.3: DF025-DF027 in
/// 0.1 mm, two's complement).
#[test]
fn a_1005_gives_the_station_position() {
    let (x, y, z) = (38_921_123_456i64, 3_123_456_789, -50_123_456_789);
    let mut b = Bits::default();
    b.put(1005, 12).put(0, 12).put(0, 6).put(0, 4);
    b.put(x & ((1 << 38) - 1), 38).put(0, 2);
    b.put(y & ((1 << 38) - 1), 38).put(0, 2);
    b.put(z & ((1 << 38) - 1), 38);
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52));
    assert_eq!(rx.station_m(), None);
    feed(&mut rx, &[frame(&b.0)]);
    let p = rx.station_m().unwrap();
    for (got, want) in p.iter().zip([x, y, z]) {
        assert!((got - want as f64 * 1e-4).abs() < 1e-9, "{p:?}");
    }
    // A 1006: the same fields and DF028, the antenna height (16 bits),
    // which the position does not include; another position.
    let mut b = Bits::default();
    b.put(1006, 12).put(0, 12).put(0, 6).put(0, 4);
    b.put(-x & ((1 << 38) - 1), 38).put(0, 2);
    b.put(y & ((1 << 38) - 1), 38).put(0, 2);
    b.put(z & ((1 << 38) - 1), 38).put(15_000, 16);
    feed(&mut rx, &[frame(&b.0)]);
    let p = rx.station_m().unwrap();
    for (got, want) in p.iter().zip([-x, y, z]) {
        assert!((got - want as f64 * 1e-4).abs() < 1e-9, "{p:?}");
    }
}

/// `f` with its DF393 (payload bit 54 of every MSM: after DF002 12,
/// DF003 12 and the 30-bit epoch time) set to `more`, the CRC redone.
fn with_more(f: &[u8], more: bool) -> Vec<u8> {
    let mut payload = f[3..f.len() - 3].to_vec();
    if more {
        payload[6] |= 0x02;
    } else {
        payload[6] &= !0x02;
    }
    frame(&payload)
}

/// An epoch whose last message is one the receiver does not decode (the
/// QZSS 1117 of GMSD7, whose signal IDs are outside Table 3.5-105) still
/// ends with it when its DF393 is 0: with the BeiDou 1127s left out, every
/// epoch closes at its 1117, one per GPS 1077.
#[test]
fn an_undecoded_last_msm_closes_the_epoch() {
    let edited: Vec<Vec<u8>> = first_epochs(8)
        .into_iter()
        .filter(|f| number(f) != 1127)
        .map(|f| {
            if number(&f) == 1117 {
                with_more(&f, false)
            } else {
                f
            }
        })
        .collect();
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52));
    let got = feed(&mut rx, &edited);
    assert_eq!(got.len(), 8);
    assert_eq!(rx.counts().epochs, 8);
}

/// A GLONASS MSM that is the epoch's last (DF393 = 0, the 1117s and
/// 1127s left out) closes the epoch it joined: one per GPS 1077.
#[test]
fn a_last_glonass_msm_closes_the_epoch() {
    let edited: Vec<Vec<u8>> = first_epochs(8)
        .into_iter()
        .filter(|f| !matches!(number(f), 1117 | 1127))
        .map(|f| {
            if number(&f) == 1087 {
                with_more(&f, false)
            } else {
                f
            }
        })
        .collect();
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52));
    let got = feed(&mut rx, &edited);
    assert_eq!(got.len(), 8);
    assert_eq!(rx.counts().epochs, 8);
}

/// A GLONASS MSM that is the epoch's last with no other MSM before it
/// (GLONASS alone): nothing dates it, so it is dropped at once, each one
/// counted.
#[test]
fn a_lone_last_glonass_msm_is_dropped() {
    let edited: Vec<Vec<u8>> = first_epochs(6)
        .into_iter()
        .filter(|f| !matches!(number(f), 1077 | 1117 | 1127))
        .map(|f| {
            if number(&f) == 1087 {
                with_more(&f, false)
            } else {
                f
            }
        })
        .collect();
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52));
    assert!(feed(&mut rx, &edited).is_empty());
    assert_eq!(rx.counts().glonass_dropped, 6);
    assert_eq!(rx.counts().epochs, 0);
}

/// A toc on the other side of a week's end from its toe is placed in
/// the toe's half-week (toe 1 h before the end of week 1709, toc 1 h
/// after it as sent in the new week's seconds, and the reverse).
#[test]
fn toc_is_placed_within_half_a_week_of_toe() {
    let w = 604_800.0;
    assert_eq!(
        super::fields::toc_near_toe(1709, w - 3600.0, 3600.0),
        1710.0 * w + 3600.0
    );
    assert_eq!(
        super::fields::toc_near_toe(1710, 3600.0, w - 3600.0),
        1710.0 * w - 3600.0
    );
    assert_eq!(
        super::fields::toc_near_toe(1710, 7200.0, 3600.0),
        1710.0 * w + 3600.0
    );
}

/// The latest week congruent to the sent one, not after the clock's; a
/// clock before the first rollover gives the week as sent.
#[test]
fn latest_week_from_a_clock() {
    assert_eq!(super::fields::latest_week(685, 1024, 1709), 1709);
    assert_eq!(super::fields::latest_week(686, 1024, 1709), 686);
    assert_eq!(super::fields::latest_week(1000, 1024, 2100), 2024);
    assert_eq!(super::fields::latest_week(1000, 1024, 500), 1000);
}

/// Each closed epoch of `frames`: its time, and its satellites with their
/// corrected pseudoranges, or why it was not formed.
type Formed = Result<(f64, Vec<(raim_core::SatId, f64)>), FormError>;

fn formed(frames: &[Vec<u8>]) -> Vec<Formed> {
    let sigmas = StreamSigmas::Snapshot(Config::default().sigma_model);
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52));
    let mut out = empty();
    let mut got = Vec::new();
    for f in frames {
        if let Some(r) = rx.on_frame(f, &sigmas, MASK_RAD, &mut out) {
            got.push(r.map(|()| {
                (
                    out.time_gps_s,
                    out.sats.iter().map(|s| (s.id, s.pseudorange_m)).collect(),
                )
            }));
        }
    }
    got
}

/// GMSD7's frames regrouped by epoch (each group starts at a 1077; the
/// frames before the first 1077 form their own group).
fn by_epoch(frames: Vec<Vec<u8>>) -> Vec<Vec<Vec<u8>>> {
    let mut out: Vec<Vec<Vec<u8>>> = std::vec![Vec::new()];
    for f in frames {
        if number(&f) == 1077 {
            out.push(Vec::new());
        }
        out.last_mut().unwrap().push(f);
    }
    out
}

/// A stream that never marks an epoch's last message (the 1127s, the
/// only MSMs with DF393 = 0, left out; BeiDou has no ephemeris in GMSD7,
/// so they add no satellite) forms the same epochs, each closed when the
/// next epoch's time arrives: all but the last one. (The first is
/// dated here, as the 1019 that follows its 1077 arrives before it
/// closes.)
#[test]
fn epochs_close_on_a_new_time_when_no_last_message_comes() {
    let all = first_epochs(usize::MAX);
    let want = formed(&all);
    assert!(
        want.iter()
            .filter(|r| r.as_ref().is_ok_and(|(_, s)| !s.is_empty()))
            .count()
            > 20
    );
    // The epochs after whose last message an ephemeris (1019, 1020)
    // comes: held open until the next 1077, they are formed with it.
    let later_ephemeris: Vec<bool> = by_epoch(all.clone())
        .iter()
        .skip(1)
        .map(|g| {
            let last = g.iter().position(|f| number(f) == 1127);
            last.is_some_and(|l| g[l..].iter().any(|f| matches!(number(f), 1019 | 1020)))
        })
        .collect();
    let cut: Vec<Vec<u8>> = all.into_iter().filter(|f| number(f) != 1127).collect();
    let got = formed(&cut);
    assert_eq!(got.len() + 1, want.len());
    assert!(matches!(want[0], Err(FormError::NotDated { .. })));
    assert!(got[0].is_ok());
    let mut compared = 0;
    for i in 1..got.len() {
        let (g, w) = (got[i].as_ref().unwrap(), want[i].as_ref().unwrap());
        assert_eq!(g.0, w.0);
        if !later_ephemeris[i] {
            assert_eq!(g, w, "epoch {i}");
            compared += 1;
        }
    }
    assert!(compared > 200, "{compared}");
}

/// A stream that sends each epoch's GLONASS MSM before its GPS one: the
/// GLONASS data waits for the GPS MSM's time and joins its epoch; the
/// epochs formed are those of GMSD7's own order.
#[test]
fn glonass_before_gps_joins_the_epoch() {
    let all = first_epochs(usize::MAX);
    let want = formed(&all);
    let mut swapped = Vec::new();
    for mut group in by_epoch(all) {
        if let (Some(g), Some(r)) = (
            group.iter().position(|f| number(f) == 1077),
            group.iter().position(|f| number(f) == 1087),
        ) {
            let glonass = group.remove(r);
            group.insert(g, glonass);
        }
        swapped.extend(group);
    }
    let got = formed(&swapped);
    assert_eq!(got, want);
    assert!(got.iter().any(|r| r
        .as_ref()
        .is_ok_and(|(_, s)| s.iter().any(|(id, _)| id.system == System::Glonass))));
}

/// An RTCM 1042 (BeiDou ephemeris, RTCM 10403.3 §3.5.12, fields DF488 to
/// DF515 in the standard's order and widths) of C20 in BDT week `week`,
/// toe and toc `toe_bdt_s` (a multiple of 8 s), TGD1 5 ns, the orbit's
/// fields in whole units of their resolutions.
fn msg1042(week: i64, toe_bdt_s: i64) -> Vec<u8> {
    let mut b = Bits::default();
    b.put(1042, 12).put(20, 6).put(week, 13).put(0, 4);
    b.put(100, 14).put(7, 5).put(toe_bdt_s / 8, 17);
    b.put(0, 11).put(0, 22).put(-1000, 24).put(1, 5);
    b.put(0, 18).put(0, 16).put(0, 32).put(0, 18);
    b.put(8_589_934, 32)
        .put(0, 18)
        .put(2_769_669_324, 32)
        .put(toe_bdt_s / 8, 17);
    b.put(0, 18).put(0, 32).put(0, 18).put(656_083_968, 32);
    b.put(0, 18)
        .put(0, 32)
        .put(0, 24)
        .put(50, 10)
        .put(0, 10)
        .put(0, 1);
    frame(&b.0)
}

/// A BeiDou ephemeris dates the stream as a GPS one does: BDT week 353
/// is GPS week 1709 (BDT week 0 = GPS week 1356, BDS ICD §5.2.3) and BDT
/// is GPS time less 14 s. With GMSD7's first epoch preceded by a 1042
/// instead of its 1019 (toe 604,768 s of BDT week 353; the epoch, 604,784 s
/// of GPS time, is 604,770 s of BDT), that epoch is dated at once: GPS
/// week 1709, 604,784 s.
/// The message's fields decode to their raw values times the standard's
/// resolutions.
#[test]
fn a_beidou_ephemeris_dates_the_stream() {
    use super::decode::{Frame, Message};
    let eph = msg1042(353, 604_768);
    let Ok(Message::Kepler(k)) = Frame::new(&eph).unwrap().message() else {
        panic!("not an ephemeris");
    };
    assert_eq!(
        (k.number, k.system, k.prn, k.week_sent),
        (1042, System::Beidou, 20, 353)
    );
    let f = k.fields;
    assert_eq!((f.toe_s, f.toc_s, f.iod), (604_768.0, 604_768.0, 7));
    assert_eq!(f.idot_sc, 100.0 * 2f64.powi(-43));
    assert_eq!(f.af0, -1000.0 * 2f64.powi(-33));
    assert_eq!(f.e, 8_589_934.0 * 2f64.powi(-33));
    assert_eq!(f.sqrt_a, 2_769_669_324.0 * 2f64.powi(-19));
    assert_eq!(f.i0_sc, 656_083_968.0 * 2f64.powi(-31));
    assert!((f.tgd - 5e-9).abs() < 1e-15, "{}", f.tgd);

    let mut frames = std::vec![eph];
    frames.extend(first_epochs(1).into_iter().filter(|f| number(f) != 1019));
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52));
    let sigmas = StreamSigmas::Snapshot(Config::default().sigma_model);
    let mut out = empty();
    let mut got = Vec::new();
    for f in &frames {
        if let Some(r) = rx.on_frame(f, &sigmas, MASK_RAD, &mut out) {
            got.push((r, out.time_gps_s));
        }
    }
    assert_eq!(got, [(Ok(()), 1709.0 * 604_800.0 + 604_784.0)]);
    assert_eq!(rx.ephemerides().0, 1);
}

/// An RTCM 1045 (Galileo F/NAV, `inav` false) or 1046 (I/NAV) of E11 in
/// GST week `week`, toe and toc `toe_s` (a multiple of 60 s): RTCM
/// 10403.3 §3.5.10-11, DF252 to DF317 in the standard's order and widths;
/// BGD(E1,E5a) 2^-32 x 20 s, BGD(E1,E5b) 2^-32 x 30 s; F/NAV E5a health
/// 3, validity 1; I/NAV E5b health 1, validity 0, E1-B health 2,
/// validity 1.
fn msg1045_1046(inav: bool, week: i64, toe_s: i64) -> Vec<u8> {
    let mut b = Bits::default();
    b.put(if inav { 1046 } else { 1045 }, 12)
        .put(11, 6)
        .put(week, 12)
        .put(42, 10)
        .put(0, 8);
    b.put(-100, 14)
        .put(toe_s / 60, 14)
        .put(0, 6)
        .put(0, 21)
        .put(5000, 31);
    b.put(0, 16).put(0, 16).put(0, 32).put(0, 16);
    b.put(1_000_000, 32)
        .put(0, 16)
        .put(2_852_038_656, 32)
        .put(toe_s / 60, 14);
    b.put(0, 16).put(0, 32).put(0, 16).put(600_000_000, 32);
    b.put(0, 16).put(0, 32).put(0, 24).put(20, 10);
    if inav {
        b.put(30, 10)
            .put(1, 2)
            .put(0, 1)
            .put(2, 2)
            .put(1, 1)
            .put(0, 2);
    } else {
        b.put(3, 2).put(1, 1).put(0, 7);
    }
    frame(&b.0)
}

/// An RTCM 1044 (QZSS, §3.5.13) of J04 (satellite ID 4) in GPS week
/// `week` (mod 1024), toe and toc `toe_s` (a multiple of 16 s), TGD
/// 2^-31 x 4 s, health 0.
fn msg1044(week: i64, toe_s: i64) -> Vec<u8> {
    let mut b = Bits::default();
    b.put(1044, 12)
        .put(4, 4)
        .put(toe_s / 16, 16)
        .put(0, 8)
        .put(0, 16)
        .put(-300, 22);
    b.put(9, 8).put(0, 16).put(0, 16).put(0, 32).put(0, 16);
    b.put(3_000_000, 32)
        .put(0, 16)
        .put(3_346_000_000, 32)
        .put(toe_s / 16, 16);
    b.put(0, 16).put(0, 32).put(0, 16).put(700_000_000, 32);
    b.put(0, 16).put(0, 32).put(0, 24).put(50, 14);
    b.put(0, 2)
        .put(week, 10)
        .put(0, 4)
        .put(0, 6)
        .put(4, 8)
        .put(0, 10)
        .put(0, 1);
    frame(&b.0)
}

/// The first GMSD7 epoch, preceded by `eph` instead of its 1019: the
/// results the receiver hands over, with their GPS times.
fn dated_by(eph: &[u8]) -> Vec<(Result<(), FormError>, f64)> {
    let mut frames = std::vec![eph.to_vec()];
    frames.extend(first_epochs(1).into_iter().filter(|f| number(f) != 1019));
    let mut rx = Box::new(StreamReceiver::<64, 256>::new(GMSD7_WEEK - 52));
    let sigmas = StreamSigmas::Snapshot(Config::default().sigma_model);
    let mut out = empty();
    let mut got = Vec::new();
    for f in &frames {
        if let Some(r) = rx.on_frame(f, &sigmas, MASK_RAD, &mut out) {
            got.push((r, out.time_gps_s));
        }
    }
    got
}

/// Galileo F/NAV and I/NAV ephemerides: the fields decode to their raw
/// values times the standard's resolutions; F/NAV's group delay is
/// BGD(E1,E5a), I/NAV's BGD(E1,E5b) (with E1/E5a's kept); the health
/// words pack each signal's health and validity bits. Either dates the
/// stream: GST week 685 is GPS week 1709 (GST week 0 = GPS week 1024;
/// GST is aligned with GPS time), toe 604,740 s, 44 s before GMSD7's
/// first epoch, which is then dated at GPS week 1709, 604,784 s.
#[test]
fn galileo_ephemerides_decode_and_date_the_stream() {
    use super::decode::{Frame, Message};
    for inav in [false, true] {
        let eph = msg1045_1046(inav, 685, 604_740);
        let Ok(Message::Kepler(k)) = Frame::new(&eph).unwrap().message() else {
            panic!("not an ephemeris");
        };
        let number = if inav { 1046 } else { 1045 };
        assert_eq!(
            (k.number, k.system, k.prn, k.week_sent),
            (number, System::Galileo, 11, 685)
        );
        let f = k.fields;
        assert_eq!((f.toe_s, f.toc_s, f.iod), (604_740.0, 604_740.0, 42));
        assert_eq!(f.idot_sc, -100.0 * 2f64.powi(-43));
        assert_eq!(f.af0, 5000.0 * 2f64.powi(-34));
        assert_eq!(f.e, 1_000_000.0 * 2f64.powi(-33));
        assert_eq!(f.sqrt_a, 2_852_038_656.0 * 2f64.powi(-19));
        assert_eq!(f.i0_sc, 600_000_000.0 * 2f64.powi(-31));
        let (bgd5a, bgd5b) = (20.0 * 2f64.powi(-32), 30.0 * 2f64.powi(-32));
        if inav {
            assert_eq!((f.tgd, f.tgd2), (bgd5b, bgd5a));
            assert_eq!(f.health, 2 | 1 << 2 | 1 << 3);
        } else {
            assert_eq!((f.tgd, f.tgd2), (bgd5a, bgd5a));
            assert_eq!(f.health, 3 | 1 << 2);
        }
        assert_eq!(dated_by(&eph), [(Ok(()), 1709.0 * 604_800.0 + 604_784.0)]);
    }
}

/// A QZSS ephemeris (1044): the fields decode to their raw values times
/// the standard's resolutions, and the 10-bit GPS week (685 = 1709 mod
/// 1024) dates the stream: toe 604,784 s, GMSD7's first epoch, dated at
/// GPS week 1709.
#[test]
fn a_qzss_ephemeris_decodes_and_dates_the_stream() {
    use super::decode::{Frame, Message};
    let eph = msg1044(685, 604_784);
    let Ok(Message::Kepler(k)) = Frame::new(&eph).unwrap().message() else {
        panic!("not an ephemeris");
    };
    assert_eq!(
        (k.number, k.system, k.prn, k.week_sent),
        (1044, System::Qzss, 4, 685)
    );
    let f = k.fields;
    assert_eq!((f.toe_s, f.toc_s, f.iod), (604_784.0, 604_784.0, 9));
    assert_eq!(f.af0, -300.0 * 2f64.powi(-31));
    assert_eq!(f.e, 3_000_000.0 * 2f64.powi(-33));
    assert_eq!(f.sqrt_a, 3_346_000_000.0 * 2f64.powi(-19));
    assert_eq!(f.i0_sc, 700_000_000.0 * 2f64.powi(-31));
    assert_eq!(f.idot_sc, 50.0 * 2f64.powi(-43));
    assert_eq!(f.tgd, 4.0 * 2f64.powi(-31));
    assert_eq!(dated_by(&eph), [(Ok(()), 1709.0 * 604_800.0 + 604_784.0)]);
}
