//! From a satellite's raw pseudorange to the core's input (SPEC §1, §11):
//! the broadcast orbit and clock at transmit time, the Earth-rotation
//! correction, Klobuchar, Saastamoinen and the group delay, or the
//! iono-free combination of two codes; then the elevation mask. The result
//! is a `raim_core::RangeObservation` whose pseudorange is fully corrected
//! and whose position is in the ECEF frame of the reception time, as the
//! core expects (docs/CORE.md).
//!
//! This is the one implementation: the host's RINEX and receiver-stream
//! replays (raim-gnss) and the firmware's own epochs from a receiver's
//! RTCM 3 stream ([`crate::rtcm`]) both call [`correct`] and
//! [`bootstrap_position`] ([`crate::bootstrap`]), so that they form the
//! same bits.

use raim_core::araim::error_model::{iono_free_factor_sq, Curves};
use raim_core::frames::{bowring_latitude_rad, ecef_to_geodetic_from, enu_rotation, Geodetic};
use raim_core::sigma::SigmaModel;
use raim_core::{RangeObservation, Real, SatId, System};

use crate::arc::transmit_state_motion_on_arc;
use crate::ephemeris::{Kepler, Orbit, SatState, C_M_S, WEEK_S};
use crate::geometry::{az_el_rotated, distance_m, elevation_rotated, rotate_earth};
use crate::glonass::{l1_hz, l2_hz, GlonassEphemeris, F_L1_BASE_HZ, F_L2_BASE_HZ};
use crate::iono::{scale_to_frequency, Klobuchar, F_B1I_HZ, F_L1_HZ};
use crate::m;
use crate::tropo::SaastamoinenSite;
use crate::velocity::SatMotion;

pub use crate::bootstrap::{bootstrap_position, SURFACE_BAND_M};

/// The broadcast ephemeris selected for one satellite: Keplerian elements
/// (GPS, Galileo, BeiDou, QZSS), alone or with their orbit's constants
/// ([`Orbit`], kept by the device's receiver across epochs: the same
/// bits, computed once), or a GLONASS state vector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Broadcast<'a> {
    Kepler(&'a Kepler),
    Orbit(&'a Orbit),
    Glonass(&'a GlonassEphemeris),
}

impl Broadcast<'_> {
    /// Position (WGS-84, Earth-fixed frame of the instant) and clock at GPS
    /// time `t_gps_s`.
    pub fn state(&self, t_gps_s: f64) -> SatState {
        match self {
            Broadcast::Kepler(k) => k.state(t_gps_s),
            Broadcast::Orbit(o) => o.state(t_gps_s),
            Broadcast::Glonass(g) => g.state(t_gps_s),
        }
    }

    /// Satellite clock at GPS time `t_gps_s`, s: [`Self::state`]'s clock to
    /// the bit, without the orbit ([`Kepler::clock_s`]; a GLONASS clock is
    /// a polynomial of t - t_b alone).
    pub fn clock_s(&self, t_gps_s: f64) -> f64 {
        match self {
            Broadcast::Kepler(k) => k.clock_s(t_gps_s),
            Broadcast::Orbit(o) => o.set.clock_s(t_gps_s),
            Broadcast::Glonass(g) => g.clock_s(t_gps_s),
        }
    }

    /// The Keplerian ephemeris, if this is one (its group delays).
    pub fn kepler(&self) -> Option<&Kepler> {
        match self {
            Broadcast::Kepler(k) => Some(k),
            Broadcast::Orbit(o) => Some(&o.set),
            Broadcast::Glonass(_) => None,
        }
    }

    /// The GLONASS frequency channel, if this is a GLONASS ephemeris.
    pub fn frequency_channel(&self) -> Option<i8> {
        match self {
            Broadcast::Kepler(_) | Broadcast::Orbit(_) => None,
            Broadcast::Glonass(g) => Some(g.frequency_channel),
        }
    }
}

/// Which corrections to apply.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Corrections {
    pub elevation_mask_rad: f64,
    pub iono: bool,
    pub tropo: bool,
    pub group_delay: bool,
    /// The sigma model of GLONASS satellites (SPEC §3's model with its own
    /// URA, [`crate::glonass::glonass_ura_m`]): each gets an explicit
    /// `sigma_m` = this model at its elevation. None: the core's model, as
    /// for every other system.
    pub glonass_sigma: Option<SigmaModel>,
}

/// Why a satellite of the epoch was not used.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rejection {
    SystemNotSelected,
    NoCode,
    NoEphemeris,
    BelowMask { elevation_rad: f64 },
}

/// One satellite's measurement and ephemeris, before any correction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SatInput<'a> {
    pub id: SatId,
    /// RINEX 3 code ("C1C"), or a pair "C1C+C2W" for the iono-free
    /// combination (higher frequency first).
    pub code: &'a str,
    /// The code's pseudorange (the first code's for a pair), m.
    pub p1_m: f64,
    /// The second code's pseudorange for a pair, m.
    pub p2_m: Option<f64>,
    pub eph: Broadcast<'a>,
    /// A Keplerian satellite's transmit state on its orbit arc
    /// ([`crate::arc`]: the cubic Hermite interpolant between exact states
    /// 30 s apart, within 1 mm of the orbit), as a receiver stream's
    /// readers take it, so that the host's and the unit's form the same
    /// bits; false, the exact orbit (a RINEX replay's).
    pub orbit_arc: bool,
}

/// One satellite ready for the core, with the terms that went into it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Corrected {
    /// Corrected pseudorange and rotated satellite position.
    pub obs: RangeObservation,
    /// The pseudorange before corrections (the combination's for a pair), m.
    pub raw_pseudorange_m: f64,
    pub elevation_rad: f64,
    pub azimuth_rad: f64,
    /// c x satellite clock (polynomial + relativity), m; added.
    pub sat_clock_m: f64,
    /// c x group delay, m; subtracted.
    pub group_delay_m: f64,
    /// Klobuchar slant delay at the signal's frequency, m; subtracted.
    pub iono_m: f64,
    /// Saastamoinen slant delay, m; subtracted.
    pub tropo_m: f64,
}

/// What the corrections of one epoch take from the receiver position
/// alone: its geodetic coordinates (ten f64 latitude iterations), its
/// local-level (ENU) rotation (four sines and cosines) and its
/// troposphere's zenith delays ([`SaastamoinenSite`]). Computed once per
/// epoch for every satellite ([`correct_at`]), or per satellite by
/// [`correct`]; the same bits either way.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReceiverFrame {
    pub geodetic: Geodetic,
    /// ECEF to ENU at the receiver (`raim_core::frames::enu_rotation`).
    rotation: nalgebra::Matrix3<f64>,
    pub tropo: SaastamoinenSite,
}

impl ReceiverFrame {
    /// The frame of a receiver at ECEF `rx_m`: its geodetic position by
    /// raim-core's latitude iteration from Bowring's closed form, which
    /// stops at the iteration's tolerance (1e-10 rad per step, within
    /// ~1e-12 rad of the fixed point) after one or two steps instead of
    /// ten (each a sine, a cosine, a square root and an arctangent in
    /// soft-float f64 on the M4).
    pub fn at(rx_m: [f64; 3]) -> Self {
        let geodetic = ecef_to_geodetic_from(rx_m, bowring_latitude_rad(rx_m));
        ReceiverFrame {
            geodetic,
            rotation: enu_rotation(&geodetic),
            tropo: SaastamoinenSite::at(geodetic.lat_rad, geodetic.height_m),
        }
    }
}

/// Carrier frequency (Hz) of a RINEX 3 code's band digit, per system; None
/// for a band this crate does not know. GLONASS FDMA: the channel-0
/// carriers (L2/L1 = 7/9 for every channel, so the iono-free combination
/// does not depend on the channel).
pub fn band_hz(system: System, code: &str) -> Option<f64> {
    let band = code.get(1..2)?;
    Some(match (system, band) {
        (System::Gps | System::Qzss, "1") | (System::Galileo, "1") => 1_575.42e6,
        (System::Gps | System::Qzss, "2") => 1_227.60e6,
        (System::Gps | System::Qzss, "5") | (System::Galileo, "5") => 1_176.45e6,
        (System::Galileo, "7") | (System::Beidou, "7") => 1_207.14e6,
        (System::Galileo, "8") => 1_191.795e6,
        (System::Galileo, "6") => 1_278.75e6,
        (System::Beidou, "2") | (System::Beidou, "1") => F_B1I_HZ,
        (System::Beidou, "6") => 1_268.52e6,
        (System::Glonass, "1") => F_L1_BASE_HZ,
        (System::Glonass, "2") => F_L2_BASE_HZ,
        _ => return None,
    })
}

/// A dual-frequency code pair "C1W+C2W": the two codes.
pub fn split_pair(code: &str) -> Option<(&str, &str)> {
    code.split_once('+')
}

/// The iono-free combination's noise amplification sqrt(g^2 + 1) / (g - 1),
/// g = (f1 / f2)^2, for equal noise on both codes (2.59 for L1/L5 and
/// E1/E5a, 2.98 for L1/L2, 3.53 for B1I/B3I); None for a single code.
pub fn iono_free_noise_factor(system: System, code: &str) -> Option<f64> {
    let (a, b) = split_pair(code)?;
    let r = band_hz(system, a)? / band_hz(system, b)?;
    let g = r * r;
    Some(m::sqrt(g * g + 1.0) / (g - 1.0))
}

/// The iono-free pseudorange of a code pair and the group delay (m,
/// subtracted like the single-frequency TGD/BGD) that refers it to the
/// broadcast clock:
/// - GPS/QZSS: the LNAV clock is the L1/L2 P(Y) combination's, so C1W+C2W
///   needs none (other GPS pairs: none applied either; the inter-signal
///   corrections of CNAV are not in the navigation file).
/// - Galileo with the I/NAV clock (the E1/E5b combination's): a pair
///   E1 + E5a gets c (BGD(E1,E5b) - BGD(E1,E5a)) (the E1 clock
///   dt - BGD(E1,E5b) = dt' - BGD(E1,E5a) solved for the E1/E5a clock dt');
///   E1 + E5b none.
/// - BeiDou (clock of B3I): B1I + B3I gets c g / (g - 1) TGD1.
/// - GLONASS (`k` None): none (tau_n refers to L1; the L1/L2 delay
///   Delta tau_n is not in RINEX 3 navigation files).
///
/// The first code must be the higher frequency. None if a band is unknown.
pub fn iono_free(
    system: System,
    code: &str,
    p1: f64,
    p2: f64,
    k: Option<&Kepler>,
) -> Option<(f64, f64)> {
    let (a, b) = split_pair(code)?;
    let (f1, f2) = (band_hz(system, a)?, band_hz(system, b)?);
    let r = f1 / f2;
    let g = r * r;
    if g.is_nan() || g <= 1.0 {
        return None;
    }
    let p = (g * p1 - p2) / (g - 1.0);
    let delay_s = match (system, b.get(1..2), k) {
        (System::Galileo, Some("5"), Some(k)) => k.group_delay_s - k.group_delay_e5a_s,
        (System::Beidou, Some("6"), Some(k)) => g / (g - 1.0) * k.group_delay_s,
        _ => 0.0,
    };
    Some((p, C_M_S * delay_s))
}

/// Carrier frequency of a code, for the ionospheric scaling; GLONASS by
/// the satellite's frequency channel `k`.
pub fn carrier_hz(system: System, code: &str, k: Option<i8>) -> f64 {
    match (system, code.get(1..2)) {
        (System::Glonass, Some("2")) => l2_hz(k.unwrap_or(0)),
        (System::Glonass, _) => l1_hz(k.unwrap_or(0)),
        (System::Beidou, Some("2")) | (System::Beidou, Some("1")) if code.ends_with('I') => {
            F_B1I_HZ
        }
        _ => F_L1_HZ,
    }
}

/// Group delay applies to the codes the broadcast value is defined for:
/// GPS/QZSS L1 C/A (TGD), Galileo E1 (BGD E1/E5b), BeiDou B1I (TGD1).
fn group_delay_applies(system: System, code: &str) -> bool {
    match system {
        System::Gps | System::Qzss => code == "C1C" || code == "C1",
        System::Galileo => code.starts_with("C1"),
        System::Beidou => code == "C2I" || code == "C1I",
        System::Glonass => false,
    }
}

/// The pseudorange the satellite's transmit time is taken from (the
/// code's, or the iono-free pair's) and, for a pair, the combination and
/// its group delay ([`iono_free`]).
#[allow(clippy::type_complexity)]
fn ranging_pseudorange(s: &SatInput<'_>) -> Result<(f64, Option<(f64, f64)>), Rejection> {
    let pair = match s.p2_m {
        Some(p2) => Some(
            iono_free(s.id.system, s.code, s.p1_m, p2, s.eph.kepler()).ok_or(Rejection::NoCode)?,
        ),
        None => None,
    };
    Ok((pair.map_or(s.p1_m, |v| v.0), pair))
}

/// GPS time at which the signal of `s` received at `t_rx_gps_s` left the
/// satellite: t_rx - P/c - dt_sv (exact whatever the receiver clock: P
/// holds it), or why `s` cannot be used (an iono-free pair of unknown
/// bands). The satellite's state there is `s.eph.state(t)`, which
/// [`correct_at`] takes.
pub fn transmit_time_s(s: &SatInput<'_>, t_rx_gps_s: f64) -> Result<f64, Rejection> {
    let (p, _) = ranging_pseudorange(s)?;
    let t_sv = t_rx_gps_s - p / C_M_S;
    Ok(t_sv - s.eph.clock_s(t_sv))
}

/// The state of `s`'s satellite at the transmit time of its signal
/// received at `t_rx_gps_s`: a Keplerian orbit on its arc
/// ([`crate::arc`], a stream's: [`SatInput::orbit_arc`]) or by
/// [`Orbit::transmit_state`] (the transmit time's eccentric anomaly one
/// Newton step from the clock's), a GLONASS orbit integrated there
/// ([`transmit_time_s`]).
pub fn transmit_state(s: &SatInput<'_>, t_rx_gps_s: f64) -> Result<SatState, Rejection> {
    Ok(transmit_state_motion(s, t_rx_gps_s, false)?.0)
}
/// The time by the satellite's clock at which the signal of `s` received
/// at `t_rx_gps_s` left it: t_sv = t_rx - P/c, P the code's or the
/// iono-free pair's pseudorange (the t_sv of [`transmit_state`]), GPS s.
pub fn signal_sent_s(s: &SatInput<'_>, t_rx_gps_s: f64) -> Result<f64, Rejection> {
    let (p, _) = ranging_pseudorange(s)?;
    Ok(t_rx_gps_s - p / C_M_S)
}

/// [`transmit_state`] and, when `motion` is true, the satellite's
/// velocity and clock drift at the same transmit time from the same
/// evaluation (a Keplerian orbit by [`transmit_state_motion_on_arc`],
/// whose nodes are [`Orbit::state_motion`]'s, or by
/// [`Orbit::transmit_state_motion`]; the state is [`transmit_state`]'s to
/// the bit). A GLONASS motion comes with its integration (the receiver's
/// [`crate::glonass::GlonassArc`]), not here: None for a GLONASS
/// satellite.
pub fn transmit_state_motion(
    s: &SatInput<'_>,
    t_rx_gps_s: f64,
    motion: bool,
) -> Result<(SatState, Option<SatMotion>), Rejection> {
    let on_arc = |o: &Orbit| -> Result<(SatState, Option<SatMotion>), Rejection> {
        let t_sv = signal_sent_s(s, t_rx_gps_s)?;
        let (_, state, mo) = if s.orbit_arc {
            transmit_state_motion_on_arc(s.id, o, t_sv)
        } else {
            o.transmit_state_motion(t_sv)
        };
        Ok((state, motion.then_some(mo)))
    };
    match s.eph {
        Broadcast::Kepler(k) => on_arc(&Orbit::new(k)),
        Broadcast::Orbit(o) => on_arc(o),
        Broadcast::Glonass(g) => Ok((g.state(transmit_time_s(s, t_rx_gps_s)?), None)),
    }
}

/// One satellite's corrected observation, every correction computed at the
/// receiver position `rx_m` (None: no atmosphere, no mask, and the Earth
/// rotation from the pseudorange's transit time); `full` false also skips
/// the atmosphere and the mask (the bootstrap pass).
pub fn correct(
    s: &SatInput<'_>,
    t_rx_gps_s: f64,
    rx_m: Option<[f64; 3]>,
    full: bool,
    c: &Corrections,
    klobuchar: Option<&Klobuchar>,
) -> Result<Corrected, Rejection> {
    let tx = transmit_state(s, t_rx_gps_s)?;
    correct_at(s, t_rx_gps_s, &tx, rx_m, None, full, c, klobuchar)
}

/// [`correct`] with the satellite's position (ECEF at transmit time, not
/// yet rotated) and clock at its transmit time given: `tx` =
/// `transmit_state(s, t_rx_gps_s)?`, computed once per
/// epoch however many passes use it (the device's receiver integrates a
/// GLONASS orbit there from a [`crate::glonass::GlonassArc`]); and, when
/// given, the receiver's frame `rx_frame` = `ReceiverFrame::at(rx_m)`,
/// computed once for all the epoch's satellites (else here, for a full
/// correction).
#[allow(clippy::too_many_arguments)]
pub fn correct_at(
    s: &SatInput<'_>,
    t_rx_gps_s: f64,
    tx: &SatState,
    rx_m: Option<[f64; 3]>,
    rx_frame: Option<&ReceiverFrame>,
    full: bool,
    c: &Corrections,
    klobuchar: Option<&Klobuchar>,
) -> Result<Corrected, Rejection> {
    correct_at_with(s, t_rx_gps_s, tx, rx_m, rx_frame, full, c, klobuchar, true)
}

/// [`correct_at`] without the azimuth, for corrections without Klobuchar
/// (`c.iono` false: a receiver stream's): the same bits in every field
/// but `azimuth_rad`, which is NaN (not computed). The device's stream
/// receiver, whose epochs use no azimuth, saves its arctangent.
#[allow(clippy::too_many_arguments)]
pub fn correct_at_without_azimuth(
    s: &SatInput<'_>,
    t_rx_gps_s: f64,
    tx: &SatState,
    rx_m: Option<[f64; 3]>,
    rx_frame: Option<&ReceiverFrame>,
    full: bool,
    c: &Corrections,
) -> Result<Corrected, Rejection> {
    let c = Corrections { iono: false, ..*c };
    correct_at_with(s, t_rx_gps_s, tx, rx_m, rx_frame, full, &c, None, false)
}

/// [`correct_at`], with the azimuth computed when `azimuth` (else NaN).
#[allow(clippy::too_many_arguments)]
fn correct_at_with(
    s: &SatInput<'_>,
    t_rx_gps_s: f64,
    tx: &SatState,
    rx_m: Option<[f64; 3]>,
    rx_frame: Option<&ReceiverFrame>,
    full: bool,
    c: &Corrections,
    klobuchar: Option<&Klobuchar>,
    azimuth: bool,
) -> Result<Corrected, Rejection> {
    let id = s.id;
    let k = s.eph;
    // An iono-free pair: the combination, its group delay, no Klobuchar
    // (the combination removes the first-order ionosphere).
    let (p, pair) = ranging_pseudorange(s)?;
    let (pos_tx, clock_s) = (tx.position_m, tx.clock_s);
    let transit_s = match rx_m {
        Some(rx) => {
            // Two fixed-point steps: the rotation moves the satellite by
            // < 150 m, changing the transit by < 0.5 us.
            let t0 = distance_m(pos_tx, rx) / C_M_S;
            distance_m(rotate_earth(pos_tx, t0), rx) / C_M_S
        }
        None => p / C_M_S,
    };
    let pos = rotate_earth(pos_tx, transit_s);
    let group_delay_m = match pair {
        Some((_, d)) if c.group_delay => d,
        Some(_) => 0.0,
        None if c.group_delay && group_delay_applies(id.system, s.code) => {
            C_M_S * k.kepler().map_or(0.0, |k| k.group_delay_s)
        }
        None => 0.0,
    };
    let (mut az, mut el, mut iono_m, mut tropo_m) = (0.0, core::f64::consts::FRAC_PI_2, 0.0, 0.0);
    if let (Some(rx), true) = (rx_m, full) {
        let here;
        let frame = match rx_frame {
            Some(f) => f,
            None => {
                here = ReceiverFrame::at(rx);
                &here
            }
        };
        let g = frame.geodetic;
        if azimuth {
            (az, el) = az_el_rotated(rx, &frame.rotation, pos);
        } else {
            az = f64::NAN;
            el = elevation_rotated(rx, &frame.rotation, pos);
        }
        if el < c.elevation_mask_rad {
            return Err(Rejection::BelowMask { elevation_rad: el });
        }
        if c.iono && pair.is_none() {
            if let Some(kb) = klobuchar {
                let tow = m::rem_euclid(t_rx_gps_s, WEEK_S);
                let l1 = kb.delay_l1_m(g.lat_rad, g.lon_rad, az, el, tow);
                let f_hz = carrier_hz(id.system, s.code, k.frequency_channel());
                iono_m = scale_to_frequency(l1, f_hz);
            }
        }
        if c.tropo {
            tropo_m = frame.tropo.slant_m(el);
        }
    }
    let sat_clock_m = C_M_S * clock_s;
    let corrected = p + sat_clock_m - group_delay_m - iono_m - tropo_m;
    let sigma_m = match (id.system, &c.glonass_sigma, rx_m.is_some() && full) {
        (System::Glonass, Some(model), true) => Some(model.sigma_m(el)),
        _ => None,
    };
    Ok(Corrected {
        obs: RangeObservation {
            id,
            pseudorange_m: corrected,
            position_m: pos,
            sigma_m,
        },
        raw_pseudorange_m: p,
        elevation_rad: el,
        azimuth_rad: az,
        sat_clock_m,
        group_delay_m,
        iono_m,
        tropo_m,
    })
}

/// The sigma of an iono-free combination with noise factor `factor` at
/// elevation `el_rad`: the sigma model's terms with no ionosphere, the
/// receiver noise and multipath amplified (they are independent on the two
/// frequencies; SPEC §1 sigma model, DO-229D J.2.4 terms).
pub fn iono_free_sigma_m(model: &SigmaModel, el_rad: f64, factor: f64) -> f64 {
    iono_free_sigma::<f32>(model, el_rad, factor).to_f64()
}

/// [`iono_free_sigma_m`] in the precision `T`: the stream's sigmas are
/// evaluated in f32 (the FPU's on the M4, where f64's exponential and
/// sine are software), whose relative precision (6e-8, a few ulp through
/// the exponential) is far below what a weight needs (docs/CORE.md
/// "Precision": the engines take sigmas in f32); within 1e-6 relative of
/// the f64 evaluation (test `stream_sigmas_in_f32_are_the_f64_ones`).
fn iono_free_sigma<T: Real>(model: &SigmaModel, el_rad: f64, factor: f64) -> T {
    use raim_core::araim::error_model::{multipath_sigma_m, tropo_sigma_m};
    let el = T::of(el_rad.max(model.min_elevation_rad));
    let tropo = tropo_sigma_m(el.sin_m());
    let mp = multipath_sigma_m(el * T::of(180.0) / T::of(core::f64::consts::PI));
    let (ura, noise, k) = (T::of(model.ura_m), T::of(model.noise_m), T::of(factor));
    (ura * ura + tropo * tropo + k * k * (mp * mp + noise * noise)).sqrt()
}

/// The sigma of `model` at elevation `el_rad`, m, evaluated in f32 (as
/// [`iono_free_sigma`]): [`SigmaModel::sigma`].
fn model_sigma_m(model: &SigmaModel, el_rad: f64) -> f64 {
    model.sigma::<f32>(el_rad as f32).to_f64()
}

/// The square root of [`Curves::variance_m2`] in the precision `T` (the
/// same terms: the ADD's troposphere, the airborne curves times the
/// pair's factor, the residual ionosphere when given), for the stream's
/// ARAIM sigmas in f32 (as [`iono_free_sigma`]).
fn curves_sigma<T: Real>(c: &Curves, el_rad: f64) -> T {
    use raim_core::araim::error_model::{airborne_variance_m2, iono_obliquity, tropo_sigma_m};
    let el = T::of(el_rad);
    let tropo = tropo_sigma_m(el.sin_m());
    let v = tropo * tropo + T::of(c.airborne_factor_sq) * airborne_variance_m2(el);
    if c.iono_vertical_m == 0.0 {
        return v.sqrt();
    }
    let iono = T::of(c.iono_vertical_m) * iono_obliquity(el);
    (v + iono * iono).sqrt()
}

/// The explicit sigma of one satellite of a receiver stream (which has no
/// ionospheric model unless it carries one): an iono-free pair gets
/// [`iono_free_sigma_m`] of `model` (`glonass` for a GLONASS satellite,
/// when given); a single-frequency GLONASS satellite with `glonass` gets
/// that model with its residual-ionosphere term times
/// `single_iono_factor`; any other satellite None (the core's model, set
/// by the configuration).
pub fn stream_sigma_m(
    system: System,
    code: &str,
    elevation_rad: f64,
    model: &SigmaModel,
    glonass: Option<&SigmaModel>,
    single_iono_factor: f64,
) -> Option<f64> {
    let g = match (system, glonass) {
        (System::Glonass, Some(g)) => Some(g),
        _ => None,
    };
    if let Some(f) = iono_free_noise_factor(system, code) {
        Some(iono_free_sigma_m(g.unwrap_or(model), elevation_rad, f))
    } else {
        g.map(|g| {
            let mut g = *g;
            g.iono_vertical_m *= single_iono_factor;
            model_sigma_m(&g, elevation_rad)
        })
    }
}

/// Code preferences for receiver streams, per system: iono-free pairs
/// first (a stream has no ionospheric model), then single codes. GLONASS
/// FDMA: L1/L2 of the same code first (C/A on both, as GLONASS-M
/// broadcasts; then P), so that no code-to-code bias enters.
pub const STREAM_CODES: [(System, &[&str]); 5] = [
    (
        System::Gps,
        &[
            "C1C+C2W", "C1C+C2L", "C1C+C2X", "C1C+C2S", "C1C+C5Q", "C1C+C5X", "C1C", "C1W",
        ],
    ),
    (
        System::Galileo,
        &[
            "C1C+C5Q", "C1X+C5X", "C1C+C7Q", "C1X+C7X", "C1C", "C1X", "C1B",
        ],
    ),
    (System::Beidou, &["C2I+C6I", "C2I+C7I", "C2I", "C1I"]),
    (
        System::Glonass,
        &["C1C+C2C", "C1P+C2P", "C1C+C2P", "C1C", "C1P"],
    ),
    (
        System::Qzss,
        &["C1C+C2L", "C1C+C2X", "C1C+C2S", "C1C+C5Q", "C1C"],
    ),
];

/// The ARAIM nominal curves of a satellite ranged with `code`
/// (`raim_core::araim::error_model::Curves`, SPEC §9.1): the ADD's
/// airborne multipath and noise curves through the noise factor of the
/// iono-free pair `code` forms ([`iono_free_noise_factor`]: L1/L2 2.98,
/// E1/E5a and L1/L5 2.59, B1I/B3I 3.53), or through the ADD's L1/L5 factor
/// for a single code; `iono_vertical_m` a residual ionosphere's vertical
/// sigma (0: none). The one rule of `raim replay --araim` (its satellite
/// models) and of the unit's stream epochs under ARAIM
/// ([`stream_sigma_for_m`]), docs/ARAIM.md "Iono-free replay".
pub fn araim_curves(system: System, code: &str, iono_vertical_m: f64) -> Curves {
    Curves {
        airborne_factor_sq: iono_free_noise_factor(system, code)
            .map_or_else(iono_free_factor_sq, |k| k * k),
        iono_vertical_m,
    }
}

/// How the satellites of a receiver stream's epoch get their sigmas.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StreamSigmas {
    /// For the snapshot monitor: [`stream_sigma_m`] of this model (the
    /// configuration's), and a single-frequency range of another system
    /// the model with its residual ionosphere doubled.
    Snapshot(SigmaModel),
    /// For ARAIM, whose ISM gives the signal-in-space term (sigma_URA,
    /// sigma_URE, added by the ARAIM join): the satellite's nominal sigma
    /// from [`araim_curves`] of the signal pair it was ranged with, as
    /// `raim replay --araim` models it; a single-frequency range carries
    /// the residual ionosphere `iono_vertical_m` doubled (a stream has no
    /// ionospheric model; the ADD's dual-frequency curves have no
    /// ionospheric term).
    Araim {
        /// The configuration's residual-ionosphere vertical sigma, m.
        iono_vertical_m: f64,
    },
}

/// The sigma (m) of one satellite of a stream epoch, ranged with `code`
/// (one code, or a pair "C1C+C5Q") at elevation `el_rad`, under `sigmas`
/// ([`StreamSigmas`]); `single_iono_factor` the factor on the residual
/// ionosphere of a single-frequency range (a stream's: 2,
/// `rtcm::NO_MODEL_IONO_FACTOR`). The device's stream receiver and the
/// host's stream replay call this one function.
pub fn stream_sigma_for_m(
    sigmas: &StreamSigmas,
    system: System,
    code: &str,
    el_rad: f64,
    single_iono_factor: f64,
) -> f64 {
    match sigmas {
        StreamSigmas::Snapshot(model) => {
            let glonass = SigmaModel {
                ura_m: crate::glonass::glonass_ura_m(model.ura_m),
                ..*model
            };
            stream_sigma_m(
                system,
                code,
                el_rad,
                model,
                Some(&glonass),
                single_iono_factor,
            )
            .unwrap_or_else(|| {
                let mut single = *model;
                single.iono_vertical_m *= single_iono_factor;
                model_sigma_m(&single, el_rad)
            })
        }
        StreamSigmas::Araim { iono_vertical_m } => {
            let iono_m = if split_pair(code).is_some() {
                0.0
            } else {
                iono_vertical_m * single_iono_factor
            };
            curves_sigma::<f32>(&araim_curves(system, code, iono_m), el_rad).to_f64()
        }
    }
}

/// A carrier-to-noise density (dB-Hz: RINEX S observable, RTCM DF403 or
/// DF408) in whole dB-Hz, as NMEA's GSV writes it and the stream receiver
/// keeps it (one byte per satellite): rounded half away from zero, 0 for
/// an unknown value (`None`, not finite, or below 0.5 dB-Hz: DF403 and
/// DF408 send 0 for "not computed"), 255 at most. The device's receiver
/// and the host's readers call this one function.
pub fn cn0_dbhz_u8(cn0_dbhz: Option<f64>) -> u8 {
    match cn0_dbhz {
        Some(v) if v.is_finite() && v >= 0.5 => {
            let r = m::round(v);
            if r >= 255.0 {
                255
            } else {
                // 1 <= r < 255: exact in u8.
                r as u8
            }
        }
        _ => 0,
    }
}

/// The stream code preferences of `system`.
pub fn stream_codes(system: System) -> &'static [&'static str] {
    STREAM_CODES
        .iter()
        .find(|(s, _)| *s == system)
        .map_or(&[], |(_, c)| *c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative tolerance of the combination's closed forms (f64 rounding
    /// of 2e7 m ranges).
    const TOL_M: f64 = 1e-6;

    /// A circular orbit ([`crate::ephemeris::circular`]) with no clock
    /// terms and the given group delays.
    fn kepler(system: System, group_delay_s: f64, group_delay_e5a_s: f64) -> Kepler {
        Kepler {
            toc_gps_s: 0.0,
            af0_s: 0.0,
            af1_s_s: 0.0,
            sqrt_a_m05: 5153.0,
            group_delay_s,
            group_delay_e5a_s,
            ..crate::ephemeris::circular(system, 1)
        }
    }

    /// The receiver's frame computed once for an epoch gives every
    /// satellite the bits [`correct`] gives it computing the frame itself
    /// (elevation, azimuth, troposphere, Klobuchar, corrected range,
    /// rotated position), single codes and pairs, above and below the
    /// mask, with the transmit state given as the device computes it; and
    /// without Klobuchar, the correction without the azimuth
    /// ([`correct_at_without_azimuth`], the device's) gives the same bits
    /// but the azimuth (NaN).
    ///
    /// Verifies: RX-FORM-COST
    #[test]
    fn one_receiver_frame_per_epoch_gives_the_per_satellite_bits() {
        use raim_core::frames::geodetic_to_ecef;
        let rx = geodetic_to_ecef(Geodetic {
            lat_rad: 0.7,
            lon_rad: 0.15,
            height_m: 48.0,
        });
        let frame = ReceiverFrame::at(rx);
        let kb = Klobuchar {
            alpha: [1.1e-8, 1.5e-8, -6.0e-8, -1.2e-7],
            beta: [9.0e4, 9.8e4, -6.5e4, -5.2e5],
        };
        let c = Corrections {
            elevation_mask_rad: 0.1,
            iono: true,
            tropo: true,
            group_delay: true,
            glonass_sigma: None,
        };
        let t = 1000.0 * WEEK_S + 7200.0;
        let mut seen = (0, 0);
        for (i, (prn, m0)) in [(1u8, 0.3f64), (2, 1.1), (3, 2.0), (4, -0.4), (5, 2.9)]
            .into_iter()
            .enumerate()
        {
            let mut k = kepler(System::Gps, 5e-9, 0.0);
            k.prn = prn;
            k.m0_rad = m0;
            k.i0_rad = 0.96;
            k.omega0_rad = 0.5 * i as f64;
            k.e = 0.01;
            let pair = i % 2 == 1;
            let s = SatInput {
                id: SatId::new(System::Gps, prn),
                code: if pair { "C1C+C2W" } else { "C1C" },
                p1_m: 2.2e7 + 1e5 * i as f64,
                p2_m: pair.then_some(2.2e7 + 1e5 * i as f64 + 3.0),
                eph: Broadcast::Kepler(&k),
                orbit_arc: false,
            };
            let tx = transmit_state(&s, t).unwrap();
            // Without Klobuchar (a stream's corrections), the correction
            // without the azimuth is the full one's bits but the azimuth.
            let stream = Corrections { iono: false, ..c };
            for full in [false, true] {
                let with = correct_at(&s, t, &tx, Some(rx), Some(&frame), full, &stream, None);
                let without =
                    correct_at_without_azimuth(&s, t, &tx, Some(rx), Some(&frame), full, &stream);
                match (with, without) {
                    (Ok(w), Ok(g)) => {
                        assert_eq!(g.azimuth_rad.is_nan(), full);
                        let g = Corrected {
                            azimuth_rad: w.azimuth_rad,
                            ..g
                        };
                        assert_eq!(w, g);
                        assert_eq!(w.elevation_rad.to_bits(), g.elevation_rad.to_bits());
                    }
                    (w, g) => assert_eq!(w, g),
                }
            }
            let want = correct(&s, t, Some(rx), true, &c, Some(&kb));
            let got = correct_at(&s, t, &tx, Some(rx), Some(&frame), true, &c, Some(&kb));
            match (want, got) {
                (Ok(w), Ok(g)) => {
                    seen.0 += 1;
                    assert_eq!(w, g);
                    assert_eq!(w.obs.pseudorange_m.to_bits(), g.obs.pseudorange_m.to_bits());
                    assert_eq!(w.tropo_m.to_bits(), g.tropo_m.to_bits());
                }
                (Err(w), Err(g)) => {
                    seen.1 += 1;
                    assert_eq!(w, g);
                }
                (w, g) => panic!("{w:?} {g:?}"),
            }
        }
        assert!(
            seen.0 > 0 && seen.1 > 0,
            "above and below the mask: {seen:?}"
        );
    }

    /// The receiver frame's geodetic position against raim-core's ten
    /// latitude iterations, over latitudes, longitudes and heights from
    /// -100 m to 10 km: within 1e-11 rad and 1e-6 m.
    ///
    /// Verifies: RX-FORM-COST
    #[test]
    fn the_frames_geodetic_position_is_the_cores() {
        use raim_core::frames::{ecef_to_geodetic, geodetic_to_ecef};
        for lat_deg in [-89.9f64, -60.0, -12.0, 0.0, 0.01, 33.0, 55.5, 89.9] {
            for lon_deg in [-179.0f64, -90.0, 0.0, 12.0, 100.0] {
                for height_m in [-100.0, 0.0, 48.0, 3000.0, 1e4] {
                    let rx = geodetic_to_ecef(Geodetic {
                        lat_rad: lat_deg.to_radians(),
                        lon_rad: lon_deg.to_radians(),
                        height_m,
                    });
                    let (got, want) = (ReceiverFrame::at(rx).geodetic, ecef_to_geodetic(rx));
                    assert!((got.lat_rad - want.lat_rad).abs() < 1e-11, "{lat_deg}");
                    assert!((got.lon_rad - want.lon_rad).abs() < 1e-11, "{lon_deg}");
                    assert!((got.height_m - want.height_m).abs() < 1e-6, "{height_m}");
                }
            }
        }
    }

    /// GLONASS codes take the satellite's FDMA carrier for the iono
    /// scaling (1602 MHz + k x 562.5 kHz, L2 1246 MHz + k x 437.5 kHz);
    /// the iono-free noise factor of L1/L2 is the channel-free 7/9 ratio's.
    #[test]
    fn glonass_carriers_follow_the_channel() {
        assert_eq!(carrier_hz(System::Glonass, "C1C", Some(-7)), 1_598.062_5e6);
        assert_eq!(carrier_hz(System::Glonass, "C1C", Some(6)), 1_605.375e6);
        assert_eq!(carrier_hz(System::Glonass, "C2C", Some(1)), 1_246.437_5e6);
        // GPS is unchanged by a channel argument.
        assert_eq!(carrier_hz(System::Gps, "C1C", None), F_L1_HZ);
        let g = (9.0f64 / 7.0).powi(2);
        let want = (g * g + 1.0).sqrt() / (g - 1.0);
        let got = iono_free_noise_factor(System::Glonass, "C1C+C2C").unwrap();
        assert!((got - want).abs() < 1e-12, "{got} {want}");
    }

    /// The noise factors against their published values: 2.59 (L1/L5,
    /// the ADD's, `error_model::iono_free_factor_sq`), 2.98 (L1/L2), 3.53
    /// (B1I/B3I); a single code has none.
    #[test]
    fn noise_factors() {
        let l15 = iono_free_noise_factor(System::Gps, "C1C+C5Q").unwrap();
        assert!((l15 * l15 - raim_core::araim::error_model::iono_free_factor_sq()).abs() < 1e-12);
        assert!((iono_free_noise_factor(System::Galileo, "C1C+C5Q").unwrap() - l15).abs() < 1e-12);
        let l12 = iono_free_noise_factor(System::Gps, "C1W+C2W").unwrap();
        assert!((l12 - 2.978).abs() < 1e-3, "{l12}");
        let b13 = iono_free_noise_factor(System::Beidou, "C2I+C6I").unwrap();
        assert!((b13 - 3.53).abs() < 1e-2, "{b13}");
        assert!(iono_free_noise_factor(System::Gps, "C1C").is_none());
        assert!(iono_free_noise_factor(System::Gps, "C1C+C9X").is_none());
    }

    /// A first-order ionosphere (delay 40.3 TEC / f^2 on each code) leaves
    /// the combination exactly; and the satellite hardware delays T1, T5a,
    /// T5b of E1, E5a, E5b, whose broadcast BGDs are (T1 - Tx) / (1 -
    /// (f1/fx)^2), are referred to the I/NAV clock (dt minus the E1/E5b
    /// combination's delay): the corrected E1/E5a combination equals the
    /// delay-free range, as the E1 single-frequency correction does.
    #[test]
    fn combination_removes_the_ionosphere_and_refers_to_the_inav_clock() {
        let range_m = 2.3e7;
        let tec = 4.0e17;
        let iono = |f: f64| 40.3 * tec / (f * f);
        let (f1, f5a, f5b) = (1_575.42e6, 1_176.45e6, 1_207.14e6);
        let (t1, t5a, t5b) = (3.0e-9, -2.0e-9, 5.0e-9);
        let c = C_M_S;
        let bgd = |tx: f64, fx: f64| (t1 - tx) / (1.0 - (f1 / fx).powi(2));
        let (bgd_a, bgd_b) = (bgd(t5a, f5a), bgd(t5b, f5b));
        let k = kepler(System::Galileo, bgd_b, bgd_a);
        // The I/NAV clock's own offset: the E1/E5b combination's delay.
        let g_b = (f1 / f5b).powi(2);
        let t_if_b = (g_b * t1 - t5b) / (g_b - 1.0);
        let p1 = range_m + iono(f1) + c * t1;
        let p5a = range_m + iono(f5a) + c * t5a;
        let (p, delay_m) = iono_free(System::Galileo, "C1C+C5Q", p1, p5a, Some(&k)).unwrap();
        // corrected = P + c dt_inav - group delay, dt_inav = -T_IF(E1,E5b).
        let corrected = p - c * t_if_b - delay_m;
        assert!(
            (corrected - range_m).abs() < TOL_M * 10.0,
            "{}",
            corrected - range_m
        );
        // E1 alone with BGD(E1,E5b), iono removed: the same range.
        let e1 = p1 - iono(f1) - c * t_if_b - c * bgd_b;
        assert!((e1 - range_m).abs() < TOL_M * 10.0, "{}", e1 - range_m);
        // GPS L1/L2 P(Y): the LNAV clock's own combination, no delay.
        let (f2, t2) = (1_227.60e6, 1.0e-9);
        let g = (f1 / f2).powi(2);
        let t_if = (g * t1 - t2) / (g - 1.0);
        let (p, delay_m) = iono_free(
            System::Gps,
            "C1W+C2W",
            range_m + iono(f1) + c * t1,
            range_m + iono(f2) + c * t2,
            Some(&kepler(System::Gps, 0.0, 0.0)),
        )
        .unwrap();
        assert_eq!(delay_m, 0.0);
        assert!((p - c * t_if - range_m).abs() < TOL_M * 10.0);
        // BeiDou B1I/B3I with the B3I clock: TGD1 = T1 - T3.
        let (fb1, fb3, tb1, tb3) = (F_B1I_HZ, 1_268.52e6, 4.0e-9, 1.5e-9);
        let (p, delay_m) = iono_free(
            System::Beidou,
            "C2I+C6I",
            range_m + iono(fb1) + c * tb1,
            range_m + iono(fb3) + c * tb3,
            Some(&kepler(System::Beidou, tb1 - tb3, 0.0)),
        )
        .unwrap();
        let corrected = p - c * tb3 - delay_m;
        assert!(
            (corrected - range_m).abs() < TOL_M * 10.0,
            "{}",
            corrected - range_m
        );
    }

    /// The ARAIM stream sigma is the replay's curves of the satellite's
    /// pair, checked against the ADD's formulas written out here (DO-229D
    /// A.4.2.4 troposphere, J.2.4 multipath, the ADD's airborne noise; the
    /// pair factor sqrt(g^2 + 1) / (g - 1) from the carriers): L1/L2 at
    /// 30 degrees, B1I/B3I at 60; a single code takes the L1/L5 factor and
    /// the residual ionosphere times the factor and the obliquity (within
    /// f32's 1e-6 relative); the snapshot rule is `stream_sigma_m`'s.
    ///
    /// Verifies: RX-ARAIM-REPLAY
    #[test]
    fn araim_stream_sigma_is_the_add_curves_of_the_pair() {
        let add_sigma = |el_deg: f64, f1_mhz: f64, f2_mhz: f64, iono_m: f64| {
            let el = el_deg.to_radians();
            let tropo = 0.12 * 1.001 / (0.002_001 + el.sin().powi(2)).sqrt();
            let mp = 0.13 + 0.53 * (-el_deg / 10.0).exp();
            let noise = 0.15 + 0.43 * (-el_deg / 6.9).exp();
            let g = (f1_mhz / f2_mhz).powi(2);
            let k2 = (g * g + 1.0) / ((g - 1.0) * (g - 1.0));
            let re = 6378.1363 / (6378.1363 + 350.0);
            let f_pp = 1.0 / (1.0 - (re * el.cos()).powi(2)).sqrt();
            (tropo * tropo + k2 * (mp * mp + noise * noise) + (iono_m * f_pp).powi(2)).sqrt()
        };
        // The stream's sigmas are f32's (`stream_sigmas_in_f32_are_the_f64_ones`).
        const REL_TOL: f64 = 1e-6;
        let araim = StreamSigmas::Araim {
            iono_vertical_m: 0.4,
        };
        let got = stream_sigma_for_m(&araim, System::Gps, "C1C+C2W", 30f64.to_radians(), 2.0);
        let want = add_sigma(30.0, 1575.42, 1227.60, 0.0);
        assert!((got - want).abs() < REL_TOL * want, "{got} {want}");
        let got = stream_sigma_for_m(&araim, System::Beidou, "C2I+C6I", 60f64.to_radians(), 2.0);
        let want = add_sigma(60.0, 1561.098, 1268.52, 0.0);
        assert!((got - want).abs() < REL_TOL * want, "{got} {want}");
        let got = stream_sigma_for_m(&araim, System::Galileo, "C1C", 20f64.to_radians(), 2.0);
        let want = add_sigma(20.0, 1575.42, 1176.45, 0.8);
        assert!((got - want).abs() < REL_TOL * want, "{got} {want}");
        let model = SigmaModel::default();
        let el = 25f64.to_radians();
        let snap = stream_sigma_for_m(
            &StreamSigmas::Snapshot(model),
            System::Gps,
            "C1C+C2W",
            el,
            2.0,
        );
        let k = iono_free_noise_factor(System::Gps, "C1C+C2W").unwrap();
        assert_eq!(snap, iono_free_sigma_m(&model, el, k));
    }

    /// The stream's sigmas evaluated in f32 ([`stream_sigma_for_m`]:
    /// [`iono_free_sigma_m`], the GLONASS and single-frequency models, the
    /// ARAIM curves) against raim-core's f64 evaluation of the same terms
    /// (`SigmaModel::sigma_m`, `Curves::variance_m2`, the f64 troposphere
    /// and multipath curves), for every stream code of every system, the
    /// default and the replays' models, ARAIM with and without a residual
    /// ionosphere, at elevations from below the floor to the zenith:
    /// within 1e-6 relative (f32's epsilon is 1.2e-7; a weight moves by
    /// twice the relative error).
    ///
    /// Verifies: RX-FORM-COST
    #[test]
    fn stream_sigmas_in_f32_are_the_f64_ones() {
        use raim_core::araim::error_model::{multipath_sigma_m, tropo_sigma_m};
        const SIGMA_REL_TOL: f64 = 1e-6;
        let replay = SigmaModel {
            ura_m: 0.3,
            iono_vertical_m: 0.5,
            noise_m: 0.2,
            ..SigmaModel::default()
        };
        let mut worst = 0.0f64;
        let mut n = 0;
        for (system, codes) in STREAM_CODES {
            for code in codes.iter() {
                for k in -10..=900 {
                    let el = (k as f64 * 0.1).to_radians();
                    let mut check = |got: f64, want: f64| {
                        let rel = (got - want).abs() / want;
                        assert!(
                            rel < SIGMA_REL_TOL,
                            "{system:?} {code} el {el}: {got} vs {want}"
                        );
                        worst = worst.max(rel);
                        n += 1;
                    };
                    for model in [SigmaModel::default(), replay] {
                        let glo = SigmaModel {
                            ura_m: crate::glonass::glonass_ura_m(model.ura_m),
                            ..model
                        };
                        let m = if system == System::Glonass {
                            glo
                        } else {
                            model
                        };
                        let want = match iono_free_noise_factor(system, code) {
                            Some(f) => {
                                let e = el.max(m.min_elevation_rad);
                                let tropo = tropo_sigma_m(e.sin());
                                let mp = multipath_sigma_m(e.to_degrees());
                                (m.ura_m * m.ura_m
                                    + tropo * tropo
                                    + f * f * (mp * mp + m.noise_m * m.noise_m))
                                    .sqrt()
                            }
                            None => SigmaModel {
                                iono_vertical_m: 2.0 * m.iono_vertical_m,
                                ..m
                            }
                            .sigma_m(el),
                        };
                        let got = stream_sigma_for_m(
                            &StreamSigmas::Snapshot(model),
                            system,
                            code,
                            el,
                            2.0,
                        );
                        check(got, want);
                    }
                    if el < 0.0 {
                        continue;
                    }
                    for iono in [0.0, 0.4] {
                        let iono_m = if split_pair(code).is_some() {
                            0.0
                        } else {
                            2.0 * iono
                        };
                        let want = araim_curves(system, code, iono_m).variance_m2(el).sqrt();
                        let got = stream_sigma_for_m(
                            &StreamSigmas::Araim {
                                iono_vertical_m: iono,
                            },
                            system,
                            code,
                            el,
                            2.0,
                        );
                        check(got, want);
                    }
                }
            }
        }
        assert!(n > 10_000 && worst > 0.0, "{n} {worst:e}");
        std::println!("{n} sigmas, worst relative difference {worst:.2e}");
    }
}

#[cfg(test)]
#[path = "ranging_cov_tests.rs"]
mod ranging_cov_tests;
