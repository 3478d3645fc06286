//! The host's causal replay of an RTCM 3 stream, as `raim replay --rtcm3`
//! runs a live source: frame by frame through the host's reader
//! (`raim_recv::rtcm`), each epoch prepared (`raim_gnss::ranging`) with the
//! ephemerides received before it, and given the stream sigmas.

#![allow(dead_code)]

pub mod esbc;

use raim_core::sigma::SigmaModel;
use raim_core::{Config, RangeObservation, System};
use raim_gnss::ranging::{prepare_epoch, PreparedEpoch, RangingOptions};
use raim_gnss::{NavData, ObsData};
use raim_nav::ranging::StreamSigmas;
use raim_recv::{Decoder, Item};

pub const GMSD7: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../shared/data/GMSD7_20121014.rtcm3"
);
/// GMSD7's GPS week (2012-10-14 to 2012-10-20).
pub const GMSD7_WEEK: i64 = 1709;
/// The week-rollover pivot of a unit built when GMSD7 was recorded: the
/// device receiver run on the original 2012 stream.
pub const GMSD7_PIVOT_WEEK: i64 = GMSD7_WEEK - 52;
/// The host reader's clock week for the original stream (its weeks are
/// the latest not after it).
pub const GMSD7_NOW_WEEK: i64 = 2400;
/// The firmware's stream elevation mask, rad.
pub const MASK_RAD: f64 = 10.0 * core::f64::consts::PI / 180.0;

/// The whole RTCM frames of a byte stream, in order (rtcm-rs checks each).
pub fn frames(bytes: &[u8]) -> Vec<&[u8]> {
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(rest) = bytes.get(i..).filter(|r| !r.is_empty()) {
        match (rest.first(), rtcm_rs::MessageFrame::new(rest)) {
            (Some(0xD3), Ok(f)) => {
                out.push(&rest[..f.frame_len()]);
                i += f.frame_len();
            }
            _ => i += 1,
        }
    }
    out
}

/// The GLONASS sigma model of `model` (its own URA).
pub fn glonass_model(model: &SigmaModel) -> SigmaModel {
    SigmaModel {
        ura_m: raim_gnss::glonass::glonass_ura_m(model.ura_m),
        ..*model
    }
}

/// The ranging options of a stream replay at the firmware's mask: every
/// system the device's receiver forms.
pub fn options(model: &SigmaModel) -> RangingOptions {
    RangingOptions {
        systems: vec![
            System::Gps,
            System::Glonass,
            System::Galileo,
            System::Beidou,
            System::Qzss,
        ],
        codes: raim_nav::ranging::STREAM_CODES
            .iter()
            .map(|(s, c)| (*s, c.iter().map(|c| c.to_string()).collect()))
            .collect(),
        elevation_mask_rad: MASK_RAD,
        iono: true,
        tropo: true,
        group_delay: true,
        glonass_sigma: Some(glonass_model(model)),
    }
}

/// The stream sigma of one prepared satellite: raim-nav's rule
/// (`stream_sigma_for_m`, the one the device's receiver calls), with the
/// stream's doubled residual ionosphere for a single-frequency range.
pub fn sigma_m(sigmas: &StreamSigmas, system: System, code: &str, el_rad: f64) -> f64 {
    raim_nav::ranging::stream_sigma_for_m(sigmas, system, code, el_rad, 2.0)
}

/// One epoch as the host forms it: its prepared form and the observations
/// with their stream sigmas.
pub struct HostEpoch {
    /// Index of the frame that closed it.
    pub frame: usize,
    pub prepared: PreparedEpoch,
    pub obs: Vec<RangeObservation>,
}

/// A week inside this build's firmware's dating window (raim-server's
/// `stream::PIVOT_WEEK` plus half a year): the host test binary and the
/// firmware compute their pivot from their own build dates, which this
/// margin lets differ by up to 26 weeks.
pub fn in_window_week() -> i64 {
    raim_server::stream::PIVOT_WEEK + 26
}

/// The bit `bit` of a frame (MSB first).
fn get_bits(f: &[u8], at: usize, width: usize) -> u64 {
    (0..width).fold(0u64, |v, k| {
        let bit = at + k;
        (v << 1) | u64::from((f[bit / 8] >> (7 - bit % 8)) & 1)
    })
}

/// Write `width` bits of `value` at bit `at` of a frame (MSB first).
fn set_bits(f: &mut [u8], at: usize, width: usize, value: u64) {
    for k in 0..width {
        let bit = at + k;
        let v = ((value >> (width - 1 - k)) & 1) as u8;
        f[bit / 8] = (f[bit / 8] & !(1 << (7 - bit % 8))) | (v << (7 - bit % 8));
    }
}

/// A sign-magnitude field (RTCM 10403.3 GLONASS fields) of `width` bits
/// with resolution `res`.
fn get_sm(f: &[u8], at: usize, width: usize, res: f64) -> f64 {
    let v = get_bits(f, at, width);
    let mag = (v & ((1 << (width - 1)) - 1)) as f64 * res;
    if v >> (width - 1) == 1 {
        -mag
    } else {
        mag
    }
}

fn set_sm(f: &mut [u8], at: usize, width: usize, res: f64, value: f64) {
    let mag = (value.abs() / res).round() as u64;
    assert!(mag < 1 << (width - 1), "{value} does not fit {width} bits");
    let sign = u64::from(value < 0.0 && mag != 0);
    set_bits(f, at, width, (sign << (width - 1)) | mag);
}

/// `bytes` as a receiver would have sent them `delta_weeks` later: the
/// same orbits, observables and times of week, with every frame's CRC-24Q
/// recomputed.
/// - 1019: the 10-bit week (DF076) moved on.
/// - GLONASS time is UTC-based: at the moved dates GPS - UTC is
///   `leap_new` against the recording's `leap_old`, so each GLONASS time
///   moves by `leap_old - leap_new` s against the GPS scale. The GLONASS
///   MSM epoch time (DF416 day, DF034 ms) is moved by that, and each 1020's
///   state vector is propagated by `leap_new - leap_old` s (raim-nav's RK4)
///   so that its unchanged t_b refers to the same instant of the orbit; it
///   is re-encoded at the field's resolution (2^-11 km, 2^-20 km/s).
///
/// Other frames are kept as they are.
pub fn move_stream_weeks(
    bytes: &[u8],
    delta_weeks: i64,
    leap_old_s: i64,
    leap_new_s: i64,
) -> Vec<u8> {
    const CRC24Q: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_24_LTE_A);
    const HDR: usize = 24;
    let shift_ms = (leap_old_s - leap_new_s) * 1000;
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    for f in frames(bytes) {
        let start = f.as_ptr() as usize - bytes.as_ptr() as usize;
        out.extend_from_slice(&bytes[i..start]);
        i = start + f.len();
        let mut f = f.to_vec();
        let number = get_bits(&f, HDR, 12);
        match number {
            1019 => {
                // DF002 12, DF009 6, DF076 10.
                let at = HDR + 18;
                let week = get_bits(&f, at, 10) as i64;
                set_bits(&mut f, at, 10, (week + delta_weeks).rem_euclid(1024) as u64);
            }
            1081..=1087 if shift_ms != 0 => {
                // DF002 12, DF003 12, DF416 3, DF034 27.
                let at = HDR + 24;
                let day = get_bits(&f, at, 3) as i64;
                let tod = get_bits(&f, at + 3, 27) as i64;
                let t = tod + shift_ms;
                let (day, tod) = match day {
                    7 => (7, t.rem_euclid(86_400_000)),
                    d => (
                        (d + t.div_euclid(86_400_000)).rem_euclid(7),
                        t.rem_euclid(86_400_000),
                    ),
                };
                set_bits(&mut f, at, 3, day as u64);
                set_bits(&mut f, at + 3, 27, tod as u64);
            }
            1020 if shift_ms != 0 => {
                // Velocity 24 (2^-20 km/s), position 27 (2^-11 km),
                // acceleration 5 (2^-30 km/s^2) per axis, from payload bit 48.
                const V: f64 = 1.0 / (1024.0 * 1024.0);
                const X: f64 = 1.0 / 2048.0;
                const A: f64 = 1.0 / (1024.0 * 1024.0 * 1024.0);
                let axis = |k: usize| HDR + 48 + 56 * k;
                let mut fields = raim_nav::glonass::GlonassIcdFields {
                    slot: get_bits(&f, HDR + 12, 6) as u8,
                    frequency_channel: get_bits(&f, HDR + 18, 5) as i8 - 7,
                    tb_gps_s: 0.0,
                    vx_km_s: get_sm(&f, axis(0), 24, V),
                    x_km: get_sm(&f, axis(0) + 24, 27, X),
                    ax_km_s2: get_sm(&f, axis(0) + 51, 5, A),
                    vy_km_s: get_sm(&f, axis(1), 24, V),
                    y_km: get_sm(&f, axis(1) + 24, 27, X),
                    ay_km_s2: get_sm(&f, axis(1) + 51, 5, A),
                    vz_km_s: get_sm(&f, axis(2), 24, V),
                    z_km: get_sm(&f, axis(2) + 24, 27, X),
                    az_km_s2: get_sm(&f, axis(2) + 51, 5, A),
                    tau_n_s: 0.0,
                    gamma_n: 0.0,
                    unhealthy: false,
                };
                // A spare slot's frequency channel may be out of the
                // ICD's range: such a set is left as it was.
                fields.frequency_channel = fields.frequency_channel.clamp(-7, 6);
                if let Ok(g) = raim_nav::glonass::GlonassEphemeris::from_icd(&fields) {
                    let (p, v) = g.propagate_pz90(-shift_ms as f64 / 1000.0);
                    for k in 0..3 {
                        set_sm(&mut f, axis(k), 24, V, v[k] / 1000.0);
                        set_sm(&mut f, axis(k) + 24, 27, X, p[k] / 1000.0);
                    }
                }
            }
            _ => {}
        }
        let n = f.len() - 3;
        let crc = CRC24Q.checksum(&f[..n]);
        f[n..].copy_from_slice(&crc.to_be_bytes()[1..]);
        out.extend_from_slice(&f);
    }
    out.extend_from_slice(&bytes[i..]);
    out
}

/// GMSD7 as sent in GPS week `week`: [`gmsd7_moved_bare`], led by an
/// RTCM 1013 with GPS - UTC when the moved dates reach the leap-second
/// table's expiry (`raim_nav::time::LEAP_TABLE_EXPIRES_GPS_S`), as a
/// receiver that sends its system parameters would: past it the unit
/// takes the count from the stream or refuses GLONASS epochs.
pub fn gmsd7_moved_to(bytes: &[u8], week: i64) -> Vec<u8> {
    let week_s = raim_nav::ephemeris::WEEK_S;
    let moved = gmsd7_moved_bare(bytes, week);
    // The stream runs from 16 s before the week to 4 min 16 s into it.
    if week as f64 * week_s + 300.0 >= raim_nav::time::LEAP_TABLE_EXPIRES_GPS_S {
        let leap = raim_nav::time::gps_minus_utc_s(week as f64 * week_s) as u8;
        [msg1013(leap), moved].concat()
    } else {
        moved
    }
}

/// GMSD7 as sent in GPS week `week`: [`move_stream_weeks`] with the
/// leap seconds of the recording and of the moved dates (raim-nav's
/// table), and no 1013.
pub fn gmsd7_moved_bare(bytes: &[u8], week: i64) -> Vec<u8> {
    let week_s = raim_nav::ephemeris::WEEK_S;
    let leap = |w: i64| raim_nav::time::gps_minus_utc_s(w as f64 * week_s) as i64;
    move_stream_weeks(bytes, week - GMSD7_WEEK, leap(GMSD7_WEEK), leap(week))
}

/// An RTCM 1013 (system parameters, RTCM 10403.3 Table 3.5-14) with GPS -
/// UTC = `leap_s` and no message announcements: DF002 12, DF003 12, DF051
/// 16, DF052 17, DF053 5, DF054 8.
pub fn msg1013(leap_s: u8) -> Vec<u8> {
    let fields: [(u64, usize); 6] = [
        (1013, 12),
        (0, 12),
        (56_214, 16),
        (3_600, 17),
        (0, 5),
        (u64::from(leap_s), 8),
    ];
    let mut payload = vec![0u8; 9];
    let mut at = 0;
    for (v, w) in fields {
        for k in 0..w {
            if (v >> (w - 1 - k)) & 1 == 1 {
                payload[(at + k) / 8] |= 1 << (7 - (at + k) % 8);
            }
        }
        at += w;
    }
    let crc = crc::Crc::<u32>::new(&crc::CRC_24_LTE_A);
    let mut f = vec![0xD3, 0, payload.len() as u8];
    f.extend_from_slice(&payload);
    let c = crc.checksum(&f);
    f.extend_from_slice(&[(c >> 16) as u8, (c >> 8) as u8, c as u8]);
    f
}

/// The host's causal replay of `bytes`, and its reader's counts, with the
/// host's clock at `now_week` (10-bit weeks read as the latest not after
/// it, as `raim replay --rtcm3` reads them against the computer's clock).
pub fn host_epochs(bytes: &[u8], now_week: i64) -> (Vec<HostEpoch>, raim_recv::Counts) {
    host_epochs_with(
        bytes,
        now_week,
        &StreamSigmas::Snapshot(Config::default().sigma_model),
    )
}

/// [`host_epochs`] with the stream sigmas `sigmas` (an ARAIM stream
/// epoch's: `StreamSigmas::Araim`, the pair curves of `raim replay
/// --araim`).
pub fn host_epochs_with(
    bytes: &[u8],
    now_week: i64,
    sigmas: &StreamSigmas,
) -> (Vec<HostEpoch>, raim_recv::Counts) {
    let opts = options(&Config::default().sigma_model);
    let mut host = raim_recv::rtcm::Rtcm3::new(now_week);
    let mut obs = ObsData {
        path: GMSD7.into(),
        approx_position_m: None,
        epochs: Vec::new(),
    };
    let mut nav = NavData::default();
    let mut out = Vec::new();
    let mut items = Vec::new();
    for (n, f) in frames(bytes).into_iter().enumerate() {
        host.push(f, &mut items);
        let mut epochs = Vec::new();
        for it in items.drain(..) {
            match it {
                Item::Epoch(e) => epochs.push(e),
                other => raim_recv::apply(other, &mut obs, &mut nav),
            }
        }
        for e in epochs {
            let prepared = prepare_epoch(&nav, &e, &opts, obs.approx_position_m);
            let sats = prepared
                .sats
                .iter()
                .map(|s| RangeObservation {
                    sigma_m: Some(sigma_m(sigmas, s.obs.id.system, &s.code, s.elevation_rad)),
                    ..s.obs
                })
                .collect();
            out.push(HostEpoch {
                frame: n,
                prepared,
                obs: sats,
            });
        }
    }
    (out, host.counts().clone())
}
