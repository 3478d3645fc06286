//! GPS (and QZSS) LNAV subframes to a broadcast ephemeris and the
//! Klobuchar coefficients (IS-GPS-200 §20.3.2-20.3.3, Figure 20-1 and
//! Tables 20-I, 20-III, 20-V).
//!
//! A subframe is handed over as ten 24-bit words with the parity bits
//! removed (u-blox RXM-SFRB gives them so; RXM-SFRBX gives 30-bit words,
//! shifted right by 6 first). The fields that span two words are then
//! contiguous, so each field is read at a fixed bit offset of the 240-bit
//! subframe. Subframes 1, 2 and 3 of one satellite with the same issue of
//! data (IODC's low 8 bits = IODE of subframes 2 and 3) make one ephemeris;
//! subframe 4 page 18 carries the Klobuchar alpha/beta.

use std::collections::BTreeMap;
use std::f64::consts::PI;

use raim_core::{SatId, System};
use raim_gnss::ephemeris::{Kepler, WEEK_S};
use raim_gnss::iono::Klobuchar;

/// Bits of one subframe (10 words x 24 data bits).
pub const SUBFRAME_BITS: usize = 240;
/// The TLM word's preamble (IS-GPS-200 Figure 20-2).
pub const PREAMBLE: u32 = 0x8B;
/// Subframe 4 page 18 (ionosphere and UTC) has SV ID 56 (Table 20-V).
const PAGE_18_SV_ID: u32 = 56;

/// Ten 24-bit words, most significant bit first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Subframe(pub [u32; 10]);

impl Subframe {
    /// Unsigned field of `len` bits at bit `pos` (0 = first bit of word 1).
    fn u(&self, pos: usize, len: usize) -> u64 {
        let mut v = 0u64;
        for b in pos..pos + len {
            let word = self.0.get(b / 24).copied().unwrap_or(0);
            let bit = (word >> (23 - (b % 24))) & 1;
            v = (v << 1) | u64::from(bit);
        }
        v
    }

    /// Two's-complement field.
    fn s(&self, pos: usize, len: usize) -> i64 {
        let v = self.u(pos, len) as i64;
        if len > 0 && v & (1 << (len - 1)) != 0 {
            v - (1 << len)
        } else {
            v
        }
    }

    /// The preamble of the TLM word.
    pub fn preamble(&self) -> u32 {
        self.0[0] >> 16
    }

    /// Subframe ID of the HOW (1-5).
    pub fn id(&self) -> u32 {
        (self.0[1] >> 2) & 7
    }

    /// Time of week of the start of the next subframe, s (HOW TOW count x 6).
    pub fn next_tow_s(&self) -> f64 {
        self.u(24, 17) as f64 * 6.0
    }
}

/// 2^-n.
fn p2(n: i32) -> f64 {
    2f64.powi(-n)
}

/// URA index to its nominal value, m (IS-GPS-200 20.3.3.3.1.3).
pub fn ura_m(index: u32) -> f64 {
    match index {
        0..=6 => 2f64.powf(1.0 + f64::from(index) / 2.0),
        7..=14 => 2f64.powi(index as i32 - 2),
        _ => f64::INFINITY,
    }
}

/// The subframe 1 fields (Table 20-I).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Sf1 {
    week10: u32,
    health: u32,
    iodc: u32,
    tgd_s: f64,
    toc_sow_s: f64,
    af2: f64,
    af1: f64,
    af0: f64,
    tx_tow_s: f64,
}

fn sf1(sf: &Subframe) -> Sf1 {
    let i = 48;
    Sf1 {
        week10: sf.u(i, 10) as u32,
        health: sf.u(i + 16, 6) as u32,
        iodc: ((sf.u(i + 22, 2) << 8) | sf.u(i + 120, 8)) as u32,
        tgd_s: sf.s(i + 112, 8) as f64 * p2(31),
        toc_sow_s: sf.u(i + 128, 16) as f64 * 16.0,
        af2: sf.s(i + 144, 8) as f64 * p2(55),
        af1: sf.s(i + 152, 16) as f64 * p2(43),
        af0: sf.s(i + 168, 22) as f64 * p2(31),
        tx_tow_s: sf.next_tow_s() - 6.0,
    }
}

/// Subframe 2 (Table 20-III): IODE, Crs, delta n, M0, Cuc, e, Cus, sqrt A, toe.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Sf2 {
    iode: u32,
    crs: f64,
    delta_n: f64,
    m0: f64,
    cuc: f64,
    e: f64,
    cus: f64,
    sqrt_a: f64,
    toe_sow_s: f64,
}

fn sf2(sf: &Subframe) -> Sf2 {
    let i = 48;
    Sf2 {
        iode: sf.u(i, 8) as u32,
        crs: sf.s(i + 8, 16) as f64 * p2(5),
        delta_n: sf.s(i + 24, 16) as f64 * p2(43) * PI,
        m0: sf.s(i + 40, 32) as f64 * p2(31) * PI,
        cuc: sf.s(i + 72, 16) as f64 * p2(29),
        e: sf.u(i + 88, 32) as f64 * p2(33),
        cus: sf.s(i + 120, 16) as f64 * p2(29),
        sqrt_a: sf.u(i + 136, 32) as f64 * p2(19),
        toe_sow_s: sf.u(i + 168, 16) as f64 * 16.0,
    }
}

/// Subframe 3 (Table 20-III): Cic, Omega0, Cis, i0, Crc, omega, Omega dot, IODE, IDOT.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Sf3 {
    cic: f64,
    omega0: f64,
    cis: f64,
    i0: f64,
    crc: f64,
    omega: f64,
    omega_dot: f64,
    iode: u32,
    idot: f64,
}

fn sf3(sf: &Subframe) -> Sf3 {
    let i = 48;
    Sf3 {
        cic: sf.s(i, 16) as f64 * p2(29),
        omega0: sf.s(i + 16, 32) as f64 * p2(31) * PI,
        cis: sf.s(i + 48, 16) as f64 * p2(29),
        i0: sf.s(i + 64, 32) as f64 * p2(31) * PI,
        crc: sf.s(i + 96, 16) as f64 * p2(5),
        omega: sf.s(i + 112, 32) as f64 * p2(31) * PI,
        omega_dot: sf.s(i + 144, 24) as f64 * p2(43) * PI,
        iode: sf.u(i + 168, 8) as u32,
        idot: sf.s(i + 176, 14) as f64 * p2(43) * PI,
    }
}

/// Klobuchar alpha/beta of subframe 4 page 18 (Table 20-X), or None for
/// another page.
pub fn klobuchar(sf: &Subframe) -> Option<Klobuchar> {
    if sf.id() != 4 || sf.u(50, 6) as u32 != PAGE_18_SV_ID {
        return None;
    }
    let i = 56;
    let a = |k: usize, n: i32| sf.s(i + 8 * k, 8) as f64 * p2(n);
    Some(Klobuchar {
        alpha: [a(0, 30), a(1, 27), a(2, 24), a(3, 24)],
        beta: [a(4, -11), a(5, -14), a(6, -16), a(7, -16)],
    })
}

/// Resolve a week number given modulo `modulus` (1024 for the 10-bit LNAV
/// week) to the full week nearest `near_week`.
pub fn unroll_week(week_mod: u32, modulus: u32, near_week: i64) -> i64 {
    let m = i64::from(modulus);
    let base = near_week - near_week.rem_euclid(m) + i64::from(week_mod);
    [base - m, base, base + m]
        .into_iter()
        .min_by_key(|w| (w - near_week).abs())
        .unwrap_or(base)
}

/// Collects subframes per satellite and assembles ephemerides.
#[derive(Debug, Default)]
pub struct LnavCollector {
    sf1: BTreeMap<SatId, Sf1>,
    sf2: BTreeMap<SatId, Sf2>,
    sf3: BTreeMap<SatId, Sf3>,
    /// Subframes whose TLM word lacked the preamble (not LNAV or corrupt).
    pub bad_preamble: u64,
}

/// What one subframe gave.
#[derive(Debug, Clone, PartialEq)]
pub enum Decoded {
    Ephemeris(Kepler),
    Klobuchar(Klobuchar),
    Nothing,
}

impl LnavCollector {
    /// Add one subframe of `id` (GPS or QZSS). `week` is the receiver's full
    /// GPS week at reception, which unrolls the 10-bit week of subframe 1.
    pub fn push(&mut self, id: SatId, sf: &Subframe, week: i64) -> Decoded {
        if sf.preamble() != PREAMBLE {
            self.bad_preamble += 1;
            return Decoded::Nothing;
        }
        match sf.id() {
            1 => {
                self.sf1.insert(id, sf1(sf));
            }
            2 => {
                self.sf2.insert(id, sf2(sf));
            }
            3 => {
                self.sf3.insert(id, sf3(sf));
            }
            4 => {
                return klobuchar(sf).map_or(Decoded::Nothing, Decoded::Klobuchar);
            }
            _ => return Decoded::Nothing,
        }
        self.assemble(id, week)
            .map_or(Decoded::Nothing, Decoded::Ephemeris)
    }

    /// An ephemeris when subframes 1-3 of `id` share their issue of data;
    /// the subframes are then forgotten so that each set is returned once.
    fn assemble(&mut self, id: SatId, week: i64) -> Option<Kepler> {
        let (a, b, c) = (self.sf1.get(&id)?, self.sf2.get(&id)?, self.sf3.get(&id)?);
        if b.iode != c.iode || (a.iodc & 0xFF) != b.iode {
            return None;
        }
        let w = unroll_week(a.week10, 1024, week);
        // toe and toc are given in seconds of the week; the week is that of
        // the transmission, shifted by one when toe is across the boundary.
        let tx_s = w as f64 * WEEK_S + a.tx_tow_s;
        let near = |sow: f64| {
            let t = w as f64 * WEEK_S + sow;
            if t - tx_s > WEEK_S / 2.0 {
                t - WEEK_S
            } else if tx_s - t > WEEK_S / 2.0 {
                t + WEEK_S
            } else {
                t
            }
        };
        let k = Kepler {
            system: id.system,
            prn: id.prn,
            toc_gps_s: near(a.toc_sow_s),
            toe_sow_s: b.toe_sow_s,
            af0_s: a.af0,
            af1_s_s: a.af1,
            af2_s_s2: a.af2,
            sqrt_a_m05: b.sqrt_a,
            e: b.e,
            i0_rad: c.i0,
            omega0_rad: c.omega0,
            omega_rad: c.omega,
            m0_rad: b.m0,
            delta_n_rad_s: b.delta_n,
            omega_dot_rad_s: c.omega_dot,
            idot_rad_s: c.idot,
            cuc_rad: b.cuc,
            cus_rad: b.cus,
            crc_m: c.crc,
            crs_m: b.crs,
            cic_rad: c.cic,
            cis_rad: c.cis,
            group_delay_s: a.tgd_s,
            group_delay_e5a_s: 0.0,
            health: a.health,
            iod: b.iode,
        };
        self.sf1.remove(&id);
        self.sf2.remove(&id);
        self.sf3.remove(&id);
        Some(k)
    }
}

/// Whether `id` broadcasts LNAV (GPS; QZSS L1 C/A uses the same format).
pub fn is_lnav(id: SatId) -> bool {
    matches!(id.system, System::Gps | System::Qzss)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Write `v` (two's complement, `len` bits) at bit `pos`.
    fn put(words: &mut [u32; 10], pos: usize, len: usize, v: i64) {
        for k in 0..len {
            let bit = ((v >> (len - 1 - k)) & 1) as u32;
            let b = pos + k;
            let shift = 23 - (b % 24);
            words[b / 24] = (words[b / 24] & !(1 << shift)) | (bit << shift);
        }
    }

    fn frame(id: u32, tow_count: i64) -> [u32; 10] {
        let mut w = [0u32; 10];
        put(&mut w, 0, 8, PREAMBLE as i64);
        put(&mut w, 24, 17, tow_count);
        put(&mut w, 43, 3, id as i64);
        w
    }

    /// Fields written at the ICD's positions with the ICD's scales come back:
    /// a round trip of every ephemeris field, the week unrolled near the
    /// receiver's week, and Klobuchar from page 18.
    #[test]
    fn subframes_round_trip() {
        let sat = SatId::new(System::Gps, 7);
        let mut s1 = frame(1, 17_995);
        put(&mut s1, 48, 10, 457); // 1481 mod 1024
        put(&mut s1, 64, 6, 0);
        put(&mut s1, 70, 2, 0);
        put(&mut s1, 160, 8, -12); // TGD
        put(&mut s1, 168, 8, 77); // IODC low
        put(&mut s1, 176, 16, 108_000 / 16);
        put(&mut s1, 192, 8, 0);
        put(&mut s1, 200, 16, -5);
        put(&mut s1, 216, 22, 123_456);
        let mut s2 = frame(2, 17_996);
        put(&mut s2, 48, 8, 77);
        put(&mut s2, 56, 16, -1000);
        put(&mut s2, 72, 16, 12_000);
        put(&mut s2, 88, 32, -300_000_000);
        put(&mut s2, 136, 32, 80_000_000);
        put(&mut s2, 184, 32, 2_702_000_000);
        put(&mut s2, 216, 16, 108_000 / 16);
        let mut s3 = frame(3, 17_997);
        put(&mut s3, 48, 16, 100);
        put(&mut s3, 64, 32, 1_000_000_000);
        put(&mut s3, 112, 32, 650_000_000);
        put(&mut s3, 144, 16, 7000);
        put(&mut s3, 160, 32, -400_000_000);
        put(&mut s3, 192, 24, -20_000);
        put(&mut s3, 216, 8, 77);
        put(&mut s3, 224, 14, -300);
        let mut c = LnavCollector::default();
        assert_eq!(c.push(sat, &Subframe(s1), 1481), Decoded::Nothing);
        assert_eq!(c.push(sat, &Subframe(s2), 1481), Decoded::Nothing);
        let Decoded::Ephemeris(k) = c.push(sat, &Subframe(s3), 1481) else {
            panic!("no ephemeris");
        };
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-30);
        assert!(close(k.toc_gps_s, 1481.0 * WEEK_S + 108_000.0));
        assert!(close(k.toe_sow_s, 108_000.0));
        assert!(close(k.group_delay_s, -12.0 * p2(31)));
        assert!(close(k.af1_s_s, -5.0 * p2(43)));
        assert!(close(k.af0_s, 123_456.0 * p2(31)));
        assert!(close(k.crs_m, -1000.0 / 32.0));
        assert!(close(k.delta_n_rad_s, 12_000.0 * p2(43) * PI));
        assert!(close(k.m0_rad, -300_000_000.0 * p2(31) * PI));
        assert!(close(k.e, 80_000_000.0 * p2(33)));
        assert!(close(k.sqrt_a_m05, 2_702_000_000.0 * p2(19)));
        assert!(close(k.cic_rad, 100.0 * p2(29)));
        assert!(close(k.omega0_rad, 1e9 * p2(31) * PI));
        assert!(close(k.i0_rad, 650_000_000.0 * p2(31) * PI));
        assert!(close(k.crc_m, 7000.0 / 32.0));
        assert!(close(k.omega_rad, -4e8 * p2(31) * PI));
        assert!(close(k.omega_dot_rad_s, -20_000.0 * p2(43) * PI));
        assert!(close(k.idot_rad_s, -300.0 * p2(43) * PI));
        assert_eq!((k.iod, k.health), (77, 0));
        // A mismatched IODE gives nothing.
        let mut s3b = s3;
        put(&mut s3b, 216, 8, 78);
        let _ = c.push(sat, &Subframe(s1), 1481);
        let _ = c.push(sat, &Subframe(s2), 1481);
        assert_eq!(c.push(sat, &Subframe(s3b), 1481), Decoded::Nothing);
        // Page 18.
        let mut s4 = frame(4, 17_998);
        put(&mut s4, 50, 6, 56);
        for (k, v) in [3i64, -2, 1, 0, 90, -1, 2, 3].iter().enumerate() {
            put(&mut s4, 56 + 8 * k, 8, *v);
        }
        let Decoded::Klobuchar(kb) = c.push(sat, &Subframe(s4), 1481) else {
            panic!("no Klobuchar");
        };
        assert!(close(kb.alpha[0], 3.0 * p2(30)) && close(kb.alpha[1], -2.0 * p2(27)));
        assert!(close(kb.beta[0], 90.0 * 2048.0) && close(kb.beta[3], 3.0 * 65536.0));
    }

    #[test]
    fn weeks_unroll_near_the_receiver() {
        assert_eq!(unroll_week(457, 1024, 1481), 1481);
        assert_eq!(unroll_week(685, 1024, 1709), 1709);
        assert_eq!(unroll_week(1023, 1024, 2048), 2047);
        assert_eq!(unroll_week(0, 1024, 2047), 2048);
    }

    #[test]
    fn ura_values() {
        assert!((ura_m(0) - 2.0).abs() < 1e-12);
        assert!((ura_m(6) - 16.0).abs() < 1e-12);
        assert!((ura_m(7) - 32.0).abs() < 1e-12);
        assert!(ura_m(15).is_infinite());
    }
}
