//! NMEA 0183 sentences for a solved epoch (SPEC §11): RMC, GGA, GSA, GST
//! and GBS, in that order (gpsd matches GBS to the fix by its time, so the
//! fix sentences come first). Each sentence is at most 82 characters
//! (`$` to `\n`), written with `core::fmt::Write` into a `heapless::String`,
//! with the XOR checksum of the characters between `$` and `*`. Numbers are
//! written by the private `fixed` module in integer arithmetic, the same text as `format!`
//! would give, without linking `core::fmt`'s float formatting (issue 10:
//! flash).
//!
//! Field choices (docs/PROTOCOL.md):
//! - Time: the epoch's `time_s` read as UTC seconds since 1970-01-01.
//! - Talker `GP` when every satellite is GPS, else `GN`. Satellite numbers
//!   in GSA/GBS: GPS 1-32, GLONASS 65-96, Galileo 301-, BeiDou 401-,
//!   QZSS 193- (the extended numbering gpsd and u-blox use).
//! - Validity: a position exists and the decision is `Ok` or `Excluded`.
//!   An `Unavailable` or `Alarm` epoch is never a valid fix (issue 15): RMC
//!   status `V` and mode `N`, GGA quality 0, GSA fix 1. RMC's
//!   NMEA 4.1 navigational status carries the integrity decision:
//!   `S` safe (ok / excluded), `C` caution (unavailable: PL above the alert
//!   limit), `U` unsafe (alarm), `V` no position.
//! - GGA altitude is the ellipsoidal height with a geoid separation of 0,
//!   so that altitude + separation is the height above the ellipsoid.
//! - DOP fields are empty (the result carries 1-sigma errors, not DOPs).
//! - GST: rms of the all-in-view range residuals; the error ellipse from the
//!   1-sigma east/north errors (no cross term in the result: axes along
//!   north and east); 1-sigma lat/lon/alt errors.
//! - GBS fields 2-4: the 1-sigma north, east and up errors of the solution
//!   in force; 5: the excluded satellite when an exclusion is in force
//!   (the first one), else the most likely failed satellite
//!   ([`WireResult::most_likely_failed`]); GSA lists only the satellites
//!   used, so an excluded satellite is absent there;
//!   6: the probability that the all-in-view test misses a bias of the
//!   estimated size on it, `ncx2_cdf(T^2; dof, w_i^2)` (SPEC §3, §6);
//!   7: its bias estimate b_i (m); 8: the bias's standard deviation
//!   sigma_i / sqrt(S_ii) (m).

use core::fmt::Write;

mod fixed;

use raim_core::stats::dist;
use raim_core::Decision;
use raim_core::{SatId, System};

use crate::result::WireResult;

/// One sentence, `$` to `\r\n` inclusive.
pub type Sentence = heapless::String<82>;

/// The five sentences of an epoch.
pub type Sentences = heapless::Vec<Sentence, 5>;

/// A sentence would not fit in 82 characters (it cannot with the formats
/// used; kept typed so a formatting mistake is not silently cut).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TooLong;

impl From<core::fmt::Error> for TooLong {
    fn from(_: core::fmt::Error) -> Self {
        TooLong
    }
}

/// XOR of the bytes.
pub fn checksum(body: &[u8]) -> u8 {
    body.iter().fold(0, |a, b| a ^ b)
}

/// `$` + body + `*hh\r\n`.
fn finish(body: &heapless::String<80>) -> Result<Sentence, TooLong> {
    const HEX: &[u8; 16] = b"0123456789ABCDEF";
    let c = checksum(body.as_bytes());
    let hex = |n: u8| char::from(HEX.get(usize::from(n & 0xf)).copied().unwrap_or(b'0'));
    let mut s = Sentence::new();
    s.write_char('$')?;
    s.write_str(body)?;
    s.write_char('*')?;
    s.write_char(hex(c >> 4))?;
    s.write_char(hex(c))?;
    s.write_str("\r\n")?;
    Ok(s)
}

/// Civil date (year, month, day) of a day count since 1970-01-01
/// (proleptic Gregorian; H. Hinnant's days-to-civil algorithm).
pub fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

/// UTC of an epoch to the hundredth of a second.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Utc {
    /// Days since 1970-01-01.
    pub days: i64,
    /// Hundredths of a second since midnight.
    pub centiseconds_of_day: u32,
}

impl Utc {
    /// `None` for a non-finite or absurd (beyond year ~300,000) time.
    pub fn from_unix_s(time_s: f64) -> Option<Utc> {
        if !(time_s.abs() < 1e13) {
            return None;
        }
        let cs = libm::round(time_s * 100.0) as i64;
        Some(Utc {
            days: cs.div_euclid(8_640_000),
            centiseconds_of_day: cs.rem_euclid(8_640_000) as u32,
        })
    }

    fn write_time<W: Write>(&self, w: &mut W) -> core::fmt::Result {
        let c = self.centiseconds_of_day;
        let (h, m, s, cs) = (c / 360_000, c / 6000 % 60, c / 100 % 60, c % 100);
        for v in [h, m, s] {
            fixed::uint(w, u64::from(v), 2)?;
        }
        w.write_char('.')?;
        fixed::uint(w, u64::from(cs), 2)
    }

    fn write_date<W: Write>(&self, w: &mut W) -> core::fmt::Result {
        let (y, m, d) = civil_from_days(self.days);
        fixed::uint(w, u64::from(d), 2)?;
        fixed::uint(w, u64::from(m), 2)?;
        fixed::uint(w, y.rem_euclid(100).unsigned_abs(), 2)
    }
}

/// `ddmm.mmmmmm,N` (or `dddmm.mmmmmm,E` with `deg_digits` 3), rounded to
/// 1e-6 minute (1.9 mm) in integers so that 59.9999999' never prints as 60'.
fn write_angle<W: Write>(
    w: &mut W,
    rad: f64,
    deg_digits: u32,
    pos: char,
    neg: char,
) -> core::fmt::Result {
    const UNITS_PER_MIN: u64 = 1_000_000;
    let deg = rad.to_degrees();
    let total = libm::round(libm::fabs(deg) * 60.0 * UNITS_PER_MIN as f64) as u64;
    let (d, rest) = (total / (60 * UNITS_PER_MIN), total % (60 * UNITS_PER_MIN));
    let (m, frac) = (rest / UNITS_PER_MIN, rest % UNITS_PER_MIN);
    let hemi = if deg < 0.0 { neg } else { pos };
    fixed::uint(w, d, deg_digits)?;
    fixed::uint(w, m, 2)?;
    w.write_char('.')?;
    fixed::uint(w, frac, 6)?;
    w.write_char(',')?;
    w.write_char(hemi)
}

/// A number with `prec` decimals, or an empty field if not finite.
fn num<W: Write>(w: &mut W, v: f64, prec: u32) -> core::fmt::Result {
    if v.is_finite() {
        fixed::decimal(w, v, prec)
    } else {
        Ok(())
    }
}

/// The NMEA satellite number (gpsd / u-blox extended numbering).
pub fn nmea_svid(id: SatId) -> u16 {
    let prn = u16::from(id.prn);
    match id.system {
        System::Gps => prn,
        System::Glonass => 64 + prn,
        System::Galileo => 300 + prn,
        System::Beidou => 400 + prn,
        System::Qzss => 192 + prn,
    }
}

fn talker(r: &WireResult) -> &'static str {
    if r.satellites.iter().all(|s| s.id.system == System::Gps) {
        "GP"
    } else {
        "GN"
    }
}

/// Every sentence of one epoch, in the order RMC, GGA, GSA, GST, GBS.
pub fn epoch_sentences(r: &WireResult) -> Result<Sentences, TooLong> {
    let mut out = Sentences::new();
    for s in [rmc(r)?, gga(r)?, gsa(r)?, gst(r)?, gbs(r)?] {
        out.push(s).map_err(|_| TooLong)?;
    }
    Ok(out)
}

/// A valid fix: a position, and a decision under which it may be used.
/// `Unavailable` (a protection level above its alert limit) and `Alarm`
/// are not (issue 15: `Unavailable` used to be reported as a valid fix).
fn usable(r: &WireResult) -> bool {
    r.geodetic.is_some() && matches!(r.decision, Decision::Ok | Decision::Excluded)
}

/// The satellite GBS names as failed, and its bias estimate (m): the first
/// exclusion in force (decision `Excluded`, or `Unavailable` after an
/// exclusion), else the most likely failed satellite.
fn gbs_satellite(r: &WireResult) -> Option<(&raim_core::SatelliteResult, f64)> {
    let in_force = matches!(r.decision, Decision::Excluded | Decision::Unavailable);
    if let Some(x) = r.exclusions.first().filter(|_| in_force) {
        if let Some(s) = r.satellites.iter().find(|s| s.id == x.id) {
            return Some((s, x.bias_m));
        }
    }
    r.most_likely_failed().map(|s| (s, s.bias_m))
}

fn time_field<W: Write>(w: &mut W, utc: Option<Utc>) -> core::fmt::Result {
    match utc {
        Some(u) => u.write_time(w),
        None => Ok(()),
    }
}

fn position_fields<W: Write>(w: &mut W, r: &WireResult) -> core::fmt::Result {
    match r.geodetic {
        Some(g) => {
            write_angle(w, g.lat_rad, 2, 'N', 'S')?;
            w.write_char(',')?;
            write_angle(w, g.lon_rad, 3, 'E', 'W')
        }
        None => w.write_str(",,,"),
    }
}

/// RMC: time, status, position, (no speed/course), date, (no variation),
/// mode, NMEA 4.1 navigational status (the integrity decision).
pub fn rmc(r: &WireResult) -> Result<Sentence, TooLong> {
    let utc = Utc::from_unix_s(r.time_s);
    let mut b = heapless::String::<80>::new();
    b.write_str(talker(r))?;
    b.write_str("RMC,")?;
    time_field(&mut b, utc)?;
    b.write_char(',')?;
    b.write_char(if usable(r) { 'A' } else { 'V' })?;
    b.write_char(',')?;
    position_fields(&mut b, r)?;
    b.write_str(",,,")?;
    if let Some(u) = utc {
        u.write_date(&mut b)?;
    }
    let nav = match (r.geodetic.is_some(), r.decision) {
        (false, _) => 'V',
        (true, Decision::Ok | Decision::Excluded) => 'S',
        (true, Decision::Unavailable) => 'C',
        (true, Decision::Alarm) => 'U',
    };
    b.write_str(",,,")?;
    b.write_char(if usable(r) { 'A' } else { 'N' })?;
    b.write_char(',')?;
    b.write_char(nav)?;
    finish(&b)
}

/// GGA: time, position, quality (1 usable, 0 not), satellites used,
/// (no HDOP), ellipsoidal height, geoid separation 0.
pub fn gga(r: &WireResult) -> Result<Sentence, TooLong> {
    let mut b = heapless::String::<80>::new();
    b.write_str(talker(r))?;
    b.write_str("GGA,")?;
    time_field(&mut b, Utc::from_unix_s(r.time_s))?;
    b.write_char(',')?;
    position_fields(&mut b, r)?;
    let used = r.satellites.iter().filter(|s| s.used).count();
    b.write_char(',')?;
    b.write_char(if usable(r) { '1' } else { '0' })?;
    b.write_char(',')?;
    fixed::uint(&mut b, used as u64, 2)?;
    b.write_str(",,")?;
    match r.geodetic {
        Some(g) => {
            num(&mut b, g.height_m, 3)?;
            b.write_str(",M,0.000,M,,")?;
        }
        None => b.write_str(",M,,M,,")?,
    }
    finish(&b)
}

/// GSA: automatic mode, 3D fix or none, up to 12 satellites used, (no DOPs).
pub fn gsa(r: &WireResult) -> Result<Sentence, TooLong> {
    let mut b = heapless::String::<80>::new();
    b.write_str(talker(r))?;
    b.write_str("GSA,A,")?;
    b.write_char(if usable(r) { '3' } else { '1' })?;
    let mut used = r
        .satellites
        .iter()
        .filter(|s| s.used)
        .map(|s| nmea_svid(s.id));
    for _ in 0..12 {
        match used.next() {
            Some(n) => {
                b.write_char(',')?;
                fixed::uint(&mut b, u64::from(n), 2)?;
            }
            None => b.write_char(',')?,
        }
    }
    b.write_str(",,,")?;
    finish(&b)
}

/// GST: time, range rms, error ellipse, 1-sigma lat/lon/alt errors (m).
pub fn gst(r: &WireResult) -> Result<Sentence, TooLong> {
    let [e, n, u] = r.sigma_enu_m;
    let mut b = heapless::String::<80>::new();
    b.write_str(talker(r))?;
    b.write_str("GST,")?;
    time_field(&mut b, Utc::from_unix_s(r.time_s))?;
    b.write_char(',')?;
    num(&mut b, range_rms_m(r), 3)?;
    let (smaj, smin, orient_deg) = if n >= e { (n, e, 0.0) } else { (e, n, 90.0) };
    for (v, p) in [
        (smaj, 3),
        (smin, 3),
        (orient_deg, 1),
        (n, 3),
        (e, 3),
        (u, 3),
    ] {
        b.write_char(',')?;
        num(&mut b, v, p)?;
    }
    finish(&b)
}

/// RMS of the all-in-view range residuals r_i = w_i sqrt(S_ii) sigma_i, m.
pub fn range_rms_m(r: &WireResult) -> f64 {
    let (sum, k) = r
        .satellites
        .iter()
        .map(|s| s.w * libm::sqrt(s.s_ii) * s.sigma_m)
        .filter(|v| v.is_finite())
        .fold((0.0, 0u32), |(a, k), v| (a + v * v, k + 1));
    if k == 0 {
        f64::NAN
    } else {
        libm::sqrt(sum / f64::from(k))
    }
}

/// GBS: time, 1-sigma lat/lon/alt errors, the most likely failed satellite,
/// its probability of missed detection, its bias and the bias's sigma.
pub fn gbs(r: &WireResult) -> Result<Sentence, TooLong> {
    let [e, n, u] = r.sigma_enu_m;
    let mut b = heapless::String::<80>::new();
    b.write_str(talker(r))?;
    b.write_str("GBS,")?;
    time_field(&mut b, Utc::from_unix_s(r.time_s))?;
    for v in [n, e, u] {
        b.write_char(',')?;
        num(&mut b, v, 3)?;
    }
    match gbs_satellite(r) {
        Some((s, bias_m)) => {
            let t = r.initial_test;
            let pmd = dist::ncx2_cdf(t.threshold, t.dof, s.w * s.w).unwrap_or(f64::NAN);
            b.write_char(',')?;
            fixed::uint(&mut b, u64::from(nmea_svid(s.id)), 2)?;
            b.write_char(',')?;
            num(&mut b, pmd, 6)?;
            b.write_char(',')?;
            num(&mut b, bias_m, 3)?;
            b.write_char(',')?;
            num(&mut b, s.sigma_m / libm::sqrt(s.s_ii), 3)?;
        }
        None => b.write_str(",,,,")?,
    }
    finish(&b)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use raim_core::frames::Geodetic;
    use raim_core::{Config, Epoch, LinearObservation, Raim};
    use std::string::String;

    fn parse(s: &str) -> (String, u8) {
        let body = s.strip_prefix('$').unwrap().strip_suffix("\r\n").unwrap();
        let (body, cs) = body.split_once('*').unwrap();
        (body.into(), u8::from_str_radix(cs, 16).unwrap())
    }

    #[test]
    fn checksum_matches_published_examples() {
        // The two classic examples of the NMEA 0183 literature, with the
        // checksums printed there.
        let gga = "GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,";
        assert_eq!(checksum(gga.as_bytes()), 0x47);
        let rmc = "GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W";
        assert_eq!(checksum(rmc.as_bytes()), 0x6A);
    }

    #[test]
    fn civil_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(-1), (1969, 12, 31));
        // 2000-03-01: 30 years (7 leap days 1972..1996) + Jan + Feb 2000 (leap).
        assert_eq!(civil_from_days(30 * 365 + 7 + 31 + 29), (2000, 3, 1));
        // 2024-02-29 = 19782 days (1,709,164,800 s / 86,400).
        assert_eq!(civil_from_days(19_782), (2024, 2, 29));
    }

    #[test]
    fn time_rounds_to_centiseconds() {
        let u = Utc::from_unix_s(1_709_164_800.0 + 12.0 * 3600.0 + 35.0 * 60.0 + 19.996).unwrap();
        let mut s = String::new();
        u.write_time(&mut s).unwrap();
        u.write_date(&mut s).unwrap();
        assert_eq!(s, "123520.00290224");
        assert_eq!(Utc::from_unix_s(f64::NAN), None);
    }

    #[test]
    fn angles_in_degrees_and_minutes() {
        let mut s = String::new();
        write_angle(&mut s, 48.1173f64.to_radians(), 2, 'N', 'S').unwrap();
        assert_eq!(s, "4807.038000,N");
        s.clear();
        write_angle(&mut s, (-11.5166666667f64).to_radians(), 3, 'E', 'W').unwrap();
        assert_eq!(s, "01131.000000,W");
        s.clear();
        // 59.99999999' rounds up to the next degree, not to 60'.
        write_angle(&mut s, (1.0 - 1e-10f64).to_radians(), 2, 'N', 'S').unwrap();
        assert_eq!(s, "0100.000000,N");
    }

    fn sky8_result(step_m: f64) -> WireResult {
        let sky = [
            (0.0, 85.0),
            (45.0, 30.0),
            (100.0, 50.0),
            (150.0, 20.0),
            (200.0, 60.0),
            (250.0, 25.0),
            (300.0, 40.0),
            (340.0, 15.0),
        ];
        let res = [0.57, step_m - 0.23, -0.80, 1.12, -0.05, 0.08, 0.40, 0.86];
        let sats: std::vec::Vec<LinearObservation> = sky
            .iter()
            .zip(res)
            .enumerate()
            .map(|(i, (&(az, el), r)): (usize, (&(f64, f64), f64))| {
                let mut o = LinearObservation::from_az_el(
                    SatId::new(System::Gps, i as u8 + 1),
                    az.to_radians(),
                    el.to_radians(),
                    r,
                );
                o.sigma_m = Some(1.0);
                o
            })
            .collect();
        let r = Raim::<32>::new()
            .process(&Config::default(), &Epoch::linear(1_709_164_800.5, &sats))
            .unwrap();
        WireResult::from_result(&r)
    }

    #[test]
    fn sentences_are_checksummed_ordered_and_carry_the_raim_fields() {
        let mut w = sky8_result(50.0);
        w.geodetic = Some(Geodetic {
            lat_rad: 0.5,
            lon_rad: -1.2,
            height_m: 123.4567,
        });
        let all = epoch_sentences(&w).unwrap();
        let kinds: std::vec::Vec<&str> = all.iter().map(|s| &s[3..6]).collect();
        assert_eq!(kinds, ["RMC", "GGA", "GSA", "GST", "GBS"]);
        for s in &all {
            assert!(s.len() <= 82, "{s}");
            let (body, cs) = parse(s);
            assert_eq!(checksum(body.as_bytes()), cs, "{s}");
        }
        let (gbs, _) = parse(&all[4]);
        let f: std::vec::Vec<&str> = gbs.split(',').collect();
        assert_eq!(f.len(), 9, "{gbs}");
        assert_eq!(f[1], "000000.50");
        let [e, n, u] = w.sigma_enu_m;
        let close = |s: &str, v: f64| (s.parse::<f64>().unwrap() - v).abs() <= 0.0005;
        assert!(close(f[2], n) && close(f[3], e) && close(f[4], u), "{gbs}");
        // The excluded satellite G02 is the most likely failed one; its bias
        // is the 50 m step within 5 sigma of the estimate's noise.
        assert_eq!(f[5], "02");
        let s = w.satellites[1];
        let sd = 1.0 / s.s_ii.sqrt();
        assert!(close(f[8], sd), "{gbs}");
        assert!(
            (f[7].parse::<f64>().unwrap() - 50.0).abs() < 5.0 * sd,
            "{gbs}"
        );
        // A 50 m bias on this satellite is far above the detection
        // threshold: the test cannot miss it.
        assert!(f[6].parse::<f64>().unwrap() < 1e-6, "{gbs}");
        // Excluded: the fix is valid and safe; GSA lists the 7 used satellites.
        assert!(all[0].contains(",A,S*"), "{}", all[0]);
        let (gsa, _) = parse(&all[2]);
        assert_eq!(gsa, "GPGSA,A,3,01,03,04,05,06,07,08,,,,,,,,");
        let (gga, _) = parse(&all[1]);
        assert!(gga.ends_with(",1,07,,123.457,M,0.000,M,,"), "{gga}");
    }

    #[test]
    fn no_fault_gbs_pmd_is_large_and_linear_epochs_have_no_position() {
        let w = sky8_result(0.0);
        let all = epoch_sentences(&w).unwrap();
        let (gbs, _) = parse(&all[4]);
        let f: std::vec::Vec<&str> = gbs.split(',').collect();
        // Residuals of about 1 sigma: a bias that small is almost surely missed.
        assert!(f[6].parse::<f64>().unwrap() > 0.9, "{gbs}");
        let (rmc, _) = parse(&all[0]);
        assert_eq!(rmc, "GPRMC,000000.50,V,,,,,,,290224,,,N,V");
    }

    /// Issue 15: only `Ok` and `Excluded` are a valid fix. `Unavailable`
    /// and `Alarm` give RMC status V and mode N, GGA quality 0 and GSA fix
    /// 1, with the integrity decision in RMC's navigational status; GBS
    /// names the excluded satellite while its exclusion is in force.
    #[test]
    fn unavailable_and_alarm_epochs_are_not_a_valid_fix() {
        let mut w = sky8_result(50.0);
        assert_eq!(w.decision, Decision::Excluded);
        w.geodetic = Some(Geodetic {
            lat_rad: 0.5,
            lon_rad: -1.2,
            height_m: 10.0,
        });
        for (decision, nav) in [
            (Decision::Ok, "S"),
            (Decision::Excluded, "S"),
            (Decision::Unavailable, "C"),
            (Decision::Alarm, "U"),
        ] {
            w.decision = decision;
            let valid = matches!(decision, Decision::Ok | Decision::Excluded);
            let all = epoch_sentences(&w).unwrap();
            let field = |k: usize| -> std::vec::Vec<String> {
                parse(&all[k]).0.split(',').map(String::from).collect()
            };
            let (rmc, gga, gsa, gbs) = (field(0), field(1), field(2), field(4));
            let want = |a: &str, b: &str| String::from(if valid { a } else { b });
            assert_eq!(rmc[2], want("A", "V"), "{decision:?} {rmc:?}");
            assert_eq!(rmc[12], want("A", "N"), "{decision:?} {rmc:?}");
            assert_eq!(rmc[13], nav, "{decision:?} {rmc:?}");
            assert_eq!(gga[6], want("1", "0"), "{decision:?} {gga:?}");
            assert_eq!(gsa[2], want("3", "1"), "{decision:?} {gsa:?}");
            // G02 (excluded, or identified for the alarm) is named failed,
            // and GSA does not list it.
            assert_eq!(gbs[5], "02", "{decision:?} {gbs:?}");
            assert!(!gsa[3..15].contains(&String::from("02")), "{gsa:?}");
        }
    }

    /// A real `Unavailable` epoch (the smallest HAL allowed, 40 m, with
    /// 10 m sigmas) is written as no fix.
    #[test]
    fn a_processed_unavailable_epoch_is_no_fix() {
        let cfg = Config {
            alert: raim_core::AlertLimits {
                hal_m: 40.0,
                val_m: None,
            },
            ..Config::default()
        };
        let sky = [
            (0.0, 85.0),
            (45.0, 30.0),
            (100.0, 50.0),
            (150.0, 20.0),
            (200.0, 60.0),
            (250.0, 25.0),
        ];
        let sats: std::vec::Vec<LinearObservation> = sky
            .iter()
            .enumerate()
            .map(|(i, &(az, el)): (usize, &(f64, f64))| {
                let mut o = LinearObservation::from_az_el(
                    SatId::new(System::Gps, i as u8 + 1),
                    f64::to_radians(az),
                    f64::to_radians(el),
                    0.0,
                );
                o.sigma_m = Some(10.0);
                o
            })
            .collect();
        let r = Raim::<32>::new()
            .process(&cfg, &Epoch::linear(1_709_164_800.0, &sats))
            .unwrap();
        assert_eq!(r.decision, Decision::Unavailable);
        let mut w = WireResult::from_result(&r);
        w.geodetic = Some(Geodetic {
            lat_rad: 0.5,
            lon_rad: -1.2,
            height_m: 10.0,
        });
        let all = epoch_sentences(&w).unwrap();
        assert!(
            all[0].contains(",V,") && all[0].contains(",N,C*"),
            "{}",
            all[0]
        );
        assert!(
            parse(&all[1]).0.split(',').nth(6) == Some("0"),
            "{}",
            all[1]
        );
    }
}
