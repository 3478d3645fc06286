//! RTCM 3 (RTCM 10403.x) to observation epochs and broadcast ephemerides.
//!
//! The `rtcm-rs` crate checks each frame (preamble 0xD3, 10-bit length,
//! CRC-24Q) and decodes its message; this module finds the frames in a
//! byte stream, counts what it skips, and turns the messages into the
//! `raim-gnss` types:
//! - MSM4-MSM7 (GPS 1074-1077, GLONASS 1084-1087, Galileo 1094-1097, QZSS
//!   1114-1117, BeiDou 1124-1127): pseudorange = (rough range + fine range)
//!   x c / 1000 (RTCM 10403.3 §3.5.16, DF397 + DF398 + DF400/DF405), one
//!   RINEX 3 code per signal ("C" + band + attribute: C1C, C2W, C2I, ...).
//!   The epoch is complete at the message whose multiple-message bit
//!   (DF393) is 0, or when the time changes.
//! - Legacy GPS 1002/1004: L1 = DF011 + DF014 x 299,792.458 m, L2 = L1 +
//!   DF017. 1001/1003 carry no ambiguity (the range modulo one
//!   light-millisecond): decoded and counted, not used.
//! - Legacy GLONASS 1010/1012: L1 = DF041 + DF044 (the integer number of
//!   599,584.916 m, two light-milliseconds), L2 = L1 + DF047 (code by
//!   DF039/DF046: C/A or P); timed like the GLONASS MSM, by the GLONASS
//!   time of day (DF034), joining the epoch they arrive with. 1009/1011
//!   carry no ambiguity: counted, not used.
//! - Ephemerides 1019 (GPS), 1042 (BeiDou), 1044 (QZSS), 1045 (Galileo
//!   F/NAV), 1046 (Galileo I/NAV) to [`Kepler`]; 1020 (GLONASS) to
//!   [`GlonassEphemeris`] (see [`glonass_fields`] for the units).
//! - GLONASS MSM carry the GLONASS time of day (DF034, UTC(SU) + 3 h, and
//!   the day of the week DF416), not a GPS time of week: they join the
//!   epoch of the GPS/Galileo/BeiDou MSM they arrive with, and once the
//!   epoch's absolute GPS time t is known, their DF034 must equal the
//!   GLONASS time of day of t (GPS - UTC from the stream's latest RTCM
//!   1013, DF054, else from the leap-second table,
//!   `raim_gnss::glonass::glonass_time_of_day_with_s`), to the millisecond;
//!   otherwise the epoch's GLONASS data is dropped and counted
//!   ([`GLONASS_TIME_MISMATCH`]). MSM5/MSM7 also carry each satellite's
//!   frequency channel (DF419), kept for checks
//!   ([`Rtcm3::msm_frequency_channels`]); the ranging takes the channel
//!   from the satellite's 1020 (an MSM range is in metres whatever the
//!   carrier, and without a 1020 there is no orbit to use it with).
//! - Station 1005/1006: the antenna reference point, ECEF.
//! - System parameters 1013: GPS - UTC (DF054) for the GLONASS times, as
//!   the unit takes it (`raim_nav::rtcm::StreamReceiver`): a count that
//!   differs from the one the GLONASS sets given so far were placed with
//!   withdraws them ([`Item::GlonassWithdrawn`]; each would be a second,
//!   ~3.9 km, off), and the stream's next 1020s are placed with it.
//!
//! RTCM epoch times are seconds of the week (BeiDou: of the BDT week, GPS
//! = BDT + 14 s) and ephemeris weeks are modulo 1024 (GPS, QZSS), 4096
//! (Galileo) or 8192 (BeiDou). The stream's own weeks are counted from its
//! first epoch (one more at each wrap of the time of week), and the whole
//! stream is placed in absolute GPS time by its first ephemeris: the 10-bit
//! week is taken as the latest one not after this computer's clock, and the
//! epoch nearest that ephemeris' toe fixes the week of the epochs. Epochs
//! before the first ephemeris wait for it.

use std::collections::BTreeMap;

use raim_core::{SatId, System};
use raim_gnss::ephemeris::{Kepler, BDT_MINUS_GPST_S, WEEK_S};
use raim_gnss::glonass::{
    glonass_time_of_day_to_gps_with_s, glonass_time_of_day_with_s, GlonassEphemeris,
    GlonassIcdFields,
};
use raim_gnss::rinex_io::{CodeObs, SignalRate};
use raim_gnss::ObsEpoch;
use rtcm_rs::msg::message::Message;
use rtcm_rs::MessageFrame;

use crate::{Counts, Decoder, Item};

use raim_nav::rtcm::fx;
pub use raim_nav::rtcm::{glonass_fields, kepler, latest_week, KeplerFields, LIGHT_MS_M};
use raim_nav::rtcm::{
    msg1019_fields, msg1042_fields, msg1044_fields, msg1045_fields, msg1046_fields, BDT_WEEK0_GPS,
    GST_WEEK0_GPS,
};
/// Milliseconds in a week.
const WEEK_MS: i64 = 604_800_000;
/// The `Counts::ignored` key of epochs that hold GLONASS MSM only.
pub const GLONASS_ALONE: &str =
    "GLONASS-only MSM epoch (no GPS, Galileo or BeiDou MSM to give its GPS time)";
/// The `Counts::ignored` key of GLONASS MSM data whose GLONASS time of day
/// is not the epoch's (dropped from the epoch).
pub const GLONASS_TIME_MISMATCH: &str =
    "GLONASS MSM whose time of day is not its epoch's (GLONASS data dropped)";
/// The `Counts::ignored` key of 1020 messages outside the ICD's ranges.
pub const GLONASS_BAD_1020: &str = "1020 (a field outside the GLONASS ICD's range)";
/// Milliseconds in a day.
const DAY_MS: i64 = 86_400_000;
/// Largest RTCM 3 frame: 3 header bytes, 1023 payload bytes, 3 CRC bytes.
const MAX_FRAME: usize = 1029;

/// The GPS week now by this computer's clock (the latest week a stream's
/// modulo-1024 week can be).
pub fn gps_week_now() -> i64 {
    let unix_s = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0);
    // GPS epoch 1980-01-06 is Unix 315964800; leap seconds (< 1 min) do not
    // move the week by more than a minute.
    ((unix_s - 315_964_800.0) / WEEK_S).floor() as i64
}

/// An ephemeris as broadcast: weeks and times not yet anchored.
#[derive(Debug, Clone, Copy)]
struct PendingEph {
    k: Kepler,
    /// Full GPS week of the ephemeris' week field (BeiDou/Galileo converted).
    week_gps: i64,
    /// toc in seconds of that week in the GPS scale.
    toc_gps_sow_s: f64,
}

/// An epoch being assembled: stream-relative week, GPS time of week (ms).
#[derive(Debug, Default)]
struct Open {
    rel_week: i64,
    tow_ms: i64,
    sats: BTreeMap<SatId, Vec<CodeObs>>,
    /// GLONASS time of day of its GLONASS MSM (DF034), ms.
    glo_tod_ms: Option<i64>,
}

/// A 1020 waiting for the stream's week: its fields (t_b still a time of
/// the Moscow day) and the stream-relative time of the latest epoch when
/// it came.
#[derive(Debug, Clone, Copy)]
struct PendingGlonass {
    fields: GlonassIcdFields,
    tb_tod_s: f64,
    near: Option<(i64, i64)>,
}

/// The most a kept phase-range rate may be, whole mm/s (24-bit two's
/// complement, as raim-nav's receiver packs it).
const UNIT_RATE_LIMIT_MM_S: f64 = (1 << 23) as f64;

/// An MSM phase-range rate (DF399 + DF404, m/s) as the unit's receiver
/// keeps it (raim-nav's `rtcm::receiver`, "Speed and course" in
/// docs/RECEIVERS.md): rounded to whole mm/s (half away from zero), none
/// at or beyond 2^23 mm/s or not finite; so that the host's replay of a
/// stream solves the unit's velocity to the bit.
pub fn unit_rate_m_s(rate_m_s: f64) -> Option<f64> {
    let mm = (rate_m_s * 1000.0).round();
    // |mm| < 2^23: exact in i32.
    (mm.abs() < UNIT_RATE_LIMIT_MM_S).then(|| f64::from(mm as i32) * 0.001)
}

/// The RTCM 3 decoder (see the module documentation).
#[derive(Debug)]
pub struct Rtcm3 {
    buf: Vec<u8>,
    counts: Counts,
    now_week: i64,
    /// Stream-relative week of the latest epoch and its time of week.
    last: Option<(i64, i64)>,
    open: Option<Open>,
    /// GLONASS MSM data waiting for the epoch it belongs to.
    glonass_wait: BTreeMap<SatId, Vec<CodeObs>>,
    /// The GLONASS time of day of the waiting data, ms.
    glonass_wait_tod_ms: Option<i64>,
    /// The GLONASS time of day of the MSM being decoded, ms.
    glo_msg_tod_ms: Option<i64>,
    /// Frequency channel per GLONASS slot from MSM5/MSM7 (DF419).
    msm_fcn: BTreeMap<u8, i8>,
    /// 1020 messages before the anchor.
    pending_glo: Vec<PendingGlonass>,
    /// Week of the stream's relative week 0, once anchored.
    base_week: Option<i64>,
    /// Epochs (relative week, tow ms, data) before the anchor.
    waiting: Vec<Open>,
    pending_eph: Vec<PendingEph>,
    /// GPS - UTC from the stream's latest 1013 (DF054), s.
    stream_leap_s: Option<u8>,
    /// The GPS - UTC the GLONASS sets given so far were placed with, s.
    glonass_placed_leap_s: Option<f64>,
}

impl Default for Rtcm3 {
    fn default() -> Self {
        Self::new(gps_week_now())
    }
}

impl Rtcm3 {
    /// A decoder that resolves 10-bit weeks against `now_week`.
    pub fn new(now_week: i64) -> Self {
        Rtcm3 {
            buf: Vec::new(),
            counts: Counts::default(),
            now_week,
            last: None,
            open: None,
            glonass_wait: BTreeMap::new(),
            glonass_wait_tod_ms: None,
            glo_msg_tod_ms: None,
            msm_fcn: BTreeMap::new(),
            pending_glo: Vec::new(),
            base_week: None,
            waiting: Vec::new(),
            pending_eph: Vec::new(),
            stream_leap_s: None,
            glonass_placed_leap_s: None,
        }
    }

    /// GPS - UTC at GPS time `t_gps_s`: the stream's latest 1013, else the
    /// leap-second table's.
    fn gps_minus_utc_s(&self, t_gps_s: f64) -> f64 {
        self.stream_leap_s
            .map_or_else(|| raim_gnss::glonass::gps_minus_utc_s(t_gps_s), f64::from)
    }

    /// GPS - UTC from the stream (RTCM 1013), if one has been received.
    pub fn stream_leap_seconds(&self) -> Option<u8> {
        self.stream_leap_s
    }

    fn frames(&mut self, out: &mut Vec<Item>, at_end: bool) {
        let mut i = 0;
        let buf = std::mem::take(&mut self.buf);
        while i < buf.len() {
            let Some(b) = buf.get(i..) else { break };
            if b.first() != Some(&0xD3) {
                self.counts.garbage_bytes += 1;
                i += 1;
                continue;
            }
            match MessageFrame::new(b) {
                Ok(f) => {
                    self.counts.frames += 1;
                    let len = f.frame_len();
                    let number = f.message_number();
                    let msg = f.get_message();
                    self.message(number, msg, out);
                    i += len.max(1);
                }
                Err(rtcm_rs::rtcm_error::RtcmError::Incomplete) => {
                    if at_end {
                        self.counts.truncated_tail_bytes += b.len() as u64;
                        i = buf.len();
                    }
                    break;
                }
                Err(_) => {
                    // A header that looks like a frame (6 reserved bits 0,
                    // the whole frame present) whose CRC fails is a bad
                    // frame; anything else is a stray 0xD3.
                    let plausible = b.get(1).is_some_and(|h| h & 0xFC == 0) && b.len() >= 6 && {
                        let n = ((usize::from(b[1] & 3)) << 8) | usize::from(b[2]);
                        b.len() >= n + 6
                    };
                    if plausible {
                        self.counts.bad_checksum += 1;
                    }
                    self.counts.garbage_bytes += 1;
                    i += 1;
                }
            }
        }
        self.buf = buf.get(i..).map(<[u8]>::to_vec).unwrap_or_default();
        // A buffer that cannot hold a frame start any more is garbage.
        if self.buf.len() > 4 * MAX_FRAME {
            let drop = self.buf.len() - MAX_FRAME;
            self.counts.garbage_bytes += drop as u64;
            self.buf.drain(..drop);
        }
    }

    fn ignore(&mut self, what: String) {
        *self.counts.ignored.entry(what).or_default() += 1;
    }

    fn message(&mut self, number: Option<u16>, msg: Message, out: &mut Vec<Item>) {
        let n = number.unwrap_or(0);
        // The phase-range rate of an MSM5/MSM7 signal (DF399 + DF404, as
        // the unit keeps it: [`unit_rate_m_s`]); MSM4/MSM6 carry none.
        macro_rules! rate {
            (rate, $m:ident, $sig:ident) => {
                $m.data_segment
                    .satellite_data
                    .iter()
                    .find(|s| s.satellite_id == $sig.satellite_id)
                    .and_then(|s| s.gnss_satellite_rough_phaserange_rates_m_s)
                    .zip($sig.gnss_signal_fine_phaserange_rate_m_s)
                    .and_then(|(rough, fine)| unit_rate_m_s(f64::from(rough) + fine))
                    .map(|m_s| SignalRate::RangeRate { m_s })
            };
            (norate, $m:ident, $sig:ident) => {
                None
            };
        }
        macro_rules! msm {
            ($m:expr, $time:expr, $sys:expr, $fine:ident, $cnr:ident, $rate:ident) => {{
                msm!($m, $time, $sys, $fine, $cnr, None, $rate)
            }};
            ($m:expr, $time:expr, $sys:expr, $fine:ident, $cnr:ident, $alt:expr, $rate:ident) => {{
                let time = $time;
                let m = &$m;
                let rough: BTreeMap<u8, f64> = m
                    .data_segment
                    .satellite_data
                    .iter()
                    .filter_map(|s| {
                        s.gnss_satellite_rough_range_integer_ms.map(|i| {
                            (
                                s.satellite_id,
                                fx(i) + s.gnss_satellite_rough_range_mod1ms_ms,
                            )
                        })
                    })
                    .collect();
                let mut obs: Vec<(SatId, CodeObs)> = Vec::new();
                for sig in m.data_segment.signal_data.iter() {
                    let (Some(r), Some(fine)) = (rough.get(&sig.satellite_id), sig.$fine) else {
                        continue;
                    };
                    let code = format!("C{}{}", sig.signal_id.band(), sig.signal_id.attribute());
                    obs.push((
                        SatId::new($sys, sig.satellite_id),
                        CodeObs {
                            code,
                            value_m: (r + fine) * LIGHT_MS_M,
                            // DF403 (u8, 1 dB-Hz) or DF408 (2^-4 dB-Hz).
                            cn0_dbhz: sig.$cnr.map(f64::from),
                            rate: rate!($rate, m, sig),
                        },
                    ));
                }
                self.msm(time, $alt, obs, m.msm_multiple_message_flag == 1, out);
            }};
        }
        let gps = |ms: u32| Some(i64::from(ms));
        let bds = |ms: u32| Some(i64::from(ms) - (BDT_MINUS_GPST_S * 1000.0) as i64);
        let bds_as_gps = |ms: u32| i64::from(ms);
        match msg {
            Message::Msg1074(m) => msm!(
                m,
                gps(m.gps_epoch_time_ms),
                System::Gps,
                gnss_signal_fine_pseudorange_ms,
                gnss_signal_cnr_dbhz,
                norate
            ),
            Message::Msg1075(m) => msm!(
                m,
                gps(m.gps_epoch_time_ms),
                System::Gps,
                gnss_signal_fine_pseudorange_ms,
                gnss_signal_cnr_dbhz,
                rate
            ),
            Message::Msg1076(m) => msm!(
                m,
                gps(m.gps_epoch_time_ms),
                System::Gps,
                gnss_signal_fine_pseudorange_ext_ms,
                gnss_signal_cnr_ext_dbhz,
                norate
            ),
            Message::Msg1077(m) => msm!(
                m,
                gps(m.gps_epoch_time_ms),
                System::Gps,
                gnss_signal_fine_pseudorange_ext_ms,
                gnss_signal_cnr_ext_dbhz,
                rate
            ),
            Message::Msg1084(m) => {
                self.glo_msg_tod_ms = Some(i64::from(m.glo_epoch_time_ms));
                msm!(
                    m,
                    None,
                    System::Glonass,
                    gnss_signal_fine_pseudorange_ms,
                    gnss_signal_cnr_dbhz,
                    norate
                )
            }
            Message::Msg1085(m) => {
                self.glo_msg_tod_ms = Some(i64::from(m.glo_epoch_time_ms));
                for s in m.data_segment.satellite_data.iter() {
                    if let Some(k) = s.glonass_satellite_frequency_channel_number {
                        self.msm_fcn.insert(s.satellite_id, k);
                    }
                }
                msm!(
                    m,
                    None,
                    System::Glonass,
                    gnss_signal_fine_pseudorange_ms,
                    gnss_signal_cnr_dbhz,
                    rate
                )
            }
            Message::Msg1086(m) => {
                self.glo_msg_tod_ms = Some(i64::from(m.glo_epoch_time_ms));
                msm!(
                    m,
                    None,
                    System::Glonass,
                    gnss_signal_fine_pseudorange_ext_ms,
                    gnss_signal_cnr_ext_dbhz,
                    norate
                )
            }
            Message::Msg1087(m) => {
                self.glo_msg_tod_ms = Some(i64::from(m.glo_epoch_time_ms));
                for s in m.data_segment.satellite_data.iter() {
                    if let Some(k) = s.glonass_satellite_frequency_channel_number {
                        self.msm_fcn.insert(s.satellite_id, k);
                    }
                }
                msm!(
                    m,
                    None,
                    System::Glonass,
                    gnss_signal_fine_pseudorange_ext_ms,
                    gnss_signal_cnr_ext_dbhz,
                    rate
                )
            }
            Message::Msg1094(m) => msm!(
                m,
                gps(m.gal_epoch_time_ms),
                System::Galileo,
                gnss_signal_fine_pseudorange_ms,
                gnss_signal_cnr_dbhz,
                norate
            ),
            Message::Msg1095(m) => msm!(
                m,
                gps(m.gal_epoch_time_ms),
                System::Galileo,
                gnss_signal_fine_pseudorange_ms,
                gnss_signal_cnr_dbhz,
                rate
            ),
            Message::Msg1096(m) => msm!(
                m,
                gps(m.gal_epoch_time_ms),
                System::Galileo,
                gnss_signal_fine_pseudorange_ext_ms,
                gnss_signal_cnr_ext_dbhz,
                norate
            ),
            Message::Msg1097(m) => msm!(
                m,
                gps(m.gal_epoch_time_ms),
                System::Galileo,
                gnss_signal_fine_pseudorange_ext_ms,
                gnss_signal_cnr_ext_dbhz,
                rate
            ),
            Message::Msg1114(m) => msm!(
                m,
                gps(m.qzss_epoch_time_ms),
                System::Qzss,
                gnss_signal_fine_pseudorange_ms,
                gnss_signal_cnr_dbhz,
                norate
            ),
            Message::Msg1115(m) => msm!(
                m,
                gps(m.qzss_epoch_time_ms),
                System::Qzss,
                gnss_signal_fine_pseudorange_ms,
                gnss_signal_cnr_dbhz,
                rate
            ),
            Message::Msg1116(m) => msm!(
                m,
                gps(m.qzss_epoch_time_ms),
                System::Qzss,
                gnss_signal_fine_pseudorange_ext_ms,
                gnss_signal_cnr_ext_dbhz,
                norate
            ),
            Message::Msg1117(m) => msm!(
                m,
                gps(m.qzss_epoch_time_ms),
                System::Qzss,
                gnss_signal_fine_pseudorange_ext_ms,
                gnss_signal_cnr_ext_dbhz,
                rate
            ),
            Message::Msg1124(m) => msm!(
                m,
                bds(m.bds_epoch_time_ms),
                System::Beidou,
                gnss_signal_fine_pseudorange_ms,
                gnss_signal_cnr_dbhz,
                Some(bds_as_gps(m.bds_epoch_time_ms)),
                norate
            ),
            Message::Msg1125(m) => msm!(
                m,
                bds(m.bds_epoch_time_ms),
                System::Beidou,
                gnss_signal_fine_pseudorange_ms,
                gnss_signal_cnr_dbhz,
                Some(bds_as_gps(m.bds_epoch_time_ms)),
                rate
            ),
            Message::Msg1126(m) => msm!(
                m,
                bds(m.bds_epoch_time_ms),
                System::Beidou,
                gnss_signal_fine_pseudorange_ext_ms,
                gnss_signal_cnr_ext_dbhz,
                Some(bds_as_gps(m.bds_epoch_time_ms)),
                norate
            ),
            Message::Msg1127(m) => msm!(
                m,
                bds(m.bds_epoch_time_ms),
                System::Beidou,
                gnss_signal_fine_pseudorange_ext_ms,
                gnss_signal_cnr_ext_dbhz,
                Some(bds_as_gps(m.bds_epoch_time_ms)),
                rate
            ),
            Message::Msg1002(m) => {
                let mut obs = Vec::new();
                for s in m.satellites.iter() {
                    if let (Some(p), amb) = (s.l1_pseudorange_m, s.l1_pseudorange_amb_m) {
                        let code = if s.gps_l1_code_ind == 0 { "C1C" } else { "C1W" };
                        obs.push((
                            SatId::new(System::Gps, s.gps_satellite_id),
                            CodeObs {
                                code: code.into(),
                                value_m: p + amb,
                                cn0_dbhz: s.l1_cnr_dbhz.map(f64::from),
                                rate: None,
                            },
                        ));
                    }
                }
                self.msm(
                    gps(m.gps_epoch_time_ms),
                    None,
                    obs,
                    m.synchronous_gnss_msg_flag == 1,
                    out,
                );
            }
            Message::Msg1004(m) => {
                let mut obs = Vec::new();
                for s in m.satellites.iter() {
                    let (Some(p), amb) = (s.l1_pseudorange_m, s.l1_pseudorange_amb_m) else {
                        continue;
                    };
                    let id = SatId::new(System::Gps, s.gps_satellite_id);
                    let l1 = p + amb;
                    let code = if s.gps_l1_code_ind == 0 { "C1C" } else { "C1W" };
                    obs.push((
                        id,
                        CodeObs {
                            code: code.into(),
                            value_m: l1,
                            cn0_dbhz: s.l1_cnr_dbhz.map(f64::from),
                            rate: None,
                        },
                    ));
                    if let Some(d) = s.l2_l1_pseudorange_diff_m {
                        let code = ["C2X", "C2P", "C2D", "C2W"]
                            .get(usize::from(s.gps_l2_code_ind))
                            .copied()
                            .unwrap_or("C2W");
                        obs.push((
                            id,
                            CodeObs {
                                code: code.into(),
                                value_m: l1 + fx(d),
                                cn0_dbhz: s.l2_cnr_dbhz.map(f64::from),
                                rate: None,
                            },
                        ));
                    }
                }
                self.msm(
                    gps(m.gps_epoch_time_ms),
                    None,
                    obs,
                    m.synchronous_gnss_msg_flag == 1,
                    out,
                );
            }
            Message::Msg1019(m) => {
                let week = latest_week(i64::from(m.gps_week_number), 1024, self.now_week);
                let k = kepler(System::Gps, m.gps_satellite_id, &msg1019_fields(&m));
                self.ephemeris(k, week, fx(m.toc_s), out);
            }
            Message::Msg1044(m) => {
                let week = latest_week(i64::from(m.qzss_week_number), 1024, self.now_week);
                let k = kepler(System::Qzss, m.qzss_satellite_id, &msg1044_fields(&m));
                self.ephemeris(k, week, fx(m.toc_s), out);
            }
            Message::Msg1045(m) => {
                let week = latest_week(
                    i64::from(m.gal_week_number),
                    4096,
                    self.now_week - GST_WEEK0_GPS,
                ) + GST_WEEK0_GPS;
                let k = kepler(System::Galileo, m.gal_satellite_id, &msg1045_fields(&m));
                self.ephemeris(k, week, fx(m.toc_s), out);
            }
            Message::Msg1046(m) => {
                let week = latest_week(
                    i64::from(m.gal_week_number),
                    4096,
                    self.now_week - GST_WEEK0_GPS,
                ) + GST_WEEK0_GPS;
                let k = kepler(System::Galileo, m.gal_satellite_id, &msg1046_fields(&m));
                self.ephemeris(k, week, fx(m.toc_s), out);
            }
            Message::Msg1042(m) => {
                let week = latest_week(
                    i64::from(m.bds_week_number),
                    8192,
                    self.now_week - BDT_WEEK0_GPS,
                ) + BDT_WEEK0_GPS;
                let k = kepler(System::Beidou, m.bds_satellite_id, &msg1042_fields(&m));
                // BDT seconds of week to GPS: + 14 s.
                self.ephemeris(k, week, fx(m.toc_s) - BDT_MINUS_GPST_S, out);
            }
            Message::Msg1020(m) => {
                self.counts.ephemerides += 1;
                let (fields, tb_tod_s) = glonass_fields(&m);
                self.pending_glo.push(PendingGlonass {
                    fields,
                    tb_tod_s,
                    near: self.last,
                });
                self.try_anchor(out);
            }
            Message::Msg1013(m) => {
                if let Some(n) = m.leap_seconds_gps_utc_s {
                    if self
                        .glonass_placed_leap_s
                        .is_some_and(|l| l != f64::from(n))
                    {
                        out.push(Item::GlonassWithdrawn);
                        self.glonass_placed_leap_s = None;
                    }
                    self.stream_leap_s = Some(n);
                }
            }
            Message::Msg1005(m) => out.push(Item::Station([
                m.antenna_ref_point_ecef_x_m,
                m.antenna_ref_point_ecef_y_m,
                m.antenna_ref_point_ecef_z_m,
            ])),
            Message::Msg1006(m) => out.push(Item::Station([
                m.antenna_ref_point_ecef_x_m,
                m.antenna_ref_point_ecef_y_m,
                m.antenna_ref_point_ecef_z_m,
            ])),
            Message::Corrupt => self.counts.undecodable += 1,
            Message::Msg1001(_) | Message::Msg1003(_) => {
                self.ignore(format!("{n} (GPS L1/L2 without the millisecond ambiguity)"))
            }
            Message::Msg1010(m) => {
                let mut obs = Vec::new();
                for s in m.satellites.iter() {
                    if let Some(p) = s.l1_pseudorange_m {
                        let code = if s.glo_l1_code_ind == 0 { "C1C" } else { "C1P" };
                        obs.push((
                            SatId::new(System::Glonass, s.glo_satellite_id),
                            CodeObs {
                                code: code.into(),
                                value_m: p + s.l1_pseudorange_amb_m,
                                cn0_dbhz: s.l1_cnr_dbhz.map(f64::from),
                                rate: None,
                            },
                        ));
                    }
                }
                self.glo_msg_tod_ms = Some(i64::from(m.glo_epoch_time_ms));
                self.msm(None, None, obs, m.synchronous_gnss_msg_flag == 1, out);
            }
            Message::Msg1012(m) => {
                let mut obs = Vec::new();
                for s in m.satellites.iter() {
                    let Some(p) = s.l1_pseudorange_m else {
                        continue;
                    };
                    let id = SatId::new(System::Glonass, s.glo_satellite_id);
                    let l1 = p + s.l1_pseudorange_amb_m;
                    let code = if s.glo_l1_code_ind == 0 { "C1C" } else { "C1P" };
                    obs.push((
                        id,
                        CodeObs {
                            code: code.into(),
                            value_m: l1,
                            cn0_dbhz: s.l1_cnr_dbhz.map(f64::from),
                            rate: None,
                        },
                    ));
                    // DF046: 0 C/A, 1 P (2, 3 reserved: not used).
                    let l2_code = match s.glo_l2_code_ind {
                        0 => Some("C2C"),
                        1 => Some("C2P"),
                        _ => None,
                    };
                    if let (Some(d), Some(code)) = (s.l2_l1_pseudorange_diff_m, l2_code) {
                        obs.push((
                            id,
                            CodeObs {
                                code: code.into(),
                                value_m: l1 + fx(d),
                                cn0_dbhz: s.l2_cnr_dbhz.map(f64::from),
                                rate: None,
                            },
                        ));
                    }
                }
                self.glo_msg_tod_ms = Some(i64::from(m.glo_epoch_time_ms));
                self.msm(None, None, obs, m.synchronous_gnss_msg_flag == 1, out);
            }
            Message::Msg1009(_) | Message::Msg1011(_) => self.ignore(format!(
                "{n} (GLONASS L1/L2 without the millisecond ambiguity)"
            )),
            _ => self.ignore(format!("{n}")),
        }
    }

    /// Add MSM (or legacy) data of one system at GPS time of week `tow_ms`
    /// (None: GLONASS, whose time needs the leap seconds: joins the epoch
    /// open at that point); `more` is the multiple-message bit.
    fn msm(
        &mut self,
        tow_ms: Option<i64>,
        alt_tow_ms: Option<i64>,
        obs: Vec<(SatId, CodeObs)>,
        more: bool,
        out: &mut Vec<Item>,
    ) {
        let Some(tow_ms) = tow_ms else {
            let tod_ms = self.glo_msg_tod_ms.take();
            let alone = self.open.is_none();
            // A satellite already waiting, or another time of day: the
            // waiting data was an epoch of its own (GLONASS alone, its
            // multiple-message bit set).
            if alone
                && (obs.iter().any(|(id, _)| self.glonass_wait.contains_key(id))
                    || (self.glonass_wait_tod_ms.is_some() && self.glonass_wait_tod_ms != tod_ms))
            {
                self.glonass_wait.clear();
                self.glonass_wait_tod_ms = None;
                self.ignore(GLONASS_ALONE.into());
            }
            let target = match self.open.as_mut() {
                Some(o) => {
                    o.glo_tod_ms = o.glo_tod_ms.or(tod_ms);
                    &mut o.sats
                }
                None => {
                    self.glonass_wait_tod_ms = self.glonass_wait_tod_ms.or(tod_ms);
                    &mut self.glonass_wait
                }
            };
            for (id, o) in obs {
                target.entry(id).or_default().push(o);
            }
            if !more && alone {
                // The epoch's last message, and no GPS-timed message in
                // it: an epoch of GLONASS alone, which has no GPS time here.
                self.glonass_wait.clear();
                self.glonass_wait_tod_ms = None;
                self.ignore(GLONASS_ALONE.into());
            } else if !more {
                self.close(out);
            }
            return;
        };
        let mut tow_ms = tow_ms.rem_euclid(WEEK_MS);
        // BeiDou MSM written before RTCM 3.2 settled on BDT carry GPS time:
        // the same epoch as the open one under either time tag.
        if let (Some(o), Some(alt)) = (self.open.as_ref(), alt_tow_ms) {
            if o.tow_ms == alt.rem_euclid(WEEK_MS) {
                tow_ms = o.tow_ms;
            }
        }
        if self.open.as_ref().is_some_and(|o| o.tow_ms != tow_ms) {
            self.close(out);
        }
        if self.open.is_none() {
            let rel_week = match self.last {
                Some((w, t)) if tow_ms < t - WEEK_MS / 2 => w + 1,
                Some((w, _)) => w,
                None => 0,
            };
            self.last = Some((rel_week, tow_ms));
            let mut o = Open {
                rel_week,
                tow_ms,
                sats: BTreeMap::new(),
                glo_tod_ms: self.glonass_wait_tod_ms.take(),
            };
            o.sats.append(&mut self.glonass_wait);
            self.open = Some(o);
        }
        if let Some(o) = self.open.as_mut() {
            for (id, c) in obs {
                o.sats.entry(id).or_default().push(c);
            }
        }
        if !more {
            self.close(out);
        }
    }

    fn close(&mut self, out: &mut Vec<Item>) {
        if let Some(o) = self.open.take() {
            self.counts.epochs += 1;
            match self.base_week {
                Some(b) => {
                    let e = self.absolute(b, o);
                    out.push(Item::Epoch(e));
                }
                None => self.waiting.push(o),
            }
            self.try_anchor(out);
        }
    }

    fn ephemeris(&mut self, k: Kepler, week_gps: i64, toc_gps_sow_s: f64, out: &mut Vec<Item>) {
        self.counts.ephemerides += 1;
        self.pending_eph.push(PendingEph {
            k,
            week_gps,
            toc_gps_sow_s,
        });
        self.try_anchor(out);
    }

    /// Fix the stream's week from the first ephemeris and the latest epoch,
    /// then release what waited.
    fn try_anchor(&mut self, out: &mut Vec<Item>) {
        if self.base_week.is_none() {
            let (Some(first), Some((rel, tow_ms))) = (self.pending_eph.first(), self.last) else {
                return;
            };
            let toe_gps_s = first.week_gps as f64 * WEEK_S + first.k.toe_sow_s
                - if first.k.system == System::Beidou {
                    BDT_MINUS_GPST_S
                } else {
                    0.0
                };
            let tow_s = tow_ms as f64 / 1000.0;
            let w = [first.week_gps - 1, first.week_gps, first.week_gps + 1]
                .into_iter()
                .min_by(|a, b| {
                    let da = (*a as f64 * WEEK_S + tow_s - toe_gps_s).abs();
                    let db = (*b as f64 * WEEK_S + tow_s - toe_gps_s).abs();
                    da.total_cmp(&db)
                })
                .unwrap_or(first.week_gps);
            self.base_week = Some(w - rel);
        }
        let Some(base) = self.base_week else { return };
        for mut p in self.pending_eph.drain(..) {
            p.k.toc_gps_s =
                raim_nav::rtcm::fields::toc_near_toe(p.week_gps, p.k.toe_sow_s, p.toc_gps_sow_s);
            out.push(Item::Ephemeris(p.k));
        }
        let now = self.last;
        for p in std::mem::take(&mut self.pending_glo) {
            let Some((rel, tow_ms)) = p.near.or(now) else {
                self.pending_glo.push(p);
                continue;
            };
            let near_gps_s = (base + rel) as f64 * WEEK_S + tow_ms as f64 / 1000.0;
            let leap_s = self.gps_minus_utc_s(near_gps_s);
            let fields = GlonassIcdFields {
                tb_gps_s: glonass_time_of_day_to_gps_with_s(p.tb_tod_s, near_gps_s, leap_s),
                ..p.fields
            };
            match GlonassEphemeris::from_icd(&fields) {
                Ok(g) => {
                    self.glonass_placed_leap_s = Some(leap_s);
                    out.push(Item::Glonass(g))
                }
                Err(_) => self.ignore(GLONASS_BAD_1020.into()),
            }
        }
        for o in std::mem::take(&mut self.waiting) {
            let e = self.absolute(base, o);
            out.push(Item::Epoch(e));
        }
    }

    /// The epoch in absolute GPS time; its GLONASS data is kept only if
    /// the GLONASS MSM's time of day (DF034) is that of the epoch's GPS
    /// time (GPS - UTC from the stream's 1013, else the table), to the
    /// millisecond.
    fn absolute(&mut self, base_week: i64, mut o: Open) -> ObsEpoch {
        let time_gps_s = (base_week + o.rel_week) as f64 * WEEK_S + o.tow_ms as f64 / 1000.0;
        if let Some(tod_ms) = o.glo_tod_ms {
            let leap_s = self.gps_minus_utc_s(time_gps_s);
            let want_ms = (glonass_time_of_day_with_s(time_gps_s, leap_s) * 1000.0).round() as i64;
            if (tod_ms - want_ms).rem_euclid(DAY_MS) != 0 {
                o.sats.retain(|id, _| id.system != System::Glonass);
                self.ignore(GLONASS_TIME_MISMATCH.into());
            }
        }
        ObsEpoch {
            time_gps_s,
            sats: o.sats,
        }
    }

    /// The frequency channel of each GLONASS slot as the MSM5/MSM7
    /// extended satellite information (DF419) gave it last.
    pub fn msm_frequency_channels(&self) -> &BTreeMap<u8, i8> {
        &self.msm_fcn
    }
}

impl Decoder for Rtcm3 {
    fn push(&mut self, bytes: &[u8], out: &mut Vec<Item>) {
        self.counts.bytes += bytes.len() as u64;
        self.buf.extend_from_slice(bytes);
        self.frames(out, false);
    }

    fn finish(&mut self, out: &mut Vec<Item>) {
        self.frames(out, true);
        self.counts.truncated_tail_bytes += self.buf.len() as u64;
        self.buf.clear();
        self.close(out);
        if !self.glonass_wait.is_empty() {
            self.glonass_wait.clear();
            self.glonass_wait_tod_ms = None;
            self.ignore(GLONASS_ALONE.into());
        }
    }

    fn counts(&self) -> &Counts {
        &self.counts
    }

    fn waiting_epochs(&self) -> usize {
        self.waiting.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ten_bit_weeks_are_the_latest_not_after_the_clock() {
        // 2026 (week ~2400): week 685 mod 1024 is 1709 (2012), not 2733.
        assert_eq!(latest_week(685, 1024, 2400), 1709);
        assert_eq!(latest_week(352, 1024, 2400), 2400);
        assert_eq!(latest_week(353, 1024, 2400), 1377);
    }

    /// A phase-range rate as the unit keeps it: whole mm/s, rounded half
    /// away from zero (raim-nav's `pack_rate_mm_s`), none at or beyond
    /// 2^23 mm/s or not finite.
    #[test]
    fn rates_are_kept_to_the_millimetre_per_second() {
        assert_eq!(unit_rate_m_s(1.23456), Some(1.235));
        assert_eq!(unit_rate_m_s(-712.3454), Some(-712.345));
        assert_eq!(unit_rate_m_s(-0.0005), Some(-0.001));
        assert_eq!(unit_rate_m_s(0.0005), Some(0.001));
        assert_eq!(unit_rate_m_s(8388.6074), Some(8388.607));
        assert_eq!(unit_rate_m_s(8388.608), None);
        assert_eq!(unit_rate_m_s(-8388.608), None);
        assert_eq!(unit_rate_m_s(f64::NAN), None);
        assert_eq!(unit_rate_m_s(f64::INFINITY), None);
    }
}
