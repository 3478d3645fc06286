//! u-blox UBX to observation epochs and GPS LNAV ephemerides.
//!
//! Frames (sync 0xB5 0x62, class, id, 16-bit length, payload, 8-bit
//! Fletcher checksum over class..payload; u-blox protocol specification
//! §"UBX Protocol") are found and checked here, so that skipped bytes and
//! bad checksums can be counted; the `ublox` crate decodes the messages it
//! knows from a checked frame:
//! - RXM-RAWX (0x02 0x15, M8/F9): pseudoranges of every system, one RINEX 3
//!   code per signal (gnssId/sigId, the specification's signal table), used
//!   when the tracking status says the pseudorange is valid (trkStat bit 0).
//! - RXM-SFRBX (0x02 0x13): GPS and QZSS LNAV subframes (30-bit words, the
//!   parity bits dropped) to [`crate::lnav`]; other systems' navigation
//!   data are counted, not decoded.
//!
//! The legacy messages of u-blox 4/5/6 (Antaris 4 / u-blox 5 protocol
//! specifications, "RXM-RAW" and "RXM-SFRB"), which the crate lacks, are
//! decoded here from their published layouts:
//! - RXM-RAW (0x02 0x10): iTOW (I4, ms), week (I2), numSV (U1), reserved
//!   (U1), then per satellite 24 bytes: cpMes (R8, cycles), prMes (R8, m),
//!   doMes (R4, Hz), sv (U1), mesQI (I1), cno (I1, dBHz), lli (U1). A
//!   pseudorange is used when mesQI >= 4 ("PR+DO OK").
//! - RXM-SFRB (0x02 0x11): chn (U1), svid (U1), ten words (U4) of 24 data
//!   bits each, parity removed. GPS PRNs 1-32; SBAS (120-158) is counted.

use raim_core::{SatId, System};
use raim_gnss::ephemeris::WEEK_S;
use raim_gnss::rinex_io::{CodeObs, SignalRate};
use raim_gnss::ObsEpoch;

use crate::lnav::{Decoded, LnavCollector, Subframe};
use crate::{Counts, Decoder, Item};

/// Largest payload accepted (RXM-RAWX with 255 measurements: 16 + 255 x 32).
const MAX_PAYLOAD: usize = 8176;
/// Longest NMEA sentence looked for between frames (82 characters by
/// NMEA 0183, with room for proprietary ones).
const NMEA_MAX: usize = 256;
/// Lowest RXM-RAW measurement quality with a valid pseudorange.
const MIN_MES_QI: i8 = 4;

/// The 8-bit Fletcher checksum of a UBX frame's class..payload bytes.
pub fn checksum(bytes: &[u8]) -> (u8, u8) {
    let (mut a, mut b) = (0u8, 0u8);
    for &x in bytes {
        a = a.wrapping_add(x);
        b = b.wrapping_add(a);
    }
    (a, b)
}

/// Wrap a payload in a UBX frame (for tests and for the docs' examples).
pub fn frame(class: u8, id: u8, payload: &[u8]) -> Vec<u8> {
    let len = u16::try_from(payload.len()).unwrap_or(u16::MAX);
    let mut f = vec![0xB5, 0x62, class, id];
    f.extend_from_slice(&len.to_le_bytes());
    f.extend_from_slice(payload);
    let (a, b) = checksum(f.get(2..).unwrap_or(&[]));
    f.extend_from_slice(&[a, b]);
    f
}

/// RINEX 3 code of a RXM-RAWX signal (gnssId, sigId), or None for a
/// signal this crate does not name.
pub fn rawx_code(gnss_id: u8, sig_id: u8) -> Option<(System, &'static str)> {
    Some(match (gnss_id, sig_id) {
        (0, 0) => (System::Gps, "C1C"),
        (0, 3) => (System::Gps, "C2L"),
        (0, 4) => (System::Gps, "C2S"),
        (0, 6) => (System::Gps, "C5I"),
        (0, 7) => (System::Gps, "C5Q"),
        (2, 0) => (System::Galileo, "C1C"),
        (2, 1) => (System::Galileo, "C1B"),
        (2, 3) => (System::Galileo, "C5I"),
        (2, 4) => (System::Galileo, "C5Q"),
        (2, 5) => (System::Galileo, "C7I"),
        (2, 6) => (System::Galileo, "C7Q"),
        (3, 0) | (3, 1) => (System::Beidou, "C2I"),
        (3, 2) | (3, 3) => (System::Beidou, "C7I"),
        (3, 5) => (System::Beidou, "C1P"),
        (3, 7) => (System::Beidou, "C5P"),
        (5, 0) => (System::Qzss, "C1C"),
        (5, 4) => (System::Qzss, "C2S"),
        (5, 5) => (System::Qzss, "C2L"),
        (6, 0) => (System::Glonass, "C1C"),
        (6, 2) => (System::Glonass, "C2C"),
        _ => return None,
    })
}

/// The UBX decoder (see the module documentation).
#[derive(Debug, Default)]
pub struct Ubx {
    buf: Vec<u8>,
    counts: Counts,
    lnav: LnavCollector,
    /// GPS week of the latest measurement epoch.
    week: Option<i64>,
}

fn le<const N: usize>(p: &[u8], at: usize) -> Option<[u8; N]> {
    p.get(at..at + N)?.try_into().ok()
}

impl Ubx {
    fn frames(&mut self, out: &mut Vec<Item>, at_end: bool) {
        let buf = std::mem::take(&mut self.buf);
        let mut i = 0;
        while i < buf.len() {
            let b = buf.get(i..).unwrap_or(&[]);
            if b.first() == Some(&b'$') {
                // An NMEA sentence between the frames (u-blox ports mix
                // both): skipped whole and counted as such.
                match b.iter().take(NMEA_MAX).position(|&x| x == b'\n') {
                    Some(end) => {
                        *self
                            .counts
                            .ignored
                            .entry("NMEA sentence".into())
                            .or_default() += 1;
                        i += end + 1;
                        continue;
                    }
                    None if b.len() < NMEA_MAX && !at_end => break,
                    None => {}
                }
            }
            if b.first() != Some(&0xB5) || b.get(1).is_some_and(|&x| x != 0x62) {
                self.counts.garbage_bytes += 1;
                i += 1;
                continue;
            }
            let Some(len) = le::<2>(b, 4).map(|l| usize::from(u16::from_le_bytes(l))) else {
                break;
            };
            if len > MAX_PAYLOAD {
                self.counts.garbage_bytes += 1;
                i += 1;
                continue;
            }
            let Some(whole) = b.get(..len + 8) else {
                break;
            };
            let (a, c) = checksum(whole.get(2..6 + len).unwrap_or(&[]));
            if whole.get(6 + len..) != Some(&[a, c][..]) {
                self.counts.bad_checksum += 1;
                self.counts.garbage_bytes += 1;
                i += 1;
                continue;
            }
            self.counts.frames += 1;
            let (class, id) = (whole[2], whole[3]);
            let payload = whole.get(6..6 + len).unwrap_or(&[]);
            self.message(class, id, payload, whole, out);
            i += len + 8;
        }
        let rest = buf.get(i..).unwrap_or(&[]);
        if at_end {
            self.counts.truncated_tail_bytes += rest.len() as u64;
        } else {
            self.buf = rest.to_vec();
        }
    }

    fn message(&mut self, class: u8, id: u8, payload: &[u8], whole: &[u8], out: &mut Vec<Item>) {
        let ok = match (class, id) {
            (0x02, 0x10) => self.rxm_raw(payload, out),
            (0x02, 0x11) => self.rxm_sfrb(payload, out),
            (0x02, 0x15) => self.rxm_rawx(whole, out),
            (0x02, 0x13) => self.rxm_sfrbx(whole, out),
            _ => {
                *self
                    .counts
                    .ignored
                    .entry(format!("UBX 0x{class:02X} 0x{id:02X}"))
                    .or_default() += 1;
                true
            }
        };
        if !ok {
            self.counts.undecodable += 1;
        }
    }

    fn rxm_raw(&mut self, p: &[u8], out: &mut Vec<Item>) -> bool {
        let (Some(tow), Some(week), Some(&n)) = (le::<4>(p, 0), le::<2>(p, 4), p.get(6)) else {
            return false;
        };
        if p.len() != 8 + 24 * usize::from(n) {
            return false;
        }
        let week = i64::from(i16::from_le_bytes(week));
        self.week = Some(week);
        let t = week as f64 * WEEK_S + f64::from(i32::from_le_bytes(tow)) / 1000.0;
        let mut e = ObsEpoch {
            time_gps_s: t,
            sats: Default::default(),
        };
        for k in 0..usize::from(n) {
            let q = 8 + 24 * k;
            let (Some(pr), Some(&sv), Some(&qi), Some(&cno)) = (
                le::<8>(p, q + 8),
                p.get(q + 20),
                p.get(q + 21),
                p.get(q + 22),
            ) else {
                return false;
            };
            let pr_m = f64::from_le_bytes(pr);
            if !(1..=32).contains(&sv)
                || (qi as i8) < MIN_MES_QI
                || !(pr_m.is_finite() && pr_m > 1e6)
            {
                continue;
            }
            e.sats
                .entry(SatId::new(System::Gps, sv))
                .or_default()
                .push(CodeObs {
                    code: "C1C".into(),
                    value_m: pr_m,
                    // cno: I1, dB-Hz.
                    cn0_dbhz: Some(f64::from(cno as i8)),
                    // doMes: R4, Hz, positive approaching (u-blox 5/6
                    // protocol specification, RXM-RAW).
                    rate: le::<4>(p, q + 16)
                        .map(f32::from_le_bytes)
                        .filter(|d| d.is_finite())
                        .map(|d| SignalRate::Doppler { hz: f64::from(d) }),
                });
        }
        self.counts.epochs += 1;
        out.push(Item::Epoch(e));
        true
    }

    fn subframe(&mut self, id: SatId, sf: Subframe, out: &mut Vec<Item>) {
        let Some(week) = self.week else {
            *self
                .counts
                .ignored
                .entry("subframe before the first epoch".into())
                .or_default() += 1;
            return;
        };
        match self.lnav.push(id, &sf, week) {
            Decoded::Ephemeris(k) => {
                self.counts.ephemerides += 1;
                out.push(Item::Ephemeris(k));
            }
            Decoded::Klobuchar(kb) => out.push(Item::Klobuchar(kb)),
            Decoded::Nothing => {}
        }
    }

    fn rxm_sfrb(&mut self, p: &[u8], out: &mut Vec<Item>) -> bool {
        if p.len() != 42 {
            return false;
        }
        let sv = p[1];
        if !(1..=32).contains(&sv) {
            *self
                .counts
                .ignored
                .entry("RXM-SFRB of SBAS".into())
                .or_default() += 1;
            return true;
        }
        let mut w = [0u32; 10];
        for (k, word) in w.iter_mut().enumerate() {
            *word = le::<4>(p, 2 + 4 * k).map_or(0, u32::from_le_bytes) & 0xFF_FFFF;
        }
        self.subframe(SatId::new(System::Gps, sv), Subframe(w), out);
        true
    }

    fn rxm_rawx(&mut self, whole: &[u8], out: &mut Vec<Item>) -> bool {
        use ublox::proto23::{PacketRef, Proto23};
        let mut parser = ublox::Parser::<Vec<u8>, Proto23>::new(Vec::new());
        let mut it = parser.consume_ubx(whole);
        let Some(Ok(ublox::UbxPacket::Proto23(PacketRef::RxmRawx(m)))) = it.next() else {
            return false;
        };
        let week = i64::from(m.week());
        self.week = Some(week);
        let mut e = ObsEpoch {
            time_gps_s: week as f64 * WEEK_S + m.rcv_tow(),
            sats: Default::default(),
        };
        for meas in m.measurements() {
            let pr_valid = meas.trk_stat().bits() & 1 == 1;
            let Some((system, code)) = rawx_code(meas.gnss_id(), meas.reserved2()) else {
                continue;
            };
            let pr = meas.pr_mes();
            if !(pr_valid && pr.is_finite() && pr > 1e6) {
                continue;
            }
            e.sats
                .entry(SatId::new(system, meas.sv_id()))
                .or_default()
                .push(CodeObs {
                    code: code.into(),
                    value_m: pr,
                    cn0_dbhz: Some(f64::from(meas.cno())),
                    // doMes: Hz, positive approaching (RXM-RAWX).
                    rate: Some(meas.do_mes())
                        .filter(|d| d.is_finite())
                        .map(|d| SignalRate::Doppler { hz: f64::from(d) }),
                });
        }
        self.counts.epochs += 1;
        out.push(Item::Epoch(e));
        true
    }

    fn rxm_sfrbx(&mut self, whole: &[u8], out: &mut Vec<Item>) -> bool {
        use ublox::proto23::{PacketRef, Proto23};
        let mut parser = ublox::Parser::<Vec<u8>, Proto23>::new(Vec::new());
        let mut it = parser.consume_ubx(whole);
        let Some(Ok(ublox::UbxPacket::Proto23(PacketRef::RxmSfrbx(m)))) = it.next() else {
            return false;
        };
        let system = match m.gnss_id() {
            0 => System::Gps,
            5 => System::Qzss,
            g => {
                *self
                    .counts
                    .ignored
                    .entry(format!("RXM-SFRBX of gnssId {g}"))
                    .or_default() += 1;
                return true;
            }
        };
        let words: Vec<u32> = m.dwrd().collect();
        if words.len() != 10 {
            return false;
        }
        let mut w = [0u32; 10];
        for (d, s) in w.iter_mut().zip(&words) {
            *d = (s >> 6) & 0xFF_FFFF;
        }
        self.subframe(SatId::new(system, m.sv_id()), Subframe(w), out);
        true
    }
}

impl Decoder for Ubx {
    fn push(&mut self, bytes: &[u8], out: &mut Vec<Item>) {
        self.counts.bytes += bytes.len() as u64;
        self.buf.extend_from_slice(bytes);
        self.frames(out, false);
    }

    fn finish(&mut self, out: &mut Vec<Item>) {
        self.frames(out, true);
    }

    fn counts(&self) -> &Counts {
        &self.counts
    }

    fn waiting_epochs(&self) -> usize {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(bytes: &[u8]) -> (Vec<Item>, Counts) {
        let mut d = Ubx::default();
        let mut out = Vec::new();
        d.push(bytes, &mut out);
        d.finish(&mut out);
        (out, d.counts().clone())
    }

    /// One RXM-RAWX measurement (32 bytes, the M8 protocol's layout).
    fn rawx_meas(pr_m: f64, gnss: u8, sv: u8, sig: u8, trk: u8) -> Vec<u8> {
        let mut m = Vec::new();
        m.extend_from_slice(&pr_m.to_le_bytes());
        m.extend_from_slice(&0f64.to_le_bytes());
        m.extend_from_slice(&0f32.to_le_bytes());
        m.extend_from_slice(&[gnss, sv, sig, 0]);
        m.extend_from_slice(&0u16.to_le_bytes());
        m.extend_from_slice(&[40, 0, 0, 0, trk, 0]);
        m
    }

    /// RXM-RAWX through the `ublox` crate: the week and receiver time give
    /// the epoch's GPS time; a GPS L1 C/A and a Galileo E5a measurement with
    /// a valid pseudorange are kept under their RINEX codes, one without
    /// (trkStat bit 0 clear) is dropped.
    #[test]
    fn rawx_measurements() {
        let mut p = Vec::new();
        p.extend_from_slice(&345_600.5f64.to_le_bytes());
        p.extend_from_slice(&2300u16.to_le_bytes());
        p.extend_from_slice(&[18, 3, 0, 1, 0, 0]);
        p.extend(rawx_meas(2.1e7, 0, 5, 0, 1));
        p.extend(rawx_meas(2.4e7, 2, 11, 3, 1));
        p.extend(rawx_meas(2.2e7, 0, 7, 0, 0));
        let (out, c) = decode(&frame(0x02, 0x15, &p));
        assert_eq!((c.frames, c.undecodable, c.epochs), (1, 0, 1));
        let Some(Item::Epoch(e)) = out.first() else {
            panic!("{out:?}")
        };
        assert!((e.time_gps_s - (2300.0 * WEEK_S + 345_600.5)).abs() < 1e-9);
        assert_eq!(e.sats.len(), 2);
        assert_eq!(e.sats[&SatId::new(System::Gps, 5)][0].code, "C1C");
        assert_eq!(e.sats[&SatId::new(System::Galileo, 11)][0].code, "C5I");
    }

    /// RXM-SFRBX: GPS LNAV words of 30 bits (24 data bits above 6 parity
    /// bits) reach the LNAV decoder: subframe 4 page 18 gives Klobuchar.
    /// A subframe before any epoch's week is counted, not decoded.
    #[test]
    fn sfrbx_subframes() {
        let mut w = [0u32; 10];
        w[0] = 0x8B << 16;
        w[1] = 4 << 2;
        // Word 3: data ID 01, SV ID 56, alpha0 = 3.
        w[2] = (1 << 22) | (56 << 16) | (3 << 8);
        let mut p = vec![0u8, 5, 0, 0, 10, 0, 2, 0];
        for x in w {
            p.extend_from_slice(&(x << 6).to_le_bytes());
        }
        let sfrbx = frame(0x02, 0x13, &p);
        let (_, c) = decode(&sfrbx);
        assert_eq!(c.ignored.get("subframe before the first epoch"), Some(&1));
        let mut raw = Vec::new();
        raw.extend_from_slice(&1_000i32.to_le_bytes());
        raw.extend_from_slice(&2300i16.to_le_bytes());
        raw.extend_from_slice(&[0, 0]);
        let mut bytes = frame(0x02, 0x10, &raw);
        bytes.extend_from_slice(&sfrbx);
        let (out, c) = decode(&bytes);
        assert_eq!(c.undecodable, 0);
        let kb = out.iter().find_map(|i| match i {
            Item::Klobuchar(k) => Some(*k),
            _ => None,
        });
        let kb = kb.expect("Klobuchar from page 18");
        assert!((kb.alpha[0] - 3.0 * 2f64.powi(-30)).abs() < 1e-20);
    }

    /// RXM-RAW: a measurement below mesQI 4 is dropped; a wrong length is
    /// undecodable; a bad checksum, garbage and an unknown class are skipped
    /// and counted; a cut frame at the end is counted as such.
    #[test]
    fn raw_and_damage() {
        let mut p = Vec::new();
        p.extend_from_slice(&5_000i32.to_le_bytes());
        p.extend_from_slice(&1481i16.to_le_bytes());
        p.extend_from_slice(&[2, 0]);
        for (sv, qi) in [(3u8, 7i8), (4, 3)] {
            p.extend_from_slice(&0f64.to_le_bytes());
            p.extend_from_slice(&2.3e7f64.to_le_bytes());
            p.extend_from_slice(&0f32.to_le_bytes());
            p.extend_from_slice(&[sv, qi as u8, 40, 0]);
        }
        let good = frame(0x02, 0x10, &p);
        let mut bad = good.clone();
        let k = bad.len() - 1;
        bad[k] ^= 1;
        let mut bytes = b"xyz".to_vec();
        bytes.extend_from_slice(&bad);
        bytes.extend_from_slice(&frame(0x02, 0x10, &p[..10]));
        bytes.extend_from_slice(&frame(0x0A, 0x04, &[1, 2]));
        bytes.extend_from_slice(&good);
        bytes.extend_from_slice(&good[..20]);
        let (out, c) = decode(&bytes);
        assert_eq!(c.bad_checksum, 1);
        assert_eq!(c.undecodable, 1);
        assert_eq!(c.ignored.get("UBX 0x0A 0x04"), Some(&1));
        assert_eq!(c.truncated_tail_bytes, 20);
        assert!(c.garbage_bytes >= 3);
        let epochs: Vec<&ObsEpoch> = out
            .iter()
            .filter_map(|i| match i {
                Item::Epoch(e) => Some(e),
                _ => None,
            })
            .collect();
        assert_eq!(epochs.len(), 1);
        assert_eq!(epochs[0].sats.len(), 1);
        assert!(epochs[0].sats.contains_key(&SatId::new(System::Gps, 3)));
    }
}
