//! Decoder paths GMSD7 (MSM7 only) does not reach (issue 37, structural
//! coverage): MSM5 and MSM6 layouts, a Galileo MSM, the invalid rough
//! range, an empty cell mask, frames too short for a header, and the
//! errors' messages. Each payload is packed here field by field from RTCM
//! 10403.3 Tables 3.5-78 to 3.5-91, and each range is the table's
//! arithmetic, (DF397 + DF398 / 1024 + fine) ms x c / 1000.

use super::*;
use std::vec::Vec;

/// A frame around `payload` (header and CRC-24Q).
fn frame(payload: &[u8]) -> Vec<u8> {
    let n = payload.len();
    let mut f = std::vec![0xD3, (n >> 8) as u8, n as u8];
    f.extend_from_slice(payload);
    let c = CRC24Q.checksum(&f);
    f.extend_from_slice(&[(c >> 16) as u8, (c >> 8) as u8, c as u8]);
    f
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
            let bit = if b >= 64 {
                i64::from(v < 0)
            } else {
                (v >> b) & 1
            };
            if bit == 1 {
                if let Some(last) = self.0.last_mut() {
                    *last |= 0x80 >> (self.1 % 8);
                }
            }
            self.1 += 1;
        }
        self
    }
}

/// One satellite (number 5), one signal (ID 2), one cell, MSM kind
/// `number % 10` in 4..=7: the header (Table 3.5-78), the satellite data
/// (DF397 `int_ms`, MSM5/7: DF419 4 bits, DF398 512, MSM5/7: DF399 14
/// bits) and the cell (fine range `fine`, phase, lock, half-cycle, C/N0
/// `cnr`, MSM5/7: DF404 15 bits).
fn msm_one(number: u16, int_ms: i64, fine: i64, cnr: i64) -> Vec<u8> {
    let kind = number % 10;
    let extended = kind == 5 || kind == 7;
    let high_res = kind == 6 || kind == 7;
    let mut b = Bits::default();
    b.put(i64::from(number), 12)
        .put(9, 12)
        .put(100_000, 30)
        .put(0, 1);
    b.put(0, 3 + 7 + 2 + 2 + 1 + 3);
    b.put(1 << 59, 64).put(1 << 30, 32).put(1, 1);
    b.put(int_ms, 8);
    if extended {
        b.put(0, 4);
    }
    b.put(512, 10);
    if extended {
        b.put(0, 14);
    }
    if high_res {
        b.put(fine, 20).put(0, 24).put(0, 10).put(0, 1).put(cnr, 10);
    } else {
        b.put(fine, 15).put(0, 22).put(0, 4).put(0, 1).put(cnr, 6);
    }
    if extended {
        b.put(0, 15);
    }
    frame(&b.0)
}

fn signals(f: &[u8]) -> (Msm<'_>, Vec<MsmSignal>) {
    let Ok(Ok(Message::Msm(m))) = Frame::new(f).map(|x| x.message()) else {
        panic!("not an MSM: {:?}", Frame::new(f).map(|x| x.message()));
    };
    let s = m.signals().collect();
    (m, s)
}

/// MSM5 (extended satellite data, standard resolution): DF400 in 2^-24
/// ms, DF403 in dB-Hz.
#[test]
fn msm5_ranges_and_cn0() {
    let f = msm_one(1075, 72, 3000, 41);
    let (m, s) = signals(&f);
    assert_eq!(
        (m.system, m.station_id, m.epoch_ms, m.more),
        (MsmSystem::Gps, 9, 100_000, false)
    );
    let want = (72.0 + 0.5 + 3000.0 / 16_777_216.0) * 299_792.458;
    assert_eq!(s.len(), 1);
    assert_eq!((s[0].sat_id, s[0].band, s[0].attribute), (5, 1, b'C'));
    assert!((s[0].pseudorange_m.unwrap() - want).abs() < 1e-6, "{s:?}");
    assert_eq!(s[0].cnr_dbhz, Some(41.0));
}

/// MSM6 (high resolution, no extended data): DF405 in 2^-29 ms, DF408
/// in 2^-4 dB-Hz.
#[test]
fn msm6_ranges_and_cn0() {
    let f = msm_one(1076, 70, -70_000, 41 * 16 + 8);
    let (_, s) = signals(&f);
    let want = (70.0 + 0.5 - 70_000.0 / 536_870_912.0) * 299_792.458;
    assert!((s[0].pseudorange_m.unwrap() - want).abs() < 1e-6, "{s:?}");
    assert_eq!(s[0].cnr_dbhz, Some(41.5));
}

/// DF397 = 0xFF marks the rough range invalid: no pseudorange, the C/N0
/// still read.
#[test]
fn an_invalid_rough_range_gives_no_pseudorange() {
    let f = msm_one(1074, 0xFF, 10, 30);
    let (_, s) = signals(&f);
    assert_eq!(s[0].pseudorange_m, None);
    assert_eq!(s[0].cnr_dbhz, Some(30.0));
}

/// A Galileo MSM4 (1094): signal ID 2 is E1 C (Table 3.5-99), the
/// satellite number its SVID.
#[test]
fn a_galileo_msm_reads_its_signal_table() {
    let f = msm_one(1094, 80, 0, 40);
    let (m, s) = signals(&f);
    assert_eq!(m.system, MsmSystem::Galileo);
    assert_eq!(m.system.system(), System::Galileo);
    assert_eq!((s[0].sat_id, s[0].band, s[0].attribute), (5, 1, b'C'));
    assert_eq!(s[0].pseudorange_m, Some(80.5 * 299_792.458));
}

/// The systems of the MSM message numbers.
#[test]
fn msm_systems_of_message_numbers() {
    for (n, want, system) in [
        (1077, Some(MsmSystem::Gps), System::Gps),
        (1084, Some(MsmSystem::Glonass), System::Glonass),
        (1097, Some(MsmSystem::Galileo), System::Galileo),
        (1114, Some(MsmSystem::Qzss), System::Qzss),
        (1127, Some(MsmSystem::Beidou), System::Beidou),
    ] {
        assert_eq!(MsmSystem::of_message(n), want);
        assert_eq!(want.unwrap().system(), system);
    }
    assert_eq!(MsmSystem::of_message(1104), None);
    assert_eq!(MsmSystem::of_message(1019), None);
    assert_eq!(
        Msm::new(&[0; 40], 1019).map(|m| m.number),
        Err(DecodeError::NotMsm { message: 1019 })
    );
}

/// An MSM with no satellite has no cell: `CellCount` with the counts.
#[test]
fn an_msm_without_satellites_is_refused() {
    let mut b = Bits::default();
    b.put(1074, 12).put(0, 12 + 30 + 1 + 18);
    b.put(0, 64).put(1 << 30, 32);
    let f = frame(&b.0);
    assert_eq!(
        Frame::new(&f).map(|x| x.message().map(|_| ())),
        Ok(Err(DecodeError::CellCount {
            satellites: 0,
            signals: 1
        }))
    );
}

/// Fewer bytes than a header and CRC: `Incomplete` with the length and
/// the 6 bytes of an empty frame. An empty frame (no payload) has no
/// message number, and reads as an unknown message.
#[test]
fn short_frames_and_an_empty_payload() {
    assert_eq!(
        Frame::new(&[]).map(|f| f.number()),
        Err(FrameError::Incomplete { len: 0, need: 6 })
    );
    assert_eq!(
        Frame::new(&[0xD3, 0]).map(|f| f.number()),
        Err(FrameError::Incomplete { len: 2, need: 6 })
    );
    assert_eq!(
        Frame::new(&[0xD3, 0, 0, 1, 2]).map(|f| f.number()),
        Err(FrameError::Incomplete { len: 5, need: 6 })
    );
    let f = frame(&[]);
    let fr = Frame::new(&f).unwrap();
    assert_eq!(fr.number(), None);
    assert!(fr.payload().is_empty());
    assert_eq!(fr.message().map(|_| ()), Ok(()));
    assert!(matches!(fr.message(), Ok(Message::Other(None))));
    // A message this decoder does not read.
    let f = frame(&[0x3F, 0x10, 0, 0]);
    assert!(matches!(
        Frame::new(&f).unwrap().message(),
        Ok(Message::Other(Some(1009)))
    ));
}

/// The decode errors' messages carry their values.
#[test]
fn decode_errors_say_what_and_where() {
    let cases: [(DecodeError, &str); 5] = [
        (
            DecodeError::Bits(BitsError::PastEnd {
                offset_bits: 70,
                width_bits: 12,
                len_bits: 72,
            }),
            "70",
        ),
        (
            DecodeError::Bits(BitsError::Width { width_bits: 65 }),
            "65 bits outside 1..=64",
        ),
        (
            DecodeError::CellCount {
                satellites: 9,
                signals: 8,
            },
            "MSM with 9 satellites x 8 signals: not 1..=64 cells",
        ),
        (
            DecodeError::SignalId {
                message: 1074,
                signal_id: 1,
            },
            "1074: signal ID 1 not in the signal table",
        ),
        (DecodeError::NotMsm { message: 1019 }, "1019 is not an MSM"),
    ];
    for (e, want) in cases {
        let s = std::format!("{e}");
        assert!(s.contains(want), "{s}");
    }
    let s = std::format!(
        "{}",
        BitsError::PastEnd {
            offset_bits: 70,
            width_bits: 12,
            len_bits: 72
        }
    );
    assert!(
        s.contains("70") && s.contains("12") && s.contains("72"),
        "{s}"
    );
}

/// Widths the typed readers do not take: `sm` below 2 or above 64 bits,
/// `u32` above 32, `u8` above 8.
#[test]
fn field_widths_outside_the_readers_are_refused() {
    let p = [0xFFu8; 16];
    let mut r = BitReader::at(&p, 0);
    assert_eq!(r.sm(1), Err(BitsError::Width { width_bits: 1 }));
    assert_eq!(r.sm(65), Err(BitsError::Width { width_bits: 65 }));
    assert_eq!(r.u32(33), Err(BitsError::Width { width_bits: 33 }));
    assert_eq!(r.u8(9), Err(BitsError::Width { width_bits: 9 }));
    // Nothing was consumed: the next field is the first.
    assert_eq!(r.sm(4), Ok(-7));
}
