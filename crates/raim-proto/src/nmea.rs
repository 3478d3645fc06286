//! NMEA 0183 4.11 sentences for a solved epoch (SPEC §11), as u-blox M9/F9
//! modules write them: RMC, VTG, GGA, GSA (one or more per constellation),
//! GSV (one set per constellation), GST, GBS and ZDA, in that order (gpsd
//! takes the used satellites of a GSV from the GSA before it, and matches
//! GBS to the fix by its time, so the fix sentences come first). Each
//! sentence is at most 82 characters (`$` to `\r\n`), written with
//! `core::fmt::Write` into a `heapless::String`, with the XOR checksum of the
//! characters between `$` and `*`. Numbers are written by `fixed` in
//! integer arithmetic, the same text as `format!` would give, without
//! linking `core::fmt`'s float formatting (flash).
//!
//! Every epoch writes every sentence whatever its values: a number that
//! does not fit its field's width with the field's decimals is written
//! with fewer decimals, and a field that cannot show it at all (or a
//! non-finite value) is left empty (`num`), so that no sentence exceeds
//! 82 characters.
//!
//! Field choices (docs/PROTOCOL.md):
//! - Time: the epoch's `time_s` read as UTC seconds since 1970-01-01.
//! - Talker `GP` when every satellite is GPS, else `GN`; GSV carries the
//!   constellation's own talker (GP, GL, GA, GB, GQ). Satellite numbers
//!   are NMEA 4.11's, within the system ID: GPS 1-32, GLONASS 65-96
//!   (64 + slot), Galileo 1-36, BeiDou 1-63, QZSS 1-10 (as u-blox M9/F9
//!   write them in 4.11 mode; [`nmea_svid`]). NMEA 4.11 system IDs: 1 GPS,
//!   2 GLONASS, 3 Galileo, 4 BeiDou, 5 QZSS; signal IDs are those of the L1/E1/B1I
//!   open signals (1, 1, 7, 1, 1): a pseudorange epoch does not say which
//!   signal it came from, and single-frequency L1 is the ranging the
//!   replay feeds.
//! - Validity: a position exists and the decision is `Ok` or `Excluded`.
//!   An `Unavailable` or `Alarm` epoch is never a valid fix: RMC
//!   status `V` and mode `N`, VTG mode `N`, GGA quality 0, GSA fix 1.
//!   RMC's NMEA 4.1 navigational status carries the integrity decision:
//!   `S` safe (ok / excluded), `C` caution (unavailable: PL above the alert
//!   limit), `U` unsafe (alarm), `V` no position.
//! - DOPs (GSA PDOP/HDOP/VDOP, GGA HDOP) and GSV need feature `nmea-sky`
//!   (flash: not in the 128 KiB firmware build, docs/FLASH.md). The DOPs
//!   are those of the geometry in use, the
//!   unweighted (G^T G)^-1 of the used satellites' ENU lines of sight with
//!   one clock column per constellation used (SPEC §1's model without the
//!   weights); empty when that matrix is singular or no position exists.
//! - GGA altitude: above mean sea level, `h - N`, with N the EGM96 geoid
//!   separation of [`geoid`] (feature `geoid`; a 1-degree grid). A build
//!   without it writes the ellipsoidal height with a separation of 0, so
//!   that altitude + separation is still the height above the ellipsoid.
//! - GSV: every satellite of the epoch, elevation and azimuth from the
//!   solved position (or the epoch's a-priori position) and the satellite's
//!   position (pseudorange epochs) or its line of sight (linearised
//!   epochs); C/N0 when the caller knows it ([`Sky::cn0_dbhz`]), else empty.
//! - RMC speed and course, VTG: when the caller has the receiver's velocity
//!   ([`Sky::velocity`]: a stream epoch with Doppler, decision `Ok` or
//!   `Excluded`, `raim_nav::velocity`), RMC's speed over ground in knots
//!   and true course in degrees, VTG's true course, speed in knots and in
//!   km/h (magnetic course empty: no magnetic model); else those fields
//!   empty, with the mode indicator. 1 knot = 1852 m / 3600 s. Feature
//!   `nmea-velocity` (on with raim-server's `rtcm`; not in the snapshot
//!   build, whose epochs carry no range rates): without it `write_epoch`
//!   leaves them empty.
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
//!   sigma_i / sqrt(S_ii) (m); 9-10: its system and signal IDs.

use core::fmt::Write;

mod fixed;
#[cfg(feature = "geoid")]
pub mod geoid;

use raim_core::frames::Geodetic;
use raim_core::measurement::MAX_SYSTEMS;
use raim_core::stats::dist;
use raim_core::{Decision, Epoch, Observations};
use raim_core::{SatId, System};

use crate::result::WireResult;

/// One sentence, `$` to `\r\n` inclusive.
pub type Sentence = heapless::String<82>;

/// Most sentences of one epoch: RMC, VTG, GGA, GST, GBS and ZDA, a GSA per
/// 12 used satellites of each constellation (at most `CAPACITY / 12 +
/// MAX_SYSTEMS`), a GSV per 4 satellites of each (at most `CAPACITY / 4 +
/// MAX_SYSTEMS`).
pub const MAX_SENTENCES: usize = 6 + crate::CAPACITY / 12 + crate::CAPACITY / 4 + 2 * MAX_SYSTEMS;

/// The sentences of an epoch.
pub type Sentences = heapless::Vec<Sentence, MAX_SENTENCES>;

/// A sentence would not fit in 82 characters (it cannot with the field
/// widths used; kept typed so a formatting mistake is not silently cut).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TooLong;

impl From<core::fmt::Error> for TooLong {
    fn from(_: core::fmt::Error) -> Self {
        TooLong
    }
}

/// The body of a sentence: `$` + 76 + `*hh\r\n` is 82.
type Body = heapless::String<80>;

/// XOR of the bytes.
pub fn checksum(body: &[u8]) -> u8 {
    body.iter().fold(0, |a, b| a ^ b)
}

/// `$` + body + `*hh\r\n`.
fn finish(body: &Body) -> Result<Sentence, TooLong> {
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

/// Writes into a fixed buffer of at most `width` characters, failing past it.
struct Field<const W: usize> {
    text: heapless::String<W>,
}

impl<const W: usize> Write for Field<W> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        self.text.push_str(s).map_err(|_| core::fmt::Error)
    }
}

/// Widest numeric field.
const MAX_WIDTH: usize = 10;

/// A number in at most `width` characters: with `prec` decimals if that
/// fits, else with as many as fit (none: no point), else an empty field;
/// empty too when not finite. The widths are chosen so that every
/// sentence fits 82 characters whatever the values.
fn num<W: Write>(w: &mut W, v: f64, prec: u32, width: usize) -> core::fmt::Result {
    if !v.is_finite() {
        return Ok(());
    }
    for p in (0..=prec).rev() {
        let mut f = Field::<MAX_WIDTH> {
            text: heapless::String::new(),
        };
        if fixed::decimal(&mut f, v, p).is_ok() && f.text.len() <= width {
            return w.write_str(&f.text);
        }
    }
    Ok(())
}

/// The NMEA 0183 4.11 satellite number, read with the system ID
/// ([`system_id`]: GSA field 18, GBS field 9) or the GSV talker: GPS PRN
/// 1-32, GLONASS 64 + slot (65-96), Galileo SVID 1-36, BeiDou PRN 1-63,
/// QZSS 1-10 (PRN 193-202 less 192), as u-blox M9/F9 write them in NMEA
/// 4.11 mode. Not the extended numbering of NMEA 4.10 receivers and
/// gpsd's skyview (Galileo 301-336, BeiDou 401-463, QZSS 193-202), which
/// gpsd derives from these with the system ID (docs/PROTOCOL.md).
pub fn nmea_svid(id: SatId) -> u16 {
    let prn = u16::from(id.prn);
    match id.system {
        System::Glonass => 64 + prn,
        System::Gps | System::Galileo | System::Beidou | System::Qzss => prn,
    }
}

/// NMEA 4.11 GNSS system ID.
pub fn system_id(s: System) -> u8 {
    match s {
        System::Gps => 1,
        System::Glonass => 2,
        System::Galileo => 3,
        System::Beidou => 4,
        System::Qzss => 5,
    }
}

/// NMEA 4.11 signal ID of the open L1-band signal (GPS L1 C/A, GLONASS L1
/// OF, Galileo E1 C/B, BeiDou B1I, QZSS L1 C/A).
pub fn signal_id(s: System) -> u8 {
    match s {
        System::Galileo => 7,
        _ => 1,
    }
}

/// The constellation's own talker, for GSV.
fn system_talker(s: System) -> &'static str {
    match s {
        System::Gps => "GP",
        System::Glonass => "GL",
        System::Galileo => "GA",
        System::Beidou => "GB",
        System::Qzss => "GQ",
    }
}

fn talker(r: &WireResult) -> &'static str {
    if r.satellites.iter().all(|s| s.id.system == System::Gps) {
        "GP"
    } else {
        "GN"
    }
}

/// What the sentences need besides the result: the epoch that produced it
/// (the satellites seen, and their lines of sight), and their C/N0 when the
/// caller knows them.
#[derive(Clone, Copy)]
pub struct Sky<'a> {
    /// The epoch whose satellites were seen.
    pub epoch: &'a Epoch<'a>,
    /// C/N0 (whole dB-Hz) of the epoch's satellites in its order; shorter
    /// (or empty) when unknown, and an entry of 0 is unknown too (a signal
    /// tracked has more; `raim_nav::ranging::cn0_dbhz_u8`). A value above
    /// 99, which GSV's two digits cannot hold, is written as unknown.
    pub cn0_dbhz: &'a [u8],
    /// The receiver's speed and course over ground, when known (RMC,
    /// VTG); None: those fields empty.
    pub velocity: Option<GroundVelocity>,
}

/// Speed and course over ground, for RMC and VTG.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundVelocity {
    /// Horizontal speed, m/s.
    pub speed_m_s: f64,
    /// Direction of the horizontal velocity, clockwise from true north,
    /// rad.
    pub course_rad: f64,
}

/// Metres per second in a knot (1852 m per hour).
const KNOT_M_S: f64 = 1852.0 / 3600.0;
/// Metres per second in a km/h.
const KM_H_M_S: f64 = 1000.0 / 3600.0;

impl GroundVelocity {
    /// Speed in knots, course in degrees in [0, 360) (a course that
    /// rounds to 360.00 at the field's 2 decimals is written 0).
    fn knots_deg(&self) -> (f64, f64) {
        let mut deg = libm::fmod(self.course_rad.to_degrees(), 360.0);
        if deg < 0.0 {
            deg += 360.0;
        }
        if deg >= 359.995 {
            deg = 0.0;
        }
        (self.speed_m_s / KNOT_M_S, deg)
    }
}

impl<'a> Sky<'a> {
    /// The epoch's satellites without C/N0.
    pub fn new(epoch: &'a Epoch<'a>) -> Self {
        Sky {
            epoch,
            cn0_dbhz: &[],
            velocity: None,
        }
    }

    fn len(&self) -> usize {
        self.epoch.len()
    }

    fn id(&self, i: usize) -> Option<SatId> {
        match self.epoch.observations {
            Observations::Ranges { sats, .. } => sats.get(i).map(|s| s.id),
            Observations::Linear { sats } => sats.get(i).map(|s| s.id),
        }
    }

    /// Unit line of sight (ENU) of satellite `i` seen from `frame`.
    fn los_enu(&self, i: usize, frame: &Frame) -> Option<[f64; 3]> {
        let v = match (self.epoch.observations, frame) {
            (Observations::Linear { sats }, _) => sats.get(i)?.los_enu,
            (Observations::Ranges { sats, .. }, Frame::At { ecef_m, trig }) => {
                let p = sats.get(i)?.position_m;
                let [dx, dy, dz] = [p[0] - ecef_m[0], p[1] - ecef_m[1], p[2] - ecef_m[2]];
                // ECEF to ENU (raim_core::frames::enu_rotation's rows).
                let [sl, cl, so, co] = *trig;
                [
                    -so * dx + co * dy,
                    -sl * co * dx - sl * so * dy + cl * dz,
                    cl * co * dx + cl * so * dy + sl * dz,
                ]
            }
            (Observations::Ranges { .. }, Frame::None) => return None,
        };
        let norm = libm::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        (norm > 0.0 && norm.is_finite()).then(|| [v[0] / norm, v[1] / norm, v[2] / norm])
    }
}

/// Where pseudorange lines of sight are seen from.
enum Frame {
    /// The point and the sines and cosines of its latitude and longitude.
    At {
        ecef_m: [f64; 3],
        trig: [f64; 4],
    },
    None,
}

/// The solved position, else the epoch's a-priori one.
fn frame(r: &WireResult, sky: &Sky) -> Frame {
    let apriori = match sky.epoch.observations {
        Observations::Ranges { apriori_m, .. } => apriori_m,
        Observations::Linear { .. } => None,
    };
    match r.position_ecef_m.or(apriori) {
        Some(ecef_m) if ecef_m.iter().all(|v| v.is_finite()) => {
            let g = r
                .geodetic
                .filter(|_| r.position_ecef_m.is_some())
                .unwrap_or_else(|| raim_core::frames::ecef_to_geodetic(ecef_m));
            Frame::At {
                ecef_m,
                trig: [
                    libm::sin(g.lat_rad),
                    libm::cos(g.lat_rad),
                    libm::sin(g.lon_rad),
                    libm::cos(g.lon_rad),
                ],
            }
        }
        _ => Frame::None,
    }
}

/// Dilutions of precision of the geometry in use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dops {
    /// Position dilution of precision.
    pub pdop: f64,
    /// Horizontal dilution of precision.
    pub hdop: f64,
    /// Vertical dilution of precision.
    pub vdop: f64,
}

/// States of the DOP model: E, N, U and a clock per system.
const DOP_STATES: usize = 3 + MAX_SYSTEMS;

/// A square matrix of the DOP model, read and written through checked
/// indices (out of range reads 0 and writes nothing: the loops below stay
/// within `DOP_STATES`).
struct Square([[f64; DOP_STATES]; DOP_STATES]);

impl Square {
    fn at(&self, i: usize, j: usize) -> f64 {
        self.0.get(i).and_then(|r| r.get(j)).copied().unwrap_or(0.0)
    }

    fn set(&mut self, i: usize, j: usize, v: f64) {
        if let Some(c) = self.0.get_mut(i).and_then(|r| r.get_mut(j)) {
            *c = v;
        }
    }
}

/// The DOPs of the used satellites: the diagonal of Q = (G^T G)^-1 with
/// rows [e, n, u, one-hot clock of the satellite's system], by the
/// Cholesky factor L of G^T G (symmetric positive definite when the
/// geometry determines the states): Q_ii = |L^-1 e_i|^2. `None` when the
/// geometry does not determine the states.
pub fn dops(r: &WireResult, sky: &Sky) -> Option<Dops> {
    let fr = frame(r, sky);
    let mut present = [false; MAX_SYSTEMS];
    let mut a = Square([[0.0; DOP_STATES]; DOP_STATES]);
    let mut rows = 0usize;
    for i in 0..sky.len() {
        let Some(id) = sky.id(i) else { continue };
        if !r.satellites.iter().any(|s| s.id == id && s.used) {
            continue;
        }
        let Some([e, n, u]) = sky.los_enu(i, &fr) else {
            continue;
        };
        let k = id.system.index();
        if let Some(p) = present.get_mut(k) {
            *p = true;
        }
        let mut g = [0.0; DOP_STATES];
        for (c, v) in g.iter_mut().zip([e, n, u]) {
            *c = v;
        }
        if let Some(c) = g.get_mut(3 + k) {
            *c = 1.0;
        }
        for (row, gi) in a.0.iter_mut().zip(g.iter()) {
            for (c, gj) in row.iter_mut().zip(g.iter()) {
                *c += gi * gj;
            }
        }
        rows += 1;
    }
    // A system not used has no clock column: a unit diagonal, uncoupled.
    for (k, p) in present.iter().enumerate() {
        if !p {
            a.set(3 + k, 3 + k, 1.0);
        }
    }
    if rows < 3 + present.iter().filter(|p| **p).count() {
        return None;
    }
    // A = L L^T, L in the lower triangle of `a`.
    for j in 0..DOP_STATES {
        let d = a.at(j, j) - (0..j).map(|k| a.at(j, k) * a.at(j, k)).sum::<f64>();
        if !(d > MIN_PIVOT) {
            return None;
        }
        let d = libm::sqrt(d);
        a.set(j, j, d);
        for i in j + 1..DOP_STATES {
            let s = a.at(i, j) - (0..j).map(|k| a.at(i, k) * a.at(j, k)).sum::<f64>();
            a.set(i, j, s / d);
        }
    }
    // Q_ii = |y|^2 with L y = e_i (forward substitution from row i).
    let mut q = [0.0f64; 3];
    for (i, qi) in q.iter_mut().enumerate() {
        let mut y = [0.0f64; DOP_STATES];
        for k in i..DOP_STATES {
            let s = f64::from(u8::from(k == i))
                - (i..k)
                    .map(|m| a.at(k, m) * y.get(m).copied().unwrap_or(0.0))
                    .sum::<f64>();
            if let Some(c) = y.get_mut(k) {
                *c = s / a.at(k, k);
            }
        }
        *qi = y.iter().map(|v| v * v).sum();
    }
    let [qe, qn, qu] = q;
    Some(Dops {
        pdop: libm::sqrt(qe + qn + qu),
        hdop: libm::sqrt(qe + qn),
        vdop: libm::sqrt(qu),
    })
}

/// Smallest Cholesky pivot of a determined geometry: G^T G's entries are
/// sums of products of unit vectors and ones, so a pivot this small means
/// a rank-deficient geometry (DOPs of 1e6 and more), not a usable one.
const MIN_PIVOT: f64 = 1e-12;

/// The geoid separation N (m) at a point, with the model if it is asked
/// for and built in.
fn separation_m(g: &Geodetic, geoid: bool) -> Option<f64> {
    #[cfg(feature = "geoid")]
    if geoid {
        return geoid::separation_m(g.lat_rad, g.lon_rad);
    }
    let _ = (g, geoid);
    None
}

/// What a writer includes beyond the fixed sentences.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Options {
    /// GGA altitude above mean sea level from the geoid model (feature
    /// `geoid`); else the ellipsoidal height with a separation of 0.
    pub geoid: bool,
    /// GSV and the DOPs of GSA and GGA (feature `nmea-sky`); else no GSV and
    /// empty DOP fields.
    pub sky: bool,
}

/// Everything this build has: the firmware's and the host's writer.
pub const BUILT: Options = Options {
    geoid: cfg!(feature = "geoid"),
    sky: cfg!(feature = "nmea-sky"),
};

/// Every sentence of one epoch, in the order RMC, VTG, GGA, GSA..., GSV...,
/// GST, GBS, ZDA, handed to `emit` one at a time (the firmware writes each
/// to its UART without holding them all). `opts` beyond [`BUILT`] are
/// ignored. A sentence that could not be formatted ([`TooLong`]: the field
/// widths exclude it) is skipped.
pub fn write_epoch<E>(
    r: &WireResult,
    sky: &Sky,
    opts: Options,
    emit: &mut dyn FnMut(&Sentence) -> Result<(), E>,
) -> Result<(), E> {
    let with_sky = BUILT.sky && opts.sky;
    let dop = if with_sky { dops(r, sky) } else { None };
    let mut put = |s: Result<Sentence, TooLong>| match s {
        Ok(s) => emit(&s),
        Err(TooLong) => Ok(()),
    };
    // Speed and course in the builds that write them (feature
    // `nmea-velocity`; the snapshot build's epochs carry no range rates).
    let velocity = sky.velocity.filter(|_| cfg!(feature = "nmea-velocity"));
    put(rmc(r, velocity))?;
    put(vtg(r, velocity))?;
    put(gga(r, dop, BUILT.geoid && opts.geoid))?;
    for sys in System::ALL {
        let used = r
            .satellites
            .iter()
            .filter(|s| s.used && s.id.system == sys)
            .count();
        let seen = (0..sky.len()).any(|i| sky.id(i).is_some_and(|id| id.system == sys));
        if !seen && used == 0 {
            continue;
        }
        // One GSA per 12 used satellites (one with none listed if none is).
        for part in 0..used.div_ceil(12).max(1) {
            put(gsa(r, dop, sys, part))?;
        }
    }
    if with_sky {
        let fr = frame(r, sky);
        for sys in System::ALL {
            let n = (0..sky.len())
                .filter(|&i| sky.id(i).is_some_and(|id| id.system == sys))
                .count();
            let parts = n.div_ceil(4);
            for part in 0..parts {
                put(gsv(sky, &fr, sys, n, part, parts))?;
            }
        }
    }
    put(gst(r))?;
    put(gbs(r))?;
    put(zda(r))
}

/// [`write_epoch`] collected (the host's form).
pub fn epoch_sentences(r: &WireResult, sky: &Sky, opts: Options) -> Result<Sentences, TooLong> {
    let mut out = Sentences::new();
    write_epoch(r, sky, opts, &mut |s: &Sentence| {
        out.push(s.clone()).map_err(|_| TooLong)
    })?;
    Ok(out)
}

/// A valid fix: a position, and a decision under which it may be used.
/// `Unavailable` (a protection level above its alert limit) and `Alarm`
/// are not.
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

/// Talker and sentence name, then the comma before the first field.
fn start(b: &mut Body, talker: &str, name: &str) -> core::fmt::Result {
    b.write_str(talker)?;
    b.write_str(name)?;
    b.write_char(',')
}

/// RMC: time, status, position, speed over ground (knots) and true
/// course (degrees) when `velocity` is given (else empty), date, (no
/// variation), mode, NMEA 4.1 navigational status (the integrity
/// decision).
pub fn rmc(r: &WireResult, velocity: Option<GroundVelocity>) -> Result<Sentence, TooLong> {
    let utc = Utc::from_unix_s(r.time_s);
    let mut b = Body::new();
    start(&mut b, talker(r), "RMC")?;
    time_field(&mut b, utc)?;
    b.write_char(',')?;
    b.write_char(if usable(r) { 'A' } else { 'V' })?;
    b.write_char(',')?;
    position_fields(&mut b, r)?;
    b.write_char(',')?;
    if let Some(v) = velocity {
        let (knots, deg) = v.knots_deg();
        num(&mut b, knots, 3, 7)?;
        b.write_char(',')?;
        num(&mut b, deg, 2, 6)?;
    } else {
        b.write_char(',')?;
    }
    b.write_char(',')?;
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

/// VTG: true course (degrees), no magnetic course, speed in knots and
/// km/h when `velocity` is given (else those fields empty), mode A
/// (usable) or N.
pub fn vtg(r: &WireResult, velocity: Option<GroundVelocity>) -> Result<Sentence, TooLong> {
    let mut b = Body::new();
    start(&mut b, talker(r), "VTG")?;
    match velocity {
        Some(v) => {
            let (knots, deg) = v.knots_deg();
            num(&mut b, deg, 2, 6)?;
            b.write_str(",T,,M,")?;
            num(&mut b, knots, 3, 7)?;
            b.write_str(",N,")?;
            num(&mut b, v.speed_m_s / KM_H_M_S, 3, 8)?;
            b.write_str(",K,")?;
        }
        None => b.write_str(",T,,M,,N,,K,")?,
    }
    b.write_char(if usable(r) { 'A' } else { 'N' })?;
    finish(&b)
}

/// GGA: time, position, quality (1 usable, 0 not), satellites used, HDOP,
/// altitude above mean sea level and geoid separation (module doc).
pub fn gga(r: &WireResult, dop: Option<Dops>, geoid: bool) -> Result<Sentence, TooLong> {
    let mut b = Body::new();
    start(&mut b, talker(r), "GGA")?;
    time_field(&mut b, Utc::from_unix_s(r.time_s))?;
    b.write_char(',')?;
    position_fields(&mut b, r)?;
    let used = r.satellites.iter().filter(|s| s.used).count();
    b.write_char(',')?;
    b.write_char(if usable(r) { '1' } else { '0' })?;
    b.write_char(',')?;
    fixed::uint(&mut b, used as u64, 2)?;
    b.write_char(',')?;
    if let Some(d) = dop {
        num(&mut b, d.hdop, 2, 4)?;
    }
    b.write_char(',')?;
    if let Some(g) = r.geodetic {
        let n = separation_m(&g, geoid).unwrap_or(0.0);
        num(&mut b, g.height_m - n, 3, 8)?;
        b.write_str(",M,")?;
        num(&mut b, n, 3, 6)?;
        b.write_str(",M,,")?;
    } else {
        b.write_str(",M,,M,,")?;
    }
    finish(&b)
}

/// GSA of one constellation (NMEA 4.11): automatic mode, 3D fix or none,
/// the used satellites `12 part ..` of `sys`, PDOP, HDOP, VDOP (of the
/// whole geometry, as u-blox writes them), system ID.
pub fn gsa(
    r: &WireResult,
    dop: Option<Dops>,
    sys: System,
    part: usize,
) -> Result<Sentence, TooLong> {
    let mut b = Body::new();
    start(&mut b, talker(r), "GSA")?;
    b.write_str("A,")?;
    b.write_char(if usable(r) { '3' } else { '1' })?;
    let mut used = r
        .satellites
        .iter()
        .filter(|s| s.used && s.id.system == sys)
        .skip(12 * part)
        .map(|s| nmea_svid(s.id));
    for _ in 0..12 {
        b.write_char(',')?;
        if let Some(n) = used.next() {
            fixed::uint(&mut b, u64::from(n), 2)?;
        }
    }
    for v in dop.map_or([f64::NAN; 3], |d| [d.pdop, d.hdop, d.vdop]) {
        b.write_char(',')?;
        num(&mut b, v, 2, 4)?;
    }
    b.write_char(',')?;
    fixed::uint(&mut b, u64::from(system_id(sys)), 1)?;
    finish(&b)
}

/// GSV part `part` of `parts` of constellation `sys` (`n` satellites):
/// number, elevation (deg, empty below the horizon or unknown), azimuth
/// (deg), C/N0 (dB-Hz, empty when unknown), four at a time; signal ID.
fn gsv(
    sky: &Sky,
    fr: &Frame,
    sys: System,
    n: usize,
    part: usize,
    parts: usize,
) -> Result<Sentence, TooLong> {
    let mut b = Body::new();
    start(&mut b, system_talker(sys), "GSV")?;
    fixed::uint(&mut b, parts as u64, 1)?;
    b.write_char(',')?;
    fixed::uint(&mut b, part as u64 + 1, 1)?;
    b.write_char(',')?;
    fixed::uint(&mut b, n as u64, 2)?;
    let sats = (0..sky.len())
        .filter_map(|i| Some((i, sky.id(i)?)))
        .filter(|(_, id)| id.system == sys)
        .skip(4 * part)
        .take(4);
    for (i, id) in sats {
        b.write_char(',')?;
        fixed::uint(&mut b, u64::from(nmea_svid(id)), 2)?;
        b.write_char(',')?;
        if let Some(l) = sky.los_enu(i, fr) {
            let el_deg = libm::round(raim_core::frames::elevation_rad(l).to_degrees());
            // Whole degrees in [0, 360): atan2 is within [-180, 180].
            let az_deg = (libm::round(libm::atan2(l[0], l[1]).to_degrees()) as i64).rem_euclid(360);
            if el_deg >= 0.0 {
                fixed::uint(&mut b, el_deg as u64, 2)?;
            }
            b.write_char(',')?;
            fixed::uint(&mut b, az_deg.unsigned_abs(), 3)?;
        } else {
            b.write_char(',')?;
        }
        b.write_char(',')?;
        let cn0 = sky.cn0_dbhz.get(i).copied().unwrap_or(0);
        if (1..=99).contains(&cn0) {
            fixed::uint(&mut b, u64::from(cn0), 2)?;
        }
    }
    b.write_char(',')?;
    fixed::uint(&mut b, u64::from(signal_id(sys)), 1)?;
    finish(&b)
}

/// GST: time, range rms, error ellipse, 1-sigma lat/lon/alt errors (m).
pub fn gst(r: &WireResult) -> Result<Sentence, TooLong> {
    let [e, n, u] = r.sigma_enu_m;
    let mut b = Body::new();
    start(&mut b, talker(r), "GST")?;
    time_field(&mut b, Utc::from_unix_s(r.time_s))?;
    b.write_char(',')?;
    num(&mut b, range_rms_m(r), 3, 8)?;
    let (smaj, smin, orient_deg) = if n >= e { (n, e, 0.0) } else { (e, n, 90.0) };
    for (v, p, width) in [
        (smaj, 3, 8),
        (smin, 3, 8),
        (orient_deg, 1, 4),
        (n, 3, 8),
        (e, 3, 8),
        (u, 3, 8),
    ] {
        b.write_char(',')?;
        num(&mut b, v, p, width)?;
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

/// GBS (NMEA 4.11): time, 1-sigma lat/lon/alt errors, the most likely
/// failed satellite, its probability of missed detection, its bias and the
/// bias's sigma, its system and signal IDs.
pub fn gbs(r: &WireResult) -> Result<Sentence, TooLong> {
    let [e, n, u] = r.sigma_enu_m;
    let mut b = Body::new();
    start(&mut b, talker(r), "GBS")?;
    time_field(&mut b, Utc::from_unix_s(r.time_s))?;
    for v in [n, e, u] {
        b.write_char(',')?;
        num(&mut b, v, 3, 8)?;
    }
    match gbs_satellite(r) {
        Some((s, bias_m)) => {
            let t = r.initial_test;
            let pmd = dist::ncx2_cdf(t.threshold, t.dof, s.w * s.w).unwrap_or(f64::NAN);
            b.write_char(',')?;
            fixed::uint(&mut b, u64::from(nmea_svid(s.id)), 2)?;
            b.write_char(',')?;
            num(&mut b, pmd, 6, 8)?;
            b.write_char(',')?;
            num(&mut b, bias_m, 3, 8)?;
            b.write_char(',')?;
            num(&mut b, s.sigma_m / libm::sqrt(s.s_ii), 3, 7)?;
            b.write_char(',')?;
            fixed::uint(&mut b, u64::from(system_id(s.id.system)), 1)?;
            b.write_char(',')?;
            fixed::uint(&mut b, u64::from(signal_id(s.id.system)), 1)?;
        }
        None => b.write_str(",,,,,,")?,
    }
    finish(&b)
}

/// ZDA: time, day, month, four-digit year, local zone 00:00.
pub fn zda(r: &WireResult) -> Result<Sentence, TooLong> {
    let utc = Utc::from_unix_s(r.time_s);
    let mut b = Body::new();
    start(&mut b, talker(r), "ZDA")?;
    time_field(&mut b, utc)?;
    match utc {
        Some(u) => {
            let (y, m, d) = civil_from_days(u.days);
            b.write_char(',')?;
            fixed::uint(&mut b, u64::from(d), 2)?;
            b.write_char(',')?;
            fixed::uint(&mut b, u64::from(m), 2)?;
            b.write_char(',')?;
            if y < 0 {
                b.write_char('-')?;
            }
            fixed::uint(&mut b, y.unsigned_abs(), 4)?;
            b.write_str(",00,00")?;
        }
        None => b.write_str(",,,,,")?,
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

    /// Eight GPS satellites (seed 000's sky) with 1 m sigmas, residuals of
    /// about 1 sigma and a `step_m` bias on G02; processed and in wire form.
    fn sky8_result(step_m: f64) -> (WireResult, std::vec::Vec<LinearObservation>) {
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
        (WireResult::from_result(&r), sats)
    }

    /// This build's sentences without the geoid.
    const NO_GEOID: Options = Options {
        geoid: false,
        sky: true,
    };

    /// The sentences of `w` for the linear epoch `sats` (no geoid).
    fn sentences(w: &WireResult, sats: &[LinearObservation]) -> std::vec::Vec<String> {
        let e = Epoch::linear(w.time_s, sats);
        let all = epoch_sentences(w, &Sky::new(&e), NO_GEOID).unwrap();
        all.iter().map(|s| String::from(s.as_str())).collect()
    }

    /// The fields of the first sentence of kind `kind` (e.g. "GBS").
    fn find(all: &[String], kind: &str) -> std::vec::Vec<String> {
        let s = all
            .iter()
            .find(|s| &s[3..6] == kind)
            .unwrap_or_else(|| panic!("no {kind} in {all:?}"));
        parse(s).0.split(',').map(String::from).collect()
    }

    fn kinds(all: &[String]) -> std::vec::Vec<&str> {
        all.iter().map(|s| &s[3..6]).collect()
    }

    fn checked(all: &[String]) {
        for s in all {
            assert!(s.len() <= 82, "{} chars: {s}", s.len());
            let (body, cs) = parse(s);
            assert_eq!(checksum(body.as_bytes()), cs, "{s}");
        }
    }

    /// Verifies: SPEC-11, NMEA-FORMAT
    #[test]
    fn sentences_are_checksummed_ordered_and_carry_the_raim_fields() {
        let (mut w, sats) = sky8_result(50.0);
        w.geodetic = Some(Geodetic {
            lat_rad: 0.5,
            lon_rad: -1.2,
            height_m: 123.4567,
        });
        let all = sentences(&w, &sats);
        assert_eq!(
            kinds(&all),
            ["RMC", "VTG", "GGA", "GSA", "GSV", "GSV", "GST", "GBS", "ZDA"]
        );
        checked(&all);
        let f = find(&all, "GBS");
        assert_eq!(f.len(), 11, "{f:?}");
        assert_eq!(f[1], "000000.50");
        let [e, n, u] = w.sigma_enu_m;
        let close = |s: &str, v: f64| (s.parse::<f64>().unwrap() - v).abs() <= 0.0005;
        assert!(
            close(&f[2], n) && close(&f[3], e) && close(&f[4], u),
            "{f:?}"
        );
        // The excluded satellite G02 is the most likely failed one; its bias
        // is the 50 m step within 5 sigma of the estimate's noise.
        assert_eq!(f[5], "02");
        let s = w.satellites[1];
        let sd = 1.0 / s.s_ii.sqrt();
        assert!(close(&f[8], sd), "{f:?}");
        assert!(
            (f[7].parse::<f64>().unwrap() - 50.0).abs() < 5.0 * sd,
            "{f:?}"
        );
        // A 50 m bias on this satellite is far above the detection
        // threshold: the test cannot miss it. GPS, L1 C/A.
        assert!(f[6].parse::<f64>().unwrap() < 1e-6, "{f:?}");
        assert_eq!((f[9].as_str(), f[10].as_str()), ("1", "1"));
        // Excluded: the fix is valid and safe; GSA lists the 7 used
        // satellites, the DOPs of that geometry and system ID 1.
        assert!(all[0].contains(",A,S*"), "{}", all[0]);
        let gsa = find(&all, "GSA");
        assert_eq!(gsa[..15].join(","), "GPGSA,A,3,01,03,04,05,06,07,08,,,,,");
        assert_eq!(gsa[18], "1");
        let gga = find(&all, "GGA");
        assert_eq!(gga[7], "07");
        assert_eq!(gga[8], gsa[16], "GGA HDOP is GSA's");
        assert_eq!(gga[9..].join(","), "123.457,M,0.000,M,,");
        // GSV: all 8 satellites seen, 4 a sentence, el/az of the sky (the
        // excluded G02 included), C/N0 unknown; signal ID 1.
        let gsv = find(&all, "GSV");
        assert_eq!(gsv[..4].join(","), "GPGSV,2,1,08");
        assert_eq!(gsv[4..12].join(","), "01,85,000,,02,30,045,");
        assert_eq!(gsv[20], "1");
        assert_eq!(find(&all, "VTG").join(","), "GPVTG,,T,,M,,N,,K,A");
        assert_eq!(
            find(&all, "ZDA").join(","),
            "GPZDA,000000.50,29,02,2024,00,00"
        );
    }

    /// The inverse of a small dense matrix by Gauss-Jordan elimination
    /// (the test's own reference for the DOPs).
    fn inverse(mut a: std::vec::Vec<std::vec::Vec<f64>>) -> std::vec::Vec<std::vec::Vec<f64>> {
        let n = a.len();
        for (i, row) in a.iter_mut().enumerate() {
            row.extend((0..n).map(|j| f64::from(u8::from(i == j))));
        }
        for c in 0..n {
            let p = (c..n)
                .max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))
                .unwrap();
            a.swap(c, p);
            let d = a[c][c];
            a[c].iter_mut().for_each(|v| *v /= d);
            for r in 0..n {
                if r != c {
                    let f = a[r][c];
                    let pivot = a[c].clone();
                    a[r].iter_mut().zip(pivot).for_each(|(v, p)| *v -= f * p);
                }
            }
        }
        a.into_iter().map(|r| r[n..].to_vec()).collect()
    }

    /// G+E+C: one GSA per constellation with its system ID, one GSV set per
    /// constellation with its talker, and DOPs equal to those of the
    /// geometry (three clock columns) computed independently.
    #[test]
    fn multi_constellation_gsa_gsv_and_dops() {
        let mut sats = std::vec::Vec::new();
        for (k, sys) in [System::Gps, System::Galileo, System::Beidou]
            .iter()
            .enumerate()
        {
            for j in 0..5 {
                let az = (72.0 * j as f64 + 25.0 * k as f64).to_radians();
                let el = (15.0 + 14.0 * j as f64 + 3.0 * k as f64).to_radians();
                let mut o =
                    LinearObservation::from_az_el(SatId::new(*sys, 3 + j as u8), az, el, 0.1);
                o.sigma_m = Some(1.0 + j as f64);
                sats.push(o);
            }
        }
        let r = Raim::<32>::new()
            .process(&Config::default(), &Epoch::linear(1_709_164_800.0, &sats))
            .unwrap();
        let w = WireResult::from_result(&r);
        let all = sentences(&w, &sats);
        checked(&all);
        let gsa: std::vec::Vec<_> = all.iter().filter(|s| &s[3..6] == "GSA").collect();
        assert_eq!(gsa.len(), 3, "{all:?}");
        for (s, (id, first)) in gsa.iter().zip([("1", "03"), ("3", "03"), ("4", "03")]) {
            let f: std::vec::Vec<&str> = parse(s).0.leak().split(',').collect();
            assert_eq!((f[0], f[3], f[18]), ("GNGSA", first, id), "{s}");
        }
        let talkers: std::vec::Vec<&str> = all
            .iter()
            .filter(|s| &s[3..6] == "GSV")
            .map(|s| &s[1..3])
            .collect();
        assert_eq!(talkers, ["GP", "GP", "GA", "GA", "GB", "GB"]);
        // Reference DOPs: (G^T G)^-1 with rows [e, n, u, clock one-hot].
        let g: std::vec::Vec<[f64; 6]> = sats
            .iter()
            .map(|o| {
                let k = match o.id.system {
                    System::Gps => 3,
                    System::Galileo => 4,
                    _ => 5,
                };
                let mut row = [0.0; 6];
                row[..3].copy_from_slice(&o.los_enu);
                row[k] = 1.0;
                row
            })
            .collect();
        let a = (0..6)
            .map(|i| {
                (0..6)
                    .map(|j| g.iter().map(|r| r[i] * r[j]).sum())
                    .collect()
            })
            .collect();
        let q = inverse(a);
        let want = [
            (q[0][0] + q[1][1] + q[2][2]).sqrt(),
            (q[0][0] + q[1][1]).sqrt(),
            q[2][2].sqrt(),
        ];
        let f = find(&all, "GSA");
        for (k, want) in want.iter().enumerate() {
            let got: f64 = f[15 + k].parse().unwrap();
            assert!(
                (got - want).abs() <= 0.005 + 1e-12,
                "DOP {k}: {got} vs {want}"
            );
        }
        let d = dops(&w, &Sky::new(&Epoch::linear(0.0, &sats))).unwrap();
        assert!((d.pdop - want[0]).abs() < 1e-9 && (d.vdop - want[2]).abs() < 1e-9);
    }

    /// NMEA 4.11 numbers a satellite within its system ID: the ends of each
    /// system's range, and GSA/GSV/GBS of a G+R+E+C+J epoch carry those
    /// numbers under the system's ID (GSA field 18) or talker (GSV).
    ///
    /// Verifies: NMEA-NUMBERING
    #[test]
    fn satellite_numbers_are_nmea_4_11_within_the_system_id() {
        for (sys, prn, svid) in [
            (System::Gps, 1, 1),
            (System::Gps, 32, 32),
            (System::Glonass, 1, 65),
            (System::Glonass, 24, 88),
            (System::Galileo, 1, 1),
            (System::Galileo, 36, 36),
            (System::Beidou, 1, 1),
            (System::Beidou, 63, 63),
            (System::Qzss, 1, 1),
            (System::Qzss, 10, 10),
        ] {
            assert_eq!(nmea_svid(SatId::new(sys, prn)), svid, "{sys:?} {prn}");
        }
        let systems = [
            (System::Gps, 7, "1", "GP"),
            (System::Glonass, 7, "2", "GL"),
            (System::Galileo, 36, "3", "GA"),
            (System::Beidou, 59, "4", "GB"),
            (System::Qzss, 2, "5", "GQ"),
        ];
        let mut sats = std::vec::Vec::new();
        for (k, (sys, prn, _, _)) in systems.iter().enumerate() {
            for j in 0..2u8 {
                let az = (40.0 * f64::from(j) + 71.0 * k as f64).to_radians();
                let el = (20.0 + 25.0 * f64::from(j) + 4.0 * k as f64).to_radians();
                sats.push(LinearObservation::from_az_el(
                    SatId::new(*sys, prn - j),
                    az,
                    el,
                    0.1,
                ));
            }
        }
        let r = Raim::<32>::new()
            .process(&Config::default(), &Epoch::linear(1_709_164_800.0, &sats))
            .unwrap();
        let w = WireResult::from_result(&r);
        let all = sentences(&w, &sats);
        checked(&all);
        for (sys, prn, id, talker) in systems {
            let (a, b) = (
                std::format!("{:02}", nmea_svid(SatId::new(sys, prn))),
                std::format!("{:02}", nmea_svid(SatId::new(sys, prn - 1))),
            );
            let used: std::vec::Vec<String> = all
                .iter()
                .map(|s| parse(s).0)
                .filter(|b| b.starts_with("GNGSA") && b.split(',').nth(18) == Some(id))
                .flat_map(|b| {
                    let f: std::vec::Vec<String> = b.split(',').map(String::from).collect();
                    f[3..15].to_vec()
                })
                .filter(|f| !f.is_empty())
                .collect();
            assert_eq!(used, [a.clone(), b.clone()], "{sys:?} {all:?}");
            let seen: std::vec::Vec<String> = all
                .iter()
                .map(|s| parse(s).0)
                .filter(|b| b.starts_with(talker) && &b[2..5] == "GSV")
                .flat_map(|b| {
                    let f: std::vec::Vec<String> = b.split(',').map(String::from).collect();
                    [f[4].clone(), f[8].clone()]
                })
                .collect();
            assert_eq!(seen, [a, b], "{sys:?} {all:?}");
        }
    }

    /// Every epoch writes every sentence whatever its values: sigmas of
    /// 1e5 m and 1e30 m, and non-finite ones, give fields that fit or are
    /// empty, never a sentence over 82 characters or a missing one.
    ///
    /// Verifies: SAFE-T9, NMEA-FORMAT
    #[test]
    fn extreme_values_keep_every_sentence_within_82_characters() {
        for sigma_m in [1e5, 1e30, f64::INFINITY] {
            let (mut w, mut sats) = sky8_result(0.0);
            for o in sats.iter_mut() {
                o.sigma_m = Some(sigma_m);
            }
            // The core refuses such sigmas on input (`SigmaOutOfRange`);
            // the writer must still cope with any value a result carries.
            w.sigma_enu_m = [sigma_m; 3];
            w.hpl_m = sigma_m;
            w.vpl_m = sigma_m;
            w.geodetic = Some(Geodetic {
                lat_rad: -0.5,
                lon_rad: 3.0,
                height_m: -sigma_m,
            });
            w.time_s = 1e12;
            for s in w.satellites.iter_mut() {
                s.bias_m = -sigma_m;
                s.sigma_m = sigma_m;
            }
            let all = sentences(&w, &sats);
            assert_eq!(
                kinds(&all),
                ["RMC", "VTG", "GGA", "GSA", "GSV", "GSV", "GST", "GBS", "ZDA"],
                "sigma {sigma_m}"
            );
            checked(&all);
            let gbs = find(&all, "GBS");
            let gst = find(&all, "GST");
            if sigma_m == 1e5 {
                // Shown, with fewer decimals.
                let v: f64 = gbs[2].parse().unwrap();
                assert!((v / w.sigma_enu_m[1] - 1.0).abs() < 1e-3, "{gbs:?}");
                assert!(!gst[8].is_empty(), "{gst:?}");
            } else {
                assert!(gbs[2].is_empty() && gst[8].is_empty(), "{gbs:?} {gst:?}");
            }
        }
    }

    /// RMC and VTG with a velocity: RMC fields 7-8 the speed in knots (3
    /// decimals) and the true course in degrees (2 decimals), VTG fields
    /// 1, 5 and 7 the course, knots and km/h (magnetic course empty); the
    /// course in [0, 360) from any angle (a course rounding to 360.00 is
    /// 0.00); without a velocity (the caller gives none for an epoch
    /// that is not a valid fix) those fields empty; extreme speeds keep
    /// the sentences within 82 characters, the field empty when it cannot
    /// show them.
    ///
    /// Verifies: NMEA-VELOCITY, NMEA-FORMAT
    #[test]
    fn rmc_and_vtg_carry_speed_and_course() {
        let (mut w, _) = sky8_result(0.0);
        w.geodetic = Some(Geodetic {
            lat_rad: 0.84,
            lon_rad: 0.2,
            height_m: 100.0,
        });
        let with = |speed_m_s: f64, course_rad: f64| {
            let v = Some(GroundVelocity {
                speed_m_s,
                course_rad,
            });
            let (rmc, vtg) = (rmc(&w, v).unwrap(), vtg(&w, v).unwrap());
            assert!(rmc.len() <= 82 && vtg.len() <= 82);
            let f = |s: &Sentence| -> std::vec::Vec<String> {
                parse(s).0.split(',').map(String::from).collect()
            };
            (f(&rmc), f(&vtg))
        };
        // 12.3 m/s toward 45 degrees: 23.909 knots, 44.28 km/h.
        let (r, v) = with(12.3, 45f64.to_radians());
        assert_eq!((r[7].as_str(), r[8].as_str()), ("23.909", "45.00"));
        assert_eq!(v[1..].join(","), "45.00,T,,M,23.909,N,44.280,K,A", "{v:?}");
        // A negative angle and one past a turn.
        let (r, _) = with(1.0, -90f64.to_radians());
        assert_eq!(r[8], "270.00");
        let (r, _) = with(1.0, 450f64.to_radians());
        assert_eq!(r[8], "90.00");
        let (r, _) = with(0.0, -1e-9);
        assert_eq!((r[7].as_str(), r[8].as_str()), ("0.000", "0.00"));
        // Extreme values: fewer decimals, or empty.
        let (r, v) = with(1e5, 1.0);
        assert_eq!(r[7], "194384");
        assert_eq!(v[7], "360000.0");
        let (r, v) = with(1e30, f64::NAN);
        assert!(r[7].is_empty() && r[8].is_empty() && v[1].is_empty() && v[7].is_empty());
        // Without a velocity: empty, as before.
        assert_eq!(parse(&vtg(&w, None).unwrap()).0, "GPVTG,,T,,M,,N,,K,A");
        let r = parse(&rmc(&w, None).unwrap()).0;
        assert_eq!(r.split(',').nth(7), Some(""));
        assert_eq!(r.split(',').nth(8), Some(""));
        // The whole epoch through `write_epoch` with the velocity in `Sky`.
        let sats: std::vec::Vec<LinearObservation> = std::vec::Vec::new();
        let e = Epoch::linear(w.time_s, &sats);
        let sky = Sky {
            epoch: &e,
            cn0_dbhz: &[],
            velocity: Some(GroundVelocity {
                speed_m_s: 12.3,
                course_rad: 45f64.to_radians(),
            }),
        };
        let all = epoch_sentences(&w, &sky, NO_GEOID).unwrap();
        if cfg!(feature = "nmea-velocity") {
            assert!(all[0].contains(",23.909,45.00,"), "{:?}", all[0]);
            assert!(
                all[1].contains("45.00,T,,M,23.909,N,44.280,K,A"),
                "{:?}",
                all[1]
            );
        } else {
            assert!(all[1].contains(",T,,M,,N,,K,A"), "{:?}", all[1]);
        }
    }

    /// Verifies: NMEA-FORMAT
    #[test]
    fn numbers_fit_their_width_or_are_empty() {
        let cases: [(f64, u32, usize, &str); 8] = [
            (1.23456, 3, 8, "1.235"),
            (12345.678, 3, 8, "12345.68"),
            (123456.7, 3, 8, "123456.7"),
            (99999999.6, 3, 8, ""),
            (1e30, 3, 8, ""),
            (-1234567.0, 3, 8, "-1234567"),
            (f64::NAN, 3, 8, ""),
            (99.996, 2, 4, "100"),
        ];
        for (v, p, width, want) in cases {
            let mut s = String::new();
            num(&mut s, v, p, width).unwrap();
            assert_eq!(s, want, "{v} {p} {width}");
        }
    }

    #[test]
    fn no_fault_gbs_pmd_is_large_and_linear_epochs_have_no_position() {
        let (w, sats) = sky8_result(0.0);
        let all = sentences(&w, &sats);
        let f = find(&all, "GBS");
        // Residuals of about 1 sigma: a bias that small is almost surely missed.
        assert!(f[6].parse::<f64>().unwrap() > 0.9, "{f:?}");
        assert_eq!(
            find(&all, "RMC").join(","),
            "GPRMC,000000.50,V,,,,,,,290224,,,N,V"
        );
    }

    /// Only `Ok` and `Excluded` are a valid fix. `Unavailable` and `Alarm`
    /// give RMC status V and mode N, VTG mode N, GGA quality 0 and GSA fix
    /// 1, with the integrity decision in RMC's navigational status; GBS
    /// names the excluded satellite while its exclusion is in force.
    ///
    /// Verifies: SAFE-T9
    #[test]
    fn unavailable_and_alarm_epochs_are_not_a_valid_fix() {
        let (mut w, sats) = sky8_result(50.0);
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
            let all = sentences(&w, &sats);
            let (rmc, gga, gsa, gbs, vtg) = (
                find(&all, "RMC"),
                find(&all, "GGA"),
                find(&all, "GSA"),
                find(&all, "GBS"),
                find(&all, "VTG"),
            );
            let want = |a: &str, b: &str| String::from(if valid { a } else { b });
            assert_eq!(rmc[2], want("A", "V"), "{decision:?} {rmc:?}");
            assert_eq!(rmc[12], want("A", "N"), "{decision:?} {rmc:?}");
            assert_eq!(rmc[13], nav, "{decision:?} {rmc:?}");
            assert_eq!(gga[6], want("1", "0"), "{decision:?} {gga:?}");
            assert_eq!(gsa[2], want("3", "1"), "{decision:?} {gsa:?}");
            assert_eq!(vtg[9], want("A", "N"), "{decision:?} {vtg:?}");
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
        let all = sentences(&w, &sats);
        let rmc = find(&all, "RMC");
        assert_eq!(
            (rmc[2].as_str(), rmc[12].as_str(), rmc[13].as_str()),
            ("V", "N", "C")
        );
        assert_eq!(find(&all, "GGA")[6], "0");
    }

    /// With the geoid, GGA's altitude is h - N and its separation N.
    ///
    /// Verifies: NMEA-ALT
    #[cfg(feature = "geoid")]
    #[test]
    fn gga_altitude_is_above_mean_sea_level() {
        let (mut w, sats) = sky8_result(0.0);
        let g = raim_core::frames::ecef_to_geodetic([-3976219.5082, 3382372.5671, 3652512.9849]);
        w.geodetic = Some(g);
        let e = Epoch::linear(w.time_s, &sats);
        let all = epoch_sentences(&w, &Sky::new(&e), BUILT).unwrap();
        let gga: std::vec::Vec<String> = parse(&all[2]).0.split(',').map(String::from).collect();
        let n = geoid::separation_m(g.lat_rad, g.lon_rad).unwrap();
        let (alt, sep): (f64, f64) = (gga[9].parse().unwrap(), gga[11].parse().unwrap());
        assert!(
            (sep - n).abs() <= 0.0005 && (alt + sep - g.height_m).abs() <= 0.001,
            "{gga:?}"
        );
    }
}
