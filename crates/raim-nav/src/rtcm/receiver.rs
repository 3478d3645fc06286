//! A receiver's RTCM 3 stream to the monitor's epochs, with no host in the
//! loop: the broadcast ephemerides the stream carries are kept
//! ([`EphemerisStore`]), each epoch's MSM ranges are gathered, and a
//! closed epoch is dated, corrected ([`crate::ranging`], the host's own
//! kernel) and handed over as `RangeObservation`s.
//!
//! Frames are decoded by [`super::decode`] (the fields used, read straight
//! from the frame's bits with small stack frames), not by `rtcm-rs`, whose
//! decoding of one frame took 20-45 KB of stack on the device (see that
//! module); the host's reader keeps `rtcm-rs`, and the host tests hold the
//! two to the same values bit for bit.
//!
//! What it reads, and how:
//! - MSM4-MSM7 of GPS (1074-1077), Galileo (1094-1097), QZSS (1114-1117),
//!   BeiDou (1124-1127) and GLONASS (1084-1087): pseudorange = (rough
//!   range + fine range) x c / 1000 (DF397 + DF398 + DF400/DF405), one
//!   RINEX 3 code per signal. GPS, Galileo (GST) and QZSS MSM carry the GPS
//!   time of week; BeiDou MSM the BDT time of week (GPS = BDT + 14 s; a
//!   BeiDou MSM whose time equals the open epoch's GPS time of week, as
//!   encoders before RTCM 3.2 wrote it, joins that epoch, as on the host).
//!   An epoch closes at the message whose multiple-message bit (DF393) is
//!   0, or when the time of week changes. GLONASS MSM carry the GLONASS
//!   time of day (DF034): they join the open epoch, and once the epoch's
//!   GPS time is known their time of day must be its GLONASS time of day
//!   to the millisecond (GPS - UTC from the stream's latest RTCM 1013,
//!   else from [`crate::time`]'s table before its expiry; past it, with no
//!   1013, the epoch is refused [`FormError::LeapSecondsUnknown`]);
//!   otherwise the epoch's GLONASS data is dropped and counted. GLONASS
//!   MSM before any other MSM of their epoch wait for it.
//! - Ephemerides 1019 (GPS), 1042 (BeiDou), 1044 (QZSS), 1045 and 1046
//!   (Galileo F/NAV and I/NAV) and 1020 (GLONASS). A truncated week is
//!   placed from the pivot in its system's own week count (GPS and QZSS
//!   10 bits, Galileo GST 12 bits from GPS week 1024, BeiDou BDT 13 bits
//!   from GPS week 1356; [`super::fields::gps_week_of`]): a receiver's
//!   week-rollover pivot is the earliest week it can run in (the
//!   firmware's build week less a lookback, raim-server's `PIVOT_WEEK`;
//!   [`super::fields::week_from_pivot`]). The stream's epochs are dated by
//!   the first Keplerian ephemeris: the week that puts the latest epoch
//!   nearest its toe (in GPS time). A 1020's t_b (a time of the Moscow
//!   day) is placed by the epoch it came after.
//! - Station 1005/1006: the antenna reference point, the a-priori position
//!   of the bootstrap solution.
//! - The legacy observables (1001-1004, 1009-1012) and the other systems'
//!   MSM (SBAS, NavIC, MSM1-3) are counted and not used here (the host's
//!   reader takes the legacy ones).
//!
//! An epoch is formed as the host's receiver-stream replay forms it
//! (docs/RECEIVERS.md): the stream codes ([`crate::ranging::STREAM_CODES`],
//! iono-free pairs first), the ephemeris in force ([`EphemerisStore::select`]),
//! two passes of [`crate::ranging::correct`] around a bootstrap position,
//! and the stream sigmas ([`crate::ranging::stream_sigma_for_m`]: for the
//! snapshot monitor the configuration's model, a single-frequency range
//! with its residual-ionosphere term doubled, since a stream carries no
//! ionospheric model; for ARAIM the ADD's curves of the satellite's signal
//! pair, `raim replay --araim`'s rule).

use heapless::Vec;
use raim_core::{RangeObservation, SatId, System};

use crate::arc::KeplerArcs;
use crate::ephemeris::{Orbit, SatState, BDT_MINUS_GPST_S, WEEK_S};
use crate::glonass::{
    glonass_time_of_day_to_gps_with_s, glonass_time_of_day_with_s, GlonassArc, GlonassEphemeris,
    GlonassIcdFields,
};
use crate::m;
use crate::ranging::{
    bootstrap_position, cn0_dbhz_u8, correct_at, correct_at_without_azimuth, signal_sent_s,
    split_pair, stream_codes, stream_sigma_for_m, transmit_time_s, Broadcast, Corrections,
    ReceiverFrame, SatInput, StreamSigmas,
};
use crate::store::{Chosen, DecodedSets, EphemerisStore, OrbitCache, Stored};
use crate::time::table_gps_minus_utc_s;
use crate::velocity::{glonass_motion, range_rate, RangeRate, SatMotion};

use super::decode::{msm_more_bit, Frame, Message, Msm, MsmSystem};
use super::fields::{gps_week_of, kepler, toc_near_toe};

/// Milliseconds in a week and in a day.
const WEEK_MS: i64 = 604_800_000;
const DAY_MS: i64 = 86_400_000;
/// The residual-ionosphere sigma of a single-frequency range is doubled:
/// the stream carries no Klobuchar model, which removes at least 50 % of
/// the delay (IS-GPS-200 20.3.3.5.2.5), so the uncorrected delay is at
/// most twice the corrected model's residual.
pub const NO_MODEL_IONO_FACTOR: f64 = 2.0;
/// Keplerian sets kept: the set in force and the next for 32 GPS, 36
/// Galileo (I/NAV and F/NAV are sets of their own: 72), 46 BeiDou (the
/// BDS-2 and BDS-3 satellites in service) and 10 QZSS satellites, less a
/// margin the oldest-out rule covers (a full store drops its oldest toc).
/// Each is kept as its message's payload and decoded when an epoch uses
/// it ([`EphemerisStore`]).
#[cfg(not(feature = "ram-192k"))]
pub const KEPLER_SETS: usize = 256;
/// Keplerian sets kept on a part with 192 KiB of RAM (feature
/// `ram-192k`, the STM32F4's stream build, whose epochs take 24
/// satellites): the set in force and the next of the satellites a
/// receiver tracks and broadcasts, not of every satellite in orbit (24
/// satellites, Galileo's I/NAV and F/NAV sets apart, within 64). A stream
/// that carries more (a caster's whole-constellation ephemeris stream)
/// loses its oldest sets first; a satellite left without a set in force
/// is not used (`FormedEpoch::rejected`), never given another's.
#[cfg(feature = "ram-192k")]
pub const KEPLER_SETS: usize = 64;
/// Decoded Keplerian sets kept across epochs ([`OrbitCache`]): as many
/// as the satellites of the default build's epoch (32, the wire's
/// capacity), so that a set is decoded and its orbit's constants computed
/// once while it is in force, not at every epoch (about 350 B each,
/// 11.3 KB). None is kept with `ram-192k` (the STM32F4's RAM is ARAIM's
/// and the particle filter's): each epoch decodes its sets.
#[cfg(not(feature = "ram-192k"))]
pub const ORBIT_CACHE_SETS: usize = 32;
/// Keplerian orbit arcs kept across epochs ([`KeplerArcs`]): one for each
/// satellite of the default build's epoch (32, the wire's capacity), 424 B
/// each.
#[cfg(not(feature = "ram-192k"))]
pub const KEPLER_ARCS: usize = 32;
/// Keplerian orbit arcs with `ram-192k`: 12, 5.1 KB of the STM32F4's
/// SRAM, whose stack region keeps more than 8 KiB over every measured
/// high water with them (docs/FLASH.md "STM32F4: the stream";
/// BENCHMARKS.md "Orbit arcs"); a Keplerian satellite beyond them has its
/// arc evaluated afresh at each epoch (two nodes: the same bits, slower).
#[cfg(feature = "ram-192k")]
pub const KEPLER_ARCS: usize = 12;
/// GLONASS sets kept: two per slot of a full constellation.
#[cfg(not(feature = "ram-192k"))]
const GLONASS_SETS: usize = 48;
/// GLONASS sets kept with `ram-192k`: two for each of 12 satellites, the
/// most in view at once (the oldest t_b goes first).
#[cfg(feature = "ram-192k")]
const GLONASS_SETS: usize = 24;
/// 1020 messages held until the stream's epochs are dated.
#[cfg(not(feature = "ram-192k"))]
const PENDING_GLONASS: usize = 32;
/// 1020 messages held until the stream is dated, with `ram-192k`: one for
/// each of 16 satellites, more than are in view (the oldest goes first).
#[cfg(feature = "ram-192k")]
const PENDING_GLONASS: usize = 16;
/// GLONASS orbits kept integrated between epochs: one per slot (1-27),
/// so every GLONASS satellite of an epoch has its own.
#[cfg(not(feature = "ram-192k"))]
const GLONASS_ARCS: usize = 27;
/// GLONASS orbits kept integrated with `ram-192k`: 12, the most GLONASS
/// satellites in view at once. A satellite beyond them in one epoch is
/// integrated from t_b ([`GlonassArcs::state`]): the same bits, slower.
#[cfg(feature = "ram-192k")]
const GLONASS_ARCS: usize = 12;

/// The GLONASS orbits of the latest epochs, each integrated up to the
/// last RK4 node before its latest transmit time ([`GlonassArc`]): an
/// epoch integrates each satellite's orbit once, from the node the
/// previous epoch reached, and the result is the ICD integration's from
/// t_b to the bit.
#[derive(Debug, Clone)]
struct GlonassArcs {
    arcs: Vec<(GlonassArc, u32), GLONASS_ARCS>,
    /// The epoch count stamped on the arcs used in it.
    epoch: u32,
}

impl GlonassArcs {
    const fn new() -> Self {
        GlonassArcs {
            arcs: Vec::new(),
            epoch: 0,
        }
    }

    /// The next epoch's arcs are stamped anew.
    fn next_epoch(&mut self) {
        self.epoch = self.epoch.wrapping_add(1);
    }

    /// `g`'s state at `t_gps_s`, from its arc: the one kept for `g`, else
    /// a new one in place of an arc no satellite of this epoch uses (with
    /// every arc in use, which 27 slots do not reach, integrated from t_b
    /// as [`GlonassEphemeris::state`]); with the integration's velocity
    /// there (PZ-90.11, m/s: the velocity solution's, [`glonass_motion`]).
    fn state(&mut self, g: &GlonassEphemeris, t_gps_s: f64) -> (SatState, [f64; 3]) {
        let epoch = self.epoch;
        let at = match self.arcs.iter().position(|(a, _)| a.ephemeris() == g) {
            Some(i) => Some(i),
            None => {
                if self.arcs.push((GlonassArc::new(g), epoch)).is_ok() {
                    Some(self.arcs.len() - 1)
                } else {
                    let free = self.arcs.iter().position(|(_, e)| *e != epoch);
                    if let Some(slot) = free.and_then(|i| self.arcs.get_mut(i)) {
                        *slot = (GlonassArc::new(g), epoch);
                    }
                    free
                }
            }
        };
        let (p, v) = match at.and_then(|i| self.arcs.get_mut(i)) {
            Some((arc, used)) => {
                *used = epoch;
                arc.propagate_pz90(t_gps_s)
            }
            None => g.propagate_pz90(t_gps_s),
        };
        // `GlonassArc::state`'s and `GlonassEphemeris::state`'s own
        // position and clock, to the bit.
        let state = SatState {
            position_m: crate::glonass::pz90_to_wgs84(p),
            clock_s: g.clock_s(t_gps_s),
        };
        (state, v)
    }
}

/// Why a closed epoch was not handed over.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FormError {
    /// No Keplerian ephemeris (1019, 1042, 1044, 1045, 1046) yet: the
    /// epoch cannot be dated (its GPS week is unknown).
    NotDated {
        /// The epoch's GPS time of week, ms.
        tow_ms: i64,
    },
    /// More signals in one epoch than the receiver holds; the rest were
    /// dropped and the epoch is refused.
    TooManySignals { capacity: u32 },
    /// An epoch with GLONASS data past the leap-second table's expiry
    /// ([`crate::time::LEAP_TABLE_EXPIRES_GPS_S`]) with no leap-second
    /// count from the stream (RTCM 1013): GLONASS time is UTC-based, so
    /// its data cannot be joined to the GPS epoch without GPS - UTC, and
    /// the epoch is refused rather than misaligned.
    LeapSecondsUnknown {
        /// The epoch's GPS time of week, ms.
        tow_ms: i64,
    },
}

/// Where the GPS - UTC leap seconds the receiver dates GLONASS with come
/// from, at its latest dated epoch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LeapSeconds {
    /// No epoch dated yet, and no 1013.
    NotDated,
    /// The stream's latest RTCM 1013 (DF054), s.
    Stream(u8),
    /// The built-in table, s: the latest epoch is before its expiry.
    Table(u8),
    /// The latest epoch is past the table's expiry and the stream sent no
    /// count: epochs with GLONASS data are refused
    /// ([`FormError::LeapSecondsUnknown`]).
    TableExpired,
}

impl core::fmt::Display for FormError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            FormError::NotDated { tow_ms } => write!(
                f,
                "epoch at GPS time of week {tow_ms} ms not dated: no ephemeris (1019, 1042, 1044, 1045, 1046) received yet"
            ),
            FormError::TooManySignals { capacity } => {
                write!(f, "more than {capacity} signals in one epoch")
            }
            FormError::LeapSecondsUnknown { tow_ms } => write!(
                f,
                "epoch at GPS time of week {tow_ms} ms has GLONASS data, but GPS - UTC is unknown: the leap-second table has expired and the stream sent no RTCM 1013"
            ),
        }
    }
}

/// What the receiver counted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RtcmCounts {
    pub frames: u32,
    pub epochs: u32,
    pub ephemerides: u32,
    /// Messages of a type this receiver does not use.
    pub ignored: u32,
    /// Frames whose message did not decode.
    pub undecodable: u32,
    /// Epochs whose GLONASS data was dropped (time of day mismatch) or
    /// GLONASS-only epochs (no GPS time to date them).
    pub glonass_dropped: u32,
    /// 1020 outside the ICD's ranges.
    pub glonass_bad: u32,
    /// RTCM 1013 system parameters taken.
    pub system_parameters: u32,
    /// Keplerian ephemerides not kept: a payload over 64 B
    /// ([`crate::store::Stored::NotKept`]).
    pub ephemerides_not_kept: u32,
}

/// One signal's pseudorange, C/N0 and phase-range rate, in 16 bytes (an
/// epoch holds up to `S` of them three times over: the open epoch, the
/// closed one and the GLONASS data waiting; test
/// `signal_takes_16_bytes`).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Signal {
    id: SatId,
    /// RINEX 3 code "C1C" less its "C": the band digit (ASCII) and the
    /// attribute letter.
    band_digit: u8,
    attribute: u8,
    /// C/N0, whole dB-Hz (0: unknown; `cn0_dbhz_u8`).
    cn0_dbhz: u8,
    /// The phase-range rate ([`pack_rate_mm_s`]).
    rate: [u8; 3],
    value_m: f64,
}

impl Signal {
    /// Whether this is the signal of RINEX 3 code `c` ("C1C").
    fn is_code(&self, c: &str) -> bool {
        c.as_bytes() == [b'C', self.band_digit, self.attribute]
    }

    /// The phase-range rate, m/s, if the MSM gave one.
    fn rate_m_s(&self) -> Option<f64> {
        unpack_rate_mm_s(self.rate)
    }
}

/// The packed mark of no rate: -2^23 mm/s.
const NO_RATE: [u8; 3] = [0x80, 0, 0];

/// A phase-range rate (MSM5/MSM7 DF399 + DF404, within +-8192 m/s) in
/// whole mm/s, 24-bit two's complement, big-endian; [`NO_RATE`] for none
/// or beyond +-8388 m/s. The millimetre (half a millimetre per second of
/// rounding against DF404's 0.1 mm/s) is far below a receiver's Doppler
/// noise (GMSD7: cm/s), and keeps a signal in 16 bytes
/// (`docs/RECEIVERS.md` "Speed and course").
fn pack_rate_mm_s(rate_m_s: Option<f64>) -> [u8; 3] {
    const LIMIT: f64 = (1 << 23) as f64;
    match rate_m_s.map(|r| m::round(r * 1000.0)) {
        Some(mm) if mm.abs() < LIMIT => {
            let [_, a, b, c] = (mm as i32).to_be_bytes();
            [a, b, c]
        }
        _ => NO_RATE,
    }
}

/// [`pack_rate_mm_s`]'s rate back, m/s.
fn unpack_rate_mm_s(p: [u8; 3]) -> Option<f64> {
    if p == NO_RATE {
        return None;
    }
    let [a, b, c] = p;
    // Sign-extend the 24 bits.
    let mm = i32::from_be_bytes([a, b, c, 0]) >> 8;
    Some(f64::from(mm) * 0.001)
}

/// An epoch being gathered: stream-relative week and GPS time of week.
#[derive(Debug, Clone)]
struct Open<const S: usize> {
    rel_week: i64,
    tow_ms: i64,
    sigs: Vec<Signal, S>,
    glo_tod_ms: Option<i64>,
    overflow: bool,
}

/// A 1020 waiting for the stream's epochs to be dated.
#[derive(Debug, Clone, Copy)]
struct PendingGlonass {
    fields: GlonassIcdFields,
    tb_tod_s: f64,
    near: Option<(i64, i64)>,
}

/// An epoch formed by the receiver: time, the a-priori position used, and
/// the corrected observations in satellite order.
#[derive(Debug, Clone, PartialEq)]
pub struct FormedEpoch<const N: usize> {
    pub time_gps_s: f64,
    /// The linearisation point of the corrections (the bootstrap
    /// solution, else the station position, else none).
    pub reference_m: Option<[f64; 3]>,
    pub sats: Vec<RangeObservation, N>,
    /// The C/N0 of each satellite of `sats` (same order), whole dB-Hz, of
    /// the first signal of the code it was ranged with (the pair's higher
    /// frequency); 0 when the MSM gave none (MSM4-7 carry it).
    pub cn0_dbhz: Vec<u8, N>,
    /// The Doppler input of each satellite of `sats` (same order) for the
    /// velocity solution ([`crate::velocity`]): the phase-range rate of
    /// the signal it was ranged with (`pick_code`'s rule), its velocity and
    /// clock drift at its transmit time; None when the MSM carries no
    /// rate (MSM4/MSM6, or marked invalid) or the epoch has no reference
    /// position.
    pub rates: Vec<Option<RangeRate>, N>,
    /// Satellites seen but not used (no code, no ephemeris, below the
    /// mask, system not used here).
    pub rejected: u32,
}

impl<const N: usize> FormedEpoch<N> {
    /// An empty epoch, to be formed into.
    pub const fn new() -> Self {
        FormedEpoch {
            time_gps_s: 0.0,
            reference_m: None,
            sats: Vec::new(),
            cn0_dbhz: Vec::new(),
            rates: Vec::new(),
            rejected: 0,
        }
    }
}

impl<const N: usize> Default for FormedEpoch<N> {
    fn default() -> Self {
        Self::new()
    }
}

/// The scratch of one epoch's forming, used only inside
/// [`StreamReceiver::on_frame_in`]: the bootstrap solution, its ranges,
/// the transmit states and the epoch's decoded Keplerian sets (`N`
/// satellites). Not on the stack: the epoch's deepest path is the
/// bootstrap solve under the forming.
#[derive(Debug, Clone)]
pub struct FormScratch<const N: usize> {
    /// The bootstrap pass's ranges.
    bootstrap_obs: Vec<RangeObservation, N>,
    /// Each input satellite's state at its transmit time (None: no usable
    /// code pair), computed once for both passes.
    transmit: Vec<Option<SatState>, N>,
    /// The Keplerian sets the epoch uses ([`EphemerisStore::load`]).
    decoded: DecodedSets<N>,
    /// Each input satellite's phase-range rate (the first signal of its
    /// code), m/s.
    rates: Vec<Option<f64>, N>,
    /// Each input satellite's velocity and clock drift at its transmit
    /// time, when it has a rate.
    motion: Vec<Option<SatMotion>, N>,
    /// Where each Keplerian satellite's set is, as its load chose it
    /// ([`EphemerisStore::select_chosen`]).
    chosen: Vec<(SatId, Chosen), N>,
}

impl<const N: usize> FormScratch<N> {
    /// Empty scratch.
    pub const fn new() -> Self {
        FormScratch {
            bootstrap_obs: Vec::new(),
            transmit: Vec::new(),
            decoded: DecodedSets::new(),
            rates: Vec::new(),
            motion: Vec::new(),
            chosen: Vec::new(),
        }
    }
}

impl<const N: usize> Default for FormScratch<N> {
    fn default() -> Self {
        Self::new()
    }
}

/// The receiver: `N` satellites per epoch, `S` signals per epoch.
#[derive(Debug, Clone)]
pub struct StreamReceiver<const N: usize, const S: usize> {
    pivot_week: i64,
    store: EphemerisStore<KEPLER_SETS, GLONASS_SETS>,
    pending_glo: Vec<PendingGlonass, PENDING_GLONASS>,
    /// (GPS week, toe in GPS s) of the first Keplerian ephemeris, until the
    /// stream is dated.
    first_eph: Option<(i64, f64)>,
    base_week: Option<i64>,
    last: Option<(i64, i64)>,
    open: Option<Open<S>>,
    /// The epoch the latest frame closed, until it is formed (held here,
    /// not on the stack).
    ready: Option<Open<S>>,
    glo_wait: Vec<Signal, S>,
    glo_wait_tod_ms: Option<i64>,
    station_m: Option<[f64; 3]>,
    counts: RtcmCounts,
    glonass_arcs: GlonassArcs,
    /// The Keplerian satellites' orbit arcs ([`KeplerArcs`]).
    kepler_arcs: KeplerArcs<KEPLER_ARCS>,
    /// The decoded Keplerian sets kept across epochs.
    #[cfg(not(feature = "ram-192k"))]
    orbits: OrbitCache<ORBIT_CACHE_SETS>,
    /// GPS - UTC of the stream's latest 1013 (DF054), s.
    stream_leap_s: Option<u8>,
    /// The GPS - UTC the GLONASS sets in the store were placed with, s.
    glonass_placed_leap_s: Option<f64>,
    /// GPS time of the latest dated epoch, s.
    latest_gps_s: Option<f64>,
}

impl<const N: usize, const S: usize> StreamReceiver<N, S> {
    /// A receiver that places truncated weeks from `pivot_week` (a GPS
    /// week): 10-bit GPS weeks in `[pivot_week, pivot_week + 1023]`, and
    /// Galileo's and BeiDou's in their own counts
    /// ([`super::fields::gps_week_of`]).
    pub const fn new(pivot_week: i64) -> Self {
        StreamReceiver {
            pivot_week,
            store: EphemerisStore::new(),
            pending_glo: Vec::new(),
            first_eph: None,
            base_week: None,
            last: None,
            open: None,
            ready: None,
            glo_wait: Vec::new(),
            glo_wait_tod_ms: None,
            station_m: None,
            counts: RtcmCounts {
                frames: 0,
                epochs: 0,
                ephemerides: 0,
                ignored: 0,
                undecodable: 0,
                glonass_dropped: 0,
                glonass_bad: 0,
                system_parameters: 0,
                ephemerides_not_kept: 0,
            },
            glonass_arcs: GlonassArcs::new(),
            kepler_arcs: KeplerArcs::new(),
            #[cfg(not(feature = "ram-192k"))]
            orbits: OrbitCache::new(),
            stream_leap_s: None,
            glonass_placed_leap_s: None,
            latest_gps_s: None,
        }
    }

    /// What has been counted so far.
    pub fn counts(&self) -> RtcmCounts {
        self.counts
    }

    /// The ephemerides held (Keplerian, GLONASS).
    pub fn ephemerides(&self) -> (usize, usize) {
        self.store.len()
    }

    /// The leap seconds GLONASS is dated with, and where they come from.
    pub fn leap_seconds(&self) -> LeapSeconds {
        match (self.stream_leap_s, self.latest_gps_s) {
            (Some(n), _) => LeapSeconds::Stream(n),
            (None, None) => LeapSeconds::NotDated,
            (None, Some(t)) => match table_gps_minus_utc_s(t) {
                Some(n) => LeapSeconds::Table(n as u8),
                None => LeapSeconds::TableExpired,
            },
        }
    }

    /// GPS - UTC in force at GPS time `t_gps_s`, for the UTC time and
    /// date of the unit's answers and NMEA sentences: the stream's (1013),
    /// else the table's (past its expiry, its latest count: the
    /// `TableExpired` state of [`Self::leap_seconds`] says the date may
    /// then be a second off; GLONASS is refused).
    pub fn utc_offset_s(&self, t_gps_s: f64) -> f64 {
        self.stream_leap_s
            .map_or_else(|| crate::time::gps_minus_utc_s(t_gps_s), f64::from)
    }

    /// GPS - UTC at GPS time `t_gps_s`: the stream's (1013), else the
    /// table's before its expiry, else unknown.
    fn gps_minus_utc_s(&self, t_gps_s: f64) -> Option<f64> {
        self.stream_leap_s
            .map(f64::from)
            .or_else(|| table_gps_minus_utc_s(t_gps_s))
    }

    /// The station position of the latest 1005/1006, if any.
    pub fn station_m(&self) -> Option<[f64; 3]> {
        self.station_m
    }

    /// Take one whole RTCM 3 frame (preamble to CRC). When it closes an
    /// epoch, that epoch is formed into `out` with the sigmas of `sigmas`
    /// (the configuration's model for the snapshot monitor, or ARAIM's
    /// curves of each satellite's signal pair) and `elevation_mask_rad`,
    /// and `Some` says whether it could be: `Ok(())` with `out` filled, or
    /// why not.
    ///
    /// The forming's scratch is a [`FormScratch`] of this call's own (on
    /// the stack: for the host, whose stack is not counted; the device
    /// lends one, [`Self::on_frame_in`]).
    #[cfg(any(test, feature = "rtcm-rs"))]
    pub fn on_frame(
        &mut self,
        frame: &[u8],
        sigmas: &StreamSigmas,
        elevation_mask_rad: f64,
        out: &mut FormedEpoch<N>,
    ) -> Option<Result<(), FormError>> {
        let mut scratch = FormScratch::new();
        self.on_frame_in(frame, sigmas, elevation_mask_rad, out, &mut scratch)
    }

    /// [`Self::on_frame`] with the forming's scratch in `scratch`: room
    /// used only inside this call, which the owner may use for other work
    /// between calls (raim-server shares it with its answer buffers).
    pub fn on_frame_in(
        &mut self,
        frame: &[u8],
        sigmas: &StreamSigmas,
        elevation_mask_rad: f64,
        out: &mut FormedEpoch<N>,
        scratch: &mut FormScratch<N>,
    ) -> Option<Result<(), FormError>> {
        self.decode(frame);
        let formed = self.form(sigmas, elevation_mask_rad, out, scratch);
        self.ready = None;
        formed
    }

    /// Decode one frame; the epoch it closed, if any, is left in `ready`.
    /// Not inlined: the decoder's state is off the stack before the epoch
    /// is formed.
    #[inline(never)]
    fn decode(&mut self, frame: &[u8]) {
        let Ok(f) = Frame::new(frame) else {
            self.counts.undecodable = self.counts.undecodable.wrapping_add(1);
            return;
        };
        self.counts.frames = self.counts.frames.wrapping_add(1);
        let message = match f.message() {
            Ok(m) => m,
            Err(_) => {
                self.counts.undecodable = self.counts.undecodable.wrapping_add(1);
                self.other_msm(&f, frame);
                return;
            }
        };
        match message {
            Message::Msm(m) => match m.system {
                MsmSystem::Glonass => self.glonass_msm(&m),
                _ => self.timed_msm(&m),
            },
            Message::Kepler(e) => {
                self.counts.ephemerides = self.counts.ephemerides.wrapping_add(1);
                let week = gps_week_of(e.system, e.week_sent, self.pivot_week);
                let mut k = kepler(e.system, e.prn, &e.fields);
                // BeiDou's toc and toe are BDT seconds of the BDT week:
                // toc to GPS (+14 s) for the clock, toe to GPS for the
                // dating, as the host's reader does.
                let bdt_s = if e.system == System::Beidou {
                    BDT_MINUS_GPST_S
                } else {
                    0.0
                };
                k.toc_gps_s = toc_near_toe(week, k.toe_sow_s, e.fields.toc_s - bdt_s);
                if let Stored::NotKept { .. } = self.store.insert_kepler(k, f.payload()) {
                    self.counts.ephemerides_not_kept =
                        self.counts.ephemerides_not_kept.wrapping_add(1);
                }
                if self.first_eph.is_none() {
                    self.first_eph = Some((week, week as f64 * WEEK_S + k.toe_sow_s - bdt_s));
                }
                self.try_date();
            }
            Message::Glo1020 { fields, tb_tod_s } => {
                self.counts.ephemerides = self.counts.ephemerides.wrapping_add(1);
                let p = PendingGlonass {
                    fields,
                    tb_tod_s,
                    near: self.last,
                };
                let placed = match self.base_week {
                    Some(base) => self.place_glonass(base, p),
                    None => false,
                };
                if !placed {
                    // Full: the oldest waiting message gives way.
                    if self.pending_glo.is_full() {
                        remove_at(&mut self.pending_glo, 0);
                    }
                    let _ = self.pending_glo.push(p);
                }
            }
            Message::Station { ecef_m } => {
                self.station_m = Some(ecef_m);
            }
            Message::SystemParameters {
                gps_minus_utc_s, ..
            } => {
                self.counts.system_parameters = self.counts.system_parameters.wrapping_add(1);
                if let Some(n) = gps_minus_utc_s {
                    // GLONASS sets placed with another count are a second
                    // off: dropped at once (the stream resends them).
                    if self
                        .glonass_placed_leap_s
                        .is_some_and(|l| l != f64::from(n))
                    {
                        self.store.clear_glonass();
                        self.glonass_placed_leap_s = None;
                    }
                    self.stream_leap_s = gps_minus_utc_s;
                    if let Some(base) = self.base_week {
                        self.place_pending(base);
                    }
                }
            }
            Message::Other(_) => {
                self.counts.ignored = self.counts.ignored.wrapping_add(1);
                self.other_msm(&f, frame)
            }
        }
    }

    /// A message not used here (or not decoded): another system's MSM
    /// still ends the epoch when its multiple-message bit is 0 (the
    /// epoch's last message).
    fn other_msm(&mut self, f: &Frame<'_>, frame: &[u8]) {
        let msm = f.number().is_some_and(|n| (1071..=1137).contains(&n));
        if msm && msm_more_bit(frame) == Some(false) {
            self.close();
        }
    }

    /// A GPS, Galileo, QZSS or BeiDou MSM: its data joins the epoch at its
    /// GPS time of week (GPS DF004, Galileo DF248, QZSS DF428; BeiDou
    /// DF427 + 14 s, or the open epoch's when DF427 equals it); DF393 = 0
    /// closes it.
    fn timed_msm(&mut self, m: &Msm<'_>) {
        let epoch_ms = i64::from(m.epoch_ms);
        let mut tow_ms = if m.system == MsmSystem::Beidou {
            (epoch_ms - (BDT_MINUS_GPST_S * 1000.0) as i64).rem_euclid(WEEK_MS)
        } else {
            epoch_ms.rem_euclid(WEEK_MS)
        };
        if let Some(o) = self.open.as_ref() {
            if m.system == MsmSystem::Beidou && o.tow_ms == epoch_ms.rem_euclid(WEEK_MS) {
                tow_ms = o.tow_ms;
            }
        }
        if self.open.as_ref().is_some_and(|o| o.tow_ms != tow_ms) {
            self.close();
        }
        if self.open.is_none() {
            let rel_week = match self.last {
                Some((w, t)) if tow_ms < t - WEEK_MS / 2 => w + 1,
                Some((w, _)) => w,
                None => 0,
            };
            self.last = Some((rel_week, tow_ms));
            let glo_tod_ms = self.glo_wait_tod_ms.take();
            // Built in place (the signal list is kilobytes).
            let o = self.open.insert(Open {
                rel_week,
                tow_ms,
                sigs: Vec::new(),
                glo_tod_ms,
                overflow: false,
            });
            for s in self.glo_wait.iter() {
                o.overflow |= o.sigs.push(*s).is_err();
            }
            self.glo_wait.clear();
            self.try_date();
        }
        if let Some(o) = self.open.as_mut() {
            for s in msm_signals(m, m.system.system()) {
                o.overflow |= o.sigs.push(s).is_err();
            }
        }
        if !m.more {
            // An epoch closed while another waits to be formed: the
            // earlier one is the one handed over (a stream never closes
            // two in one frame unless its epochs hold no data).
            self.close();
        }
    }

    /// A GLONASS MSM: its data joins the open epoch with its GLONASS time
    /// of day (DF034), or waits for the epoch's GPS MSM.
    fn glonass_msm(&mut self, m: &Msm<'_>) {
        let tod_ms = i64::from(m.epoch_ms);
        match self.open.as_mut() {
            Some(o) => {
                o.glo_tod_ms = o.glo_tod_ms.or(Some(tod_ms));
                for s in msm_signals(m, System::Glonass) {
                    o.overflow |= o.sigs.push(s).is_err();
                }
                if !m.more {
                    self.close();
                }
            }
            None => {
                // Another time of day, or a satellite already waiting: the
                // waiting data was an epoch of GLONASS alone.
                let again = msm_signals(m, System::Glonass)
                    .take(S)
                    .any(|s| self.glo_wait.iter().any(|w| w.id == s.id));
                if again || self.glo_wait_tod_ms.is_some_and(|t| t != tod_ms) {
                    self.drop_glonass_wait();
                }
                self.glo_wait_tod_ms = Some(tod_ms);
                for s in msm_signals(m, System::Glonass) {
                    let _ = self.glo_wait.push(s);
                }
                if !m.more {
                    self.drop_glonass_wait();
                }
            }
        }
    }

    /// GLONASS data with no GPS MSM to date it: dropped and counted.
    fn drop_glonass_wait(&mut self) {
        if !self.glo_wait.is_empty() {
            self.counts.glonass_dropped = self.counts.glonass_dropped.wrapping_add(1);
        }
        self.glo_wait.clear();
        self.glo_wait_tod_ms = None;
    }

    /// Close the open epoch, if any: it is the one formed after this frame
    /// unless the frame already closed one (a stream never closes two in
    /// one frame unless its epochs hold no data), then it is dropped.
    fn close(&mut self) {
        if self.open.is_none() {
            return;
        }
        self.counts.epochs = self.counts.epochs.wrapping_add(1);
        if self.ready.is_none() {
            core::mem::swap(&mut self.ready, &mut self.open);
        }
        self.open = None;
    }

    /// Date the stream from the first Keplerian ephemeris and the latest
    /// epoch: the GPS week (of the three around the ephemeris') that puts
    /// that epoch nearest the toe; then place the waiting 1020s.
    fn try_date(&mut self) {
        if self.base_week.is_some() {
            return;
        }
        let (Some((week, toe_gps_s)), Some((rel, tow_ms))) = (self.first_eph, self.last) else {
            return;
        };
        let tow_s = tow_ms as f64 / 1000.0;
        let dist = |w: i64| (w as f64 * WEEK_S + tow_s - toe_gps_s).abs();
        let mut w = week;
        for c in [week - 1, week + 1] {
            if dist(c) < dist(w) {
                w = c;
            }
        }
        let base = w - rel;
        self.base_week = Some(base);
        self.place_pending(base);
    }

    /// Place the waiting 1020s that can be: in arrival order, one at a
    /// time (not the whole list on the stack); those whose leap seconds
    /// are unknown wait on.
    fn place_pending(&mut self, base: i64) {
        let mut i = 0;
        while let Some(p) = self.pending_glo.get(i).copied() {
            if self.place_glonass(base, p) {
                remove_at(&mut self.pending_glo, i);
            } else {
                i += 1;
            }
        }
    }

    /// A 1020 in GPS time, checked and stored; false when it cannot be
    /// placed yet (no epoch to place it by, or GPS - UTC unknown). Its
    /// t_b is a time of the Moscow day: GPS - UTC places it. When the
    /// count differs from the one the stored GLONASS sets were placed with
    /// (a 1013 that corrects the table, or the table across a leap
    /// second), those sets are dropped: each may be a second off (3.9 km
    /// along its orbit); the stream resends them.
    fn place_glonass(&mut self, base: i64, p: PendingGlonass) -> bool {
        let Some((rel, tow_ms)) = p.near.or(self.last) else {
            return false;
        };
        let near_gps_s = (base + rel) as f64 * WEEK_S + tow_ms as f64 / 1000.0;
        let Some(leap_s) = self.gps_minus_utc_s(near_gps_s) else {
            return false;
        };
        if self.glonass_placed_leap_s.is_some_and(|l| l != leap_s) {
            self.store.clear_glonass();
        }
        self.glonass_placed_leap_s = Some(leap_s);
        let fields = GlonassIcdFields {
            tb_gps_s: glonass_time_of_day_to_gps_with_s(p.tb_tod_s, near_gps_s, leap_s),
            ..p.fields
        };
        match GlonassEphemeris::from_icd(&fields) {
            Ok(g) => {
                let _: Stored = self.store.insert_glonass(g);
            }
            Err(_) => self.counts.glonass_bad = self.counts.glonass_bad.wrapping_add(1),
        }
        true
    }

    /// Form the epoch the latest frame closed, if any, into `out` (in
    /// place: the epoch is not copied onto the stack).
    #[inline(never)]
    fn form(
        &mut self,
        sigmas: &StreamSigmas,
        elevation_mask_rad: f64,
        out: &mut FormedEpoch<N>,
        scratch: &mut FormScratch<N>,
    ) -> Option<Result<(), FormError>> {
        let leap_s = match (self.base_week, self.ready.as_ref()) {
            (Some(base), Some(o)) => {
                let t = (base + o.rel_week) as f64 * WEEK_S + o.tow_ms as f64 / 1000.0;
                self.latest_gps_s = Some(t);
                self.gps_minus_utc_s(t)
            }
            _ => None,
        };
        let Self {
            ready,
            base_week,
            counts,
            store,
            station_m,
            glonass_arcs,
            kepler_arcs,
            #[cfg(not(feature = "ram-192k"))]
            orbits,
            ..
        } = self;
        // No set is kept across epochs with `ram-192k`: an empty cache of
        // no capacity (the store's own load and select).
        #[cfg(feature = "ram-192k")]
        let orbits = &mut OrbitCache::<0>::new();
        let FormScratch {
            bootstrap_obs: first,
            transmit,
            decoded,
            rates,
            motion,
            chosen,
        } = scratch;
        let o = ready.as_mut()?;
        out.sats.clear();
        out.cn0_dbhz.clear();
        out.rates.clear();
        out.rejected = 0;
        out.reference_m = None;
        let Some(base) = *base_week else {
            out.time_gps_s = o.tow_ms as f64 / 1000.0;
            return Some(Err(FormError::NotDated { tow_ms: o.tow_ms }));
        };
        let time_gps_s = (base + o.rel_week) as f64 * WEEK_S + o.tow_ms as f64 / 1000.0;
        out.time_gps_s = time_gps_s;
        if o.overflow {
            return Some(Err(FormError::TooManySignals {
                capacity: u32::try_from(S).unwrap_or(u32::MAX),
            }));
        }
        if let Some(tod_ms) = o.glo_tod_ms {
            let Some(leap_s) = leap_s else {
                return Some(Err(FormError::LeapSecondsUnknown { tow_ms: o.tow_ms }));
            };
            let want_ms = m::round(glonass_time_of_day_with_s(time_gps_s, leap_s) * 1000.0) as i64;
            if (tod_ms - want_ms).rem_euclid(DAY_MS) != 0 {
                o.sigs.retain(|s| s.id.system != System::Glonass);
                counts.glonass_dropped = counts.glonass_dropped.wrapping_add(1);
            }
        }
        // Satellite order, as the host's epochs (a BTreeMap by SatId).
        sort_checked(&mut o.sigs, |a, b| {
            (a.id, a.band_digit, a.attribute) < (b.id, b.band_digit, b.attribute)
        });
        // The Keplerian sets the satellites with a code will use: kept
        // from an earlier epoch with their orbits' constants (`orbits`),
        // else decoded from the store's payloads (and kept when there is
        // room); more than N decoded for the epoch alone is the capacity
        // refusal the inputs below would give.
        store.start_epoch(decoded);
        orbits.next_epoch();
        chosen.clear();
        let mut from = 0;
        while let Some((id, have)) = next_satellite(&o.sigs, &mut from) {
            if pick_code(stream_codes(id.system), have).is_some() {
                // A satellite with a Keplerian set in force is an input
                // below: more than N of them is the capacity refusal the
                // inputs would give.
                let kept = match store.load_cached(id, time_gps_s, decoded, orbits) {
                    Ok(c @ (Chosen::Kept(_) | Chosen::Decoded(_))) => chosen.push((id, c)).is_ok(),
                    Ok(_) => true,
                    Err(_) => false,
                };
                if !kept {
                    return Some(Err(FormError::TooManySignals {
                        capacity: u32::try_from(N).unwrap_or(u32::MAX),
                    }));
                }
            }
        }
        let mut inputs: Vec<SatInput<'_>, N> = Vec::new();
        // The C/N0 of each input, in the same order.
        let mut cn0s: Vec<u8, N> = Vec::new();
        rates.clear();
        let mut previous: Option<SatId> = None;
        for s in o.sigs.iter() {
            if previous == Some(s.id) {
                continue;
            }
            previous = Some(s.id);
            let have: &[Signal] = {
                let start = o.sigs.iter().position(|x| x.id == s.id).unwrap_or(0);
                let len = o
                    .sigs
                    .iter()
                    .skip(start)
                    .take_while(|x| x.id == s.id)
                    .count();
                o.sigs.get(start..start + len).unwrap_or(&[])
            };
            let Some((code, p1_m, p2_m, cn0, rate)) = pick_code(stream_codes(s.id.system), have)
            else {
                out.rejected += 1;
                continue;
            };
            // The set as its load chose it (a GLONASS set chosen here).
            let c = match s.id.system {
                System::Glonass => Chosen::Glonass,
                _ => chosen
                    .iter()
                    .find(|(id, _)| *id == s.id)
                    .map_or(Chosen::None, |(_, c)| *c),
            };
            let Some(eph) = store.select_chosen(s.id, time_gps_s, c, decoded, orbits) else {
                out.rejected += 1;
                continue;
            };
            let input = SatInput {
                id: s.id,
                code,
                p1_m,
                p2_m,
                eph,
                orbit_arc: true,
            };
            if inputs.push(input).is_err() || cn0s.push(cn0).is_err() || rates.push(rate).is_err() {
                return Some(Err(FormError::TooManySignals {
                    capacity: u32::try_from(N).unwrap_or(u32::MAX),
                }));
            }
        }
        // Each satellite's sigma is set below (`stream_sigma_for_m`), so
        // the corrections give none.
        let c = Corrections {
            elevation_mask_rad,
            iono: false,
            tropo: true,
            group_delay: true,
            glonass_sigma: None,
        };
        // Each satellite's orbit and clock at its transmit time, once for
        // both passes (the transmit time does not depend on the receiver
        // position); a GLONASS orbit from its arc.
        // A satellite with a phase-range rate: its velocity and clock
        // drift there too, from the same evaluation (a GLONASS velocity
        // from the same integration; a Keplerian satellite's state and
        // motion from its orbit arc, `KeplerArcs`: kept, or evaluated
        // afresh beyond the arcs' capacity, the same bits).
        glonass_arcs.next_epoch();
        kepler_arcs.next_epoch();
        transmit.clear();
        motion.clear();
        for (s, rate) in inputs.iter().zip(rates.iter()) {
            let t_sv = signal_sent_s(s, time_gps_s).ok();
            let (tx, mo) = match s.eph {
                Broadcast::Glonass(g) => match transmit_time_s(s, time_gps_s) {
                    Ok(t) => {
                        let (state, v) = glonass_arcs.state(g, t);
                        (Some(state), rate.map(|_| glonass_motion(v, g.gamma_n)))
                    }
                    Err(_) => (None, None),
                },
                Broadcast::Orbit(o) => match t_sv {
                    Some(t_sv) => {
                        let (_, state, mo) = kepler_arcs.transmit_state_motion(s.id, o, t_sv);
                        (Some(state), rate.map(|_| mo))
                    }
                    None => (None, None),
                },
                Broadcast::Kepler(k) => match t_sv {
                    Some(t_sv) => {
                        let (_, state, mo) =
                            kepler_arcs.transmit_state_motion_of(s.id, k, t_sv, || Orbit::new(k));
                        (Some(state), rate.map(|_| mo))
                    }
                    None => (None, None),
                },
            };
            // `inputs`, `transmit` and `motion` have the same capacity N.
            let _ = transmit.push(tx);
            let _ = motion.push(mo);
        }
        // The bootstrap pass: clock- and rotation-corrected ranges.
        let apriori = *station_m;
        first.clear();
        for (s, tx) in inputs.iter().zip(transmit.iter()) {
            let Some(tx) = tx else { continue };
            if let Ok(x) = correct_at(s, time_gps_s, tx, apriori, None, false, &c, None) {
                let _ = first.push(x.obs);
            }
        }
        let reference = bootstrap_position::<N>(first, apriori).or(apriori);
        out.reference_m = reference;
        // Every correction at the reference; with none (the bootstrap
        // failed and no station position), the bootstrap pass's ranges, as
        // the host hands them over.
        // The receiver's frame (geodetic position, local-level rotation,
        // zenith troposphere), once for every satellite.
        let rx_frame = reference.map(ReceiverFrame::at);
        for (((s, tx), cn0), (rate, mo)) in inputs
            .iter()
            .zip(transmit.iter())
            .zip(cn0s.iter())
            .zip(rates.iter().zip(motion.iter()))
        {
            let Some(tx) = tx else {
                out.rejected += 1;
                continue;
            };
            match correct_at_without_azimuth(
                s,
                time_gps_s,
                tx,
                reference,
                rx_frame.as_ref(),
                reference.is_some(),
                &c,
            ) {
                Ok(mut x) => {
                    x.obs.sigma_m = Some(stream_sigma_for_m(
                        sigmas,
                        s.id.system,
                        s.code,
                        x.elevation_rad,
                        NO_MODEL_IONO_FACTOR,
                    ));
                    let doppler = match (rate, mo, reference) {
                        (Some(r), Some(mo), Some(rx)) => {
                            Some(range_rate(*r, mo, x.obs.position_m, rx))
                        }
                        _ => None,
                    };
                    // `out.sats`, `out.cn0_dbhz` and `out.rates` have the
                    // capacity N of `inputs`, and are filled together.
                    if out.sats.push(x.obs).is_ok() {
                        let _ = out.cn0_dbhz.push(*cn0);
                        let _ = out.rates.push(doppler);
                    }
                }
                Err(_) => out.rejected += 1,
            }
        }
        Some(Ok(()))
    }
}

/// The next satellite of `sigs` (sorted by satellite) from `*from` on,
/// and its signals, advancing `*from` past them; None at the end.
fn next_satellite<'s>(sigs: &'s [Signal], from: &mut usize) -> Option<(SatId, &'s [Signal])> {
    let rest = sigs.get(*from..)?;
    let id = rest.first()?.id;
    let len = rest.iter().take_while(|s| s.id == id).count();
    *from += len;
    Some((id, rest.get(..len)?))
}

/// An MSM's signals with a valid pseudorange, in cell order.
fn msm_signals<'m>(m: &'m Msm<'_>, system: System) -> impl Iterator<Item = Signal> + 'm {
    m.signals().filter_map(move |s| {
        Some(Signal {
            id: SatId::new(system, s.sat_id),
            band_digit: b'0' + s.band,
            attribute: s.attribute,
            cn0_dbhz: cn0_dbhz_u8(s.cnr_dbhz),
            rate: pack_rate_mm_s(s.phase_range_rate_m_s),
            value_m: s.pseudorange_m?,
        })
    })
}

/// The first preferred code present: a single code, or a pair (both
/// present) for the iono-free combination; with the C/N0 of its (first)
/// signal and the satellite's phase-range rate: its (first) signal's,
/// else the pair's second's, else the first of the satellite's other
/// signals (in code order) that has one (a range rate is the same on
/// every carrier but for the ionosphere's rate, a few mm/s; a receiver
/// may send it on one signal only, e.g. GMSD7 on L1 C/A, not on the P
/// codes GLONASS is ranged with).
#[allow(clippy::type_complexity)]
fn pick_code<'c>(
    codes: &[&'c str],
    have: &[Signal],
) -> Option<(&'c str, f64, Option<f64>, u8, Option<f64>)> {
    let find = |c: &str| have.iter().find(|s| s.is_code(c));
    let any_rate = || have.iter().find_map(Signal::rate_m_s);
    codes.iter().find_map(|&c| match split_pair(c) {
        Some((a, b)) => {
            let (first, second) = (find(a)?, find(b)?);
            let rate = first
                .rate_m_s()
                .or_else(|| second.rate_m_s())
                .or_else(any_rate);
            Some((c, first.value_m, Some(second.value_m), first.cn0_dbhz, rate))
        }
        None => find(c).map(|s| {
            (
                c,
                s.value_m,
                None,
                s.cn0_dbhz,
                s.rate_m_s().or_else(any_rate),
            )
        }),
    })
}

/// Sorts `v` by `less` (stable insertion sort: the stream's signals come
/// sorted within each message, so it is close to linear), with checked
/// accesses only: `core`'s sort carries a panic path
/// (`panic_on_ord_violation`) into the firmware (docs/EVIDENCE.md "Panic
/// sites").
fn sort_checked<T: Copy>(v: &mut [T], less: impl Fn(&T, &T) -> bool) {
    for i in 1..v.len() {
        let mut j = i;
        while j > 0 && j < v.len() {
            match (v.get(j - 1), v.get(j)) {
                (Some(a), Some(b)) if less(b, a) => v.swap(j - 1, j),
                _ => break,
            }
            j -= 1;
        }
    }
}

/// Removes the element at `index`, keeping the others in order; nothing
/// when there is none (heapless's `Vec::remove` would panic there: the
/// stream receiver links no panic path, docs/EVIDENCE.md "Panic sites").
fn remove_at<T, const N: usize>(v: &mut heapless::Vec<T, N>, index: usize) {
    let mut k = 0usize;
    v.retain(|_| {
        let keep = k != index;
        k += 1;
        keep
    });
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::{pack_rate_mm_s, remove_at, sort_checked, unpack_rate_mm_s, Signal, NO_RATE};
    use std::vec::Vec;

    /// The checked insertion sort orders as the standard stable sort
    /// (ties keep their arrival order), on sorted, reversed, blocked and
    /// pseudo-random inputs with ties.
    #[test]
    fn sort_checked_equals_the_stable_sort() {
        let mut x = 12345u64;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let mut cases: Vec<Vec<(u8, usize)>> = std::vec![
            Vec::new(),
            (0..50).map(|i| (i as u8, i)).collect(),
            (0..50).rev().map(|i| (i as u8, i)).collect(),
            (0..60).map(|i| ((i % 20) as u8, i)).collect(),
        ];
        for n in [1usize, 2, 7, 100, 256] {
            cases.push((0..n).map(|i| ((next() % 16) as u8, i)).collect());
        }
        for c in cases {
            let mut want = c.clone();
            want.sort_by_key(|a| a.0);
            let mut got = c.clone();
            sort_checked(&mut got, |a, b| a.0 < b.0);
            assert_eq!(got, want);
        }
    }

    /// A signal stays in 16 bytes with its rate (three per signal of an
    /// epoch: 768 signals on the default build, 360 on the STM32F4's).
    #[test]
    fn signal_takes_16_bytes() {
        assert_eq!(core::mem::size_of::<Signal>(), 16);
    }

    /// A rate is packed to the millimetre per second and back, both signs,
    /// DF399's extremes and the marks; beyond 24 bits, none.
    ///
    /// Verifies: RX-DOPPLER
    #[test]
    fn rates_pack_to_the_millimetre() {
        for r in [
            0.0,
            0.0004,
            -0.0004,
            0.0006,
            1.2345,
            -1.2345,
            799.9999,
            -8191.9999,
            8191.0 + 1.6383,
            -8192.0 + 0.0001,
        ] {
            let back = unpack_rate_mm_s(pack_rate_mm_s(Some(r))).unwrap();
            assert!((back - r).abs() <= 0.0005 + 1e-12, "{r} -> {back}");
            assert_eq!(back, (r * 1000.0).round() * 0.001, "{r}");
        }
        assert_eq!(unpack_rate_mm_s(pack_rate_mm_s(None)), None);
        assert_eq!(pack_rate_mm_s(Some(8389.0)), NO_RATE);
        assert_eq!(pack_rate_mm_s(Some(f64::NAN)), NO_RATE);
        assert_eq!(
            unpack_rate_mm_s(pack_rate_mm_s(Some(-8388.607))),
            Some(-8388.607)
        );
    }

    /// Removing by index keeps the order of the rest; an index past the
    /// end removes nothing.
    #[test]
    fn remove_at_keeps_the_order() {
        let mut v: heapless::Vec<u8, 8> = heapless::Vec::from_slice(&[1, 2, 3, 4]).unwrap();
        remove_at(&mut v, 0);
        assert_eq!(v.as_slice(), &[2, 3, 4]);
        remove_at(&mut v, 1);
        assert_eq!(v.as_slice(), &[2, 4]);
        remove_at(&mut v, 9);
        assert_eq!(v.as_slice(), &[2, 4]);
    }
}

#[cfg(test)]
#[path = "receiver_arcs_tests.rs"]
mod receiver_arcs_tests;
