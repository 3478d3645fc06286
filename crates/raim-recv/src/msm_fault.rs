//! Seeded faults written into an RTCM 3 stream: each MSM4-MSM7 pseudorange
//! of a faulted satellite is moved by the fault's bias at the MSM's epoch,
//! every signal of the satellite alike (so an iono-free combination carries
//! the bias unchanged), and the frame's CRC-24Q is recomputed. Every other
//! bit of the stream is kept: frames without a faulted satellite are copied
//! as they are, and in a faulted MSM only the faulted satellite's fine
//! pseudoranges (DF400/DF405) change, with its rough range (DF397/DF398)
//! and fine phase ranges (DF401/DF406) when the bias does not fit the fine
//! field (below).
//!
//! The faults are `raim_gnss::faults` ones (`FaultPlan`, the vocabulary of
//! `raim replay --fault`: steps, ramps, clock jumps, seeded noise), applied
//! by `FaultPlan::apply` to each MSM's satellites at the MSM's GPS time: a
//! satellite's bias is what `apply` adds to its range. Times are counted
//! from the stream's own MSM epochs: GPS, Galileo and QZSS time of week,
//! BeiDou BDT + 14 s (RTCM 3.2 and later), one week more at each wrap of
//! the time of week, and the week of the first MSM taken as GPS week 0, so
//! that `+S` is S seconds after the first MSM and `HH:MM:SS` a GPS time of
//! day of its day, as in `raim replay` (the stream carries no full week in
//! its MSM). A GLONASS MSM carries a UTC(SU)-based time of day (DF034,
//! Moscow time): it is timed by the MSM of another system of its epoch, as
//! a receiver's reader joins them (the one before it in the stream, else
//! the one after), whose GPS time of day it must equal to the millisecond
//! plus 3 h less a whole number of leap seconds (0 to 60 s): the stream
//! itself gives the leap seconds. A GLONASS MSM with no such neighbour
//! cannot be timed, and a fault that could touch its satellites is refused
//! ([`MsmFaultError::GlonassUntimed`]).
//!
//! Resolution: the bias is written at the MSM's fine-pseudorange
//! resolution (MSM4/5 DF400 2^-24 ms, 1.8 cm; MSM6/7 DF405 2^-29 ms,
//! 0.56 mm), so each faulted pseudorange reads back within half of it of
//! the original plus the bias. A bias that would take a fine pseudorange
//! out of its field (about +-292 m about the rough range) moves the
//! satellite's rough range by a whole number of 2^-10 ms units instead, the
//! remainder going to the fine fields, and moves the fine phase ranges back
//! by the same units (the carrier phase is left as received); a phase range
//! that no longer fits its field is marked invalid (counted).

use raim_core::{RangeObservation, SatId, System};

/// CRC-24Q (RTCM 10403.3 §4.2): the catalogue's CRC-24/LTE-A.
const CRC24Q: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_24_LTE_A);
/// Bits before the payload (preamble, 6 reserved bits, 10-bit length).
const HDR_BITS: usize = 24;
/// MSM header bits before the satellite mask (DF002 to DF418).
const MSM_FIXED_BITS: usize = 73;
/// BDT = GPS - 14 s.
const BDT_MINUS_GPST_S: f64 = -14.0;
const WEEK_S: f64 = 604_800.0;
/// One light-millisecond, m (RTCM 10403.3: 299,792.458 m).
pub const LIGHT_MS_M: f64 = 299_792.458;

/// Why a stream could not be faulted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MsmFaultError {
    #[error("the stream has no MSM4-MSM7 of GPS, Galileo, QZSS or BeiDou to time the faults by")]
    NoMsm,
    #[error("a fault may touch GLONASS satellites (frame {frame}, {sat:?}) whose MSM has no MSM of another system in its epoch (the one before or after it, at its time of day plus 3 h less 0-60 leap seconds) to take the GPS time from")]
    GlonassUntimed { frame: usize, sat: SatId },
    #[error("frame {frame}: {sat:?} with a bias of {bias_m} m: its rough range would be {rough_ms} ms, outside DF397's 0-254 ms")]
    RoughRange {
        frame: usize,
        sat: SatId,
        bias_m: f64,
        rough_ms: f64,
    },
    #[error("frame {frame}: {sat:?} with a bias of {bias_m} m: a fine pseudorange does not fit its field even with the rough range moved")]
    FineRange {
        frame: usize,
        sat: SatId,
        bias_m: f64,
    },
    #[error("frame {frame}: {sat:?} has a bias that is not a finite number ({bias_m})")]
    NonFinite {
        frame: usize,
        sat: SatId,
        bias_m: f64,
    },
}

/// What [`fault_stream`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FaultedStream {
    pub bytes: Vec<u8>,
    /// Frames with a valid CRC-24Q (all copied or rewritten).
    pub frames: usize,
    /// MSM frames rewritten.
    pub msm_faulted: usize,
    /// Pseudoranges (cells) moved.
    pub cells_faulted: usize,
    /// Satellites whose rough range was moved.
    pub rough_moved: usize,
    /// Fine phase ranges marked invalid (out of their field).
    pub phase_dropped: usize,
    /// MSM4-7 frames whose layout could not be read (more than 64 cells,
    /// or shorter than their masks say): copied as they are, unfaulted.
    pub msm_unread: usize,
    /// The GPS time of the first MSM (seconds from the GPS week 0 of the
    /// first MSM's week): what `+S` and `HH:MM:SS` are counted from.
    pub first_gps_s: f64,
}

/// The bits `at..at + width` of `f`, MSB first.
fn get_bits(f: &[u8], at: usize, width: usize) -> u64 {
    (0..width).fold(0u64, |v, k| {
        let bit = at + k;
        let byte = f.get(bit / 8).copied().unwrap_or(0);
        (v << 1) | u64::from((byte >> (7 - bit % 8)) & 1)
    })
}

fn set_bits(f: &mut [u8], at: usize, width: usize, value: u64) {
    for k in 0..width {
        let bit = at + k;
        let v = ((value >> (width - 1 - k)) & 1) as u8;
        if let Some(b) = f.get_mut(bit / 8) {
            *b = (*b & !(1 << (7 - bit % 8))) | (v << (7 - bit % 8));
        }
    }
}

/// A two's-complement field.
fn get_signed(f: &[u8], at: usize, width: usize) -> i64 {
    let v = get_bits(f, at, width) as i64;
    if v >> (width - 1) == 1 {
        v - (1 << width)
    } else {
        v
    }
}

fn set_signed(f: &mut [u8], at: usize, width: usize, value: i64) {
    set_bits(f, at, width, (value & ((1 << width) - 1)) as u64);
}

/// The RTCM frames of `bytes` with a valid CRC-24Q: (start, length).
fn frame_spans(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 6 <= bytes.len() {
        if bytes[i] != 0xD3 || bytes[i + 1] & 0xFC != 0 {
            i += 1;
            continue;
        }
        let len = (usize::from(bytes[i + 1] & 0x03) << 8) | usize::from(bytes[i + 2]);
        let n = 3 + len + 3;
        if i + n > bytes.len() {
            i += 1;
            continue;
        }
        let f = &bytes[i..i + n];
        let crc = CRC24Q.checksum(&f[..3 + len]);
        if crc.to_be_bytes()[1..] == f[3 + len..] {
            out.push((i, n));
            i += n;
        } else {
            i += 1;
        }
    }
    out
}

/// The MSM layout of a message number: system and MSM type 4-7.
fn msm_of(number: u64) -> Option<(System, u8)> {
    let system = match number / 10 {
        107 => System::Gps,
        108 => System::Glonass,
        109 => System::Galileo,
        111 => System::Qzss,
        112 => System::Beidou,
        _ => return None,
    };
    let kind = (number % 10) as u8;
    (4..=7).contains(&kind).then_some((system, kind))
}

/// An MSM's layout in its frame.
struct Layout {
    system: System,
    kind: u8,
    /// Satellite IDs (1-based mask positions), in order.
    sats: Vec<u8>,
    /// Per cell, in order: the satellite index.
    cells: Vec<usize>,
    /// Bit offset of the satellite data.
    sat_at: usize,
    /// Bit offset of the signal data.
    sig_at: usize,
}

impl Layout {
    fn parse(f: &[u8], system: System, kind: u8) -> Option<Layout> {
        // DF002 12 + DF003 12 + time 30 + DF393 1 + DF409 3 + DF001 7 +
        // DF411 2 + DF412 2 + DF417 1 + DF418 3 = 73 bits before DF394.
        let mask_at = HDR_BITS + MSM_FIXED_BITS;
        let sat_mask = get_bits(f, mask_at, 64);
        let sig_mask = get_bits(f, mask_at + 64, 32);
        let sats: Vec<u8> = (0..64u8)
            .filter(|k| sat_mask >> (63 - k) & 1 == 1)
            .map(|k| k + 1)
            .collect();
        let nsig = sig_mask.count_ones() as usize;
        let cell_at = mask_at + 96;
        let x = sats.len() * nsig;
        if x > 64 {
            return None;
        }
        let mut cells = Vec::new();
        for (i, _) in sats.iter().enumerate() {
            for j in 0..nsig {
                if get_bits(f, cell_at + i * nsig + j, 1) == 1 {
                    cells.push(i);
                }
            }
        }
        let sat_at = cell_at + x;
        let per_sat = if kind % 2 == 1 {
            8 + 4 + 10 + 14
        } else {
            8 + 10
        };
        let sig_at = sat_at + per_sat * sats.len();
        let per_cell: usize = match kind {
            4 => 15 + 22 + 4 + 1 + 6,
            5 => 15 + 22 + 4 + 1 + 6 + 15,
            6 => 20 + 24 + 10 + 1 + 10,
            _ => 20 + 24 + 10 + 1 + 10 + 15,
        };
        let end = sig_at + per_cell * cells.len();
        (end <= f.len().saturating_sub(3) * 8).then_some(Layout {
            system,
            kind,
            sats,
            cells,
            sat_at,
            sig_at,
        })
    }

    /// (DF397 offset, DF398 offset) of satellite `i`.
    fn rough_at(&self, i: usize) -> (usize, usize) {
        let n = self.sats.len();
        let int_at = self.sat_at + 8 * i;
        let mod_at = if self.kind % 2 == 1 {
            self.sat_at + 12 * n + 10 * i
        } else {
            self.sat_at + 8 * n + 10 * i
        };
        (int_at, mod_at)
    }

    /// Fine pseudorange: (offset of cell `c`, width, resolution ms).
    fn fine_pr(&self, c: usize) -> (usize, usize, f64) {
        if self.kind <= 5 {
            (self.sig_at + 15 * c, 15, 2f64.powi(-24))
        } else {
            (self.sig_at + 20 * c, 20, 2f64.powi(-29))
        }
    }

    /// Fine phase range: (offset of cell `c`, width, resolution ms).
    fn fine_phase(&self, c: usize) -> (usize, usize, f64) {
        let n = self.cells.len();
        if self.kind <= 5 {
            (self.sig_at + 15 * n + 22 * c, 22, 2f64.powi(-29))
        } else {
            (self.sig_at + 20 * n + 24 * c, 24, 2f64.powi(-31))
        }
    }
}

/// A GLONASS MSM's time of day (DF034, ms of the Moscow day; the 3-bit
/// day of week DF416 before it is not used).
fn glonass_tod_ms(f: &[u8]) -> i64 {
    get_bits(f, HDR_BITS + 24 + 3, 27) as i64
}

/// GLONASS time is UTC(SU) + 3 h: ms.
const MOSCOW_MS: i64 = 10_800_000;
const DAY_MS: i64 = 86_400_000;
/// The leap seconds a GLONASS MSM may differ from GPS time by, ms.
const MAX_LEAP_MS: i64 = 60_000;

/// Whether a GLONASS time of day `tod_ms` is the epoch of GPS time
/// `t_gps_s` (GPS time of day + 3 h - whole leap seconds within 0-60 s).
fn same_epoch(t_gps_s: f64, tod_ms: i64) -> bool {
    let gps_tod_ms = (t_gps_s * 1000.0).round() as i64;
    let leap_ms = (gps_tod_ms + MOSCOW_MS - tod_ms).rem_euclid(DAY_MS);
    leap_ms % 1000 == 0 && leap_ms <= MAX_LEAP_MS
}

/// The stream time of every MSM frame of `bytes` (`spans`): GPS, Galileo,
/// QZSS and BeiDou by their time of week ([`Clock`]), a GLONASS MSM by
/// the MSM of another system next to it in its epoch ([`same_epoch`]: the
/// one before it, else the one after); None for other frames and an
/// untimed GLONASS MSM.
fn msm_times(bytes: &[u8], spans: &[(usize, usize)]) -> Vec<Option<f64>> {
    let mut clock = Clock::default();
    let mut times = vec![None; spans.len()];
    let mut glonass = Vec::new();
    for (k, &(start, n)) in spans.iter().enumerate() {
        let f = &bytes[start..start + n];
        let Some((system, _)) = msm_of(get_bits(f, HDR_BITS, 12)) else {
            continue;
        };
        match msm_tow_s(f, system) {
            Some(tow) => times[k] = Some(clock.at(tow)),
            None => glonass.push((k, glonass_tod_ms(f))),
        }
    }
    for (k, tod_ms) in glonass {
        let before = times[..k].iter().rev().flatten().next().copied();
        let after = times[k + 1..].iter().flatten().next().copied();
        times[k] = [before, after]
            .into_iter()
            .flatten()
            .find(|&t| same_epoch(t, tod_ms));
    }
    times
}

/// The MSM's epoch time, GPS seconds of the week (GLONASS: None).
fn msm_tow_s(f: &[u8], system: System) -> Option<f64> {
    let ms = get_bits(f, HDR_BITS + 24, 30) as f64;
    match system {
        System::Glonass => None,
        System::Beidou => Some((ms / 1000.0 - BDT_MINUS_GPST_S).rem_euclid(WEEK_S)),
        _ => Some(ms / 1000.0),
    }
}

/// Continuous GPS time from times of week: one week more at each wrap.
#[derive(Default)]
struct Clock {
    last_tow_s: Option<f64>,
    weeks: f64,
}

impl Clock {
    fn at(&mut self, tow_s: f64) -> f64 {
        if let Some(last) = self.last_tow_s {
            if tow_s < last - WEEK_S / 2.0 {
                self.weeks += 1.0;
            } else if tow_s > last + WEEK_S / 2.0 {
                // A late MSM of the previous week.
                return (self.weeks - 1.0) * WEEK_S + tow_s;
            }
        }
        self.last_tow_s = Some(tow_s);
        self.weeks * WEEK_S + tow_s
    }
}

/// The GPS time (from the first MSM's week) of the stream's first MSM of
/// GPS, Galileo, QZSS or BeiDou: the time `+S` and `HH:MM:SS` of a fault
/// spec are counted from (`FaultPlan::parse_cli`).
pub fn first_msm_gps_s(bytes: &[u8]) -> Option<f64> {
    frame_spans(bytes).into_iter().find_map(|(s, n)| {
        let f = &bytes[s..s + n];
        let (system, _) = msm_of(get_bits(f, HDR_BITS, 12))?;
        msm_tow_s(f, system)
    })
}

/// `bytes` with the biases `bias` gives written into its MSM
/// pseudoranges: `bias(t_gps_s, sats)` adds each satellite's bias at GPS
/// time `t_gps_s` to its `pseudorange_m` (given as 0; `position_m` is
/// zero and unused). `FaultPlan::apply` is such a function
/// ([`fault_stream`]).
pub fn bias_stream(
    bytes: &[u8],
    mut bias: impl FnMut(f64, &mut [RangeObservation]),
) -> Result<FaultedStream, MsmFaultError> {
    let first = first_msm_gps_s(bytes).ok_or(MsmFaultError::NoMsm)?;
    let mut out = FaultedStream {
        first_gps_s: first,
        ..FaultedStream::default()
    };
    let mut copied = 0;
    let spans = frame_spans(bytes);
    let times = msm_times(bytes, &spans);
    out.frames = spans.len();
    for (k, (start, n)) in spans.into_iter().enumerate() {
        out.bytes.extend_from_slice(&bytes[copied..start]);
        copied = start + n;
        let frame = &bytes[start..start + n];
        let mut f = frame.to_vec();
        let number = get_bits(&f, HDR_BITS, 12);
        let Some((system, kind)) = msm_of(number) else {
            out.bytes.extend_from_slice(frame);
            continue;
        };
        let Some(layout) = Layout::parse(&f, system, kind) else {
            out.msm_unread += 1;
            out.bytes.extend_from_slice(frame);
            continue;
        };
        let t = times[k];
        let mut sats: Vec<RangeObservation> = layout
            .sats
            .iter()
            .map(|&id| RangeObservation {
                id: SatId::new(layout.system, id),
                pseudorange_m: 0.0,
                position_m: [0.0; 3],
                sigma_m: None,
            })
            .collect();
        let Some(t) = t else {
            // An untimed GLONASS MSM: refuse a fault that touches its
            // satellites at any time of the stream (probed at the first
            // MSM's time and ten years on).
            for probe in [first, first + 520.0 * WEEK_S] {
                let mut s = sats.clone();
                bias(probe, &mut s);
                if let Some(x) = s.iter().find(|x| x.pseudorange_m != 0.0) {
                    return Err(MsmFaultError::GlonassUntimed {
                        frame: k,
                        sat: x.id,
                    });
                }
            }
            out.bytes.extend_from_slice(frame);
            continue;
        };
        bias(t, &mut sats);
        if sats.iter().all(|s| s.pseudorange_m == 0.0) {
            out.bytes.extend_from_slice(frame);
            continue;
        }
        for (i, s) in sats.iter().enumerate() {
            let bias_m = s.pseudorange_m;
            if bias_m == 0.0 {
                continue;
            }
            if !bias_m.is_finite() {
                return Err(MsmFaultError::NonFinite {
                    frame: k,
                    sat: s.id,
                    bias_m,
                });
            }
            let moved = move_satellite(&mut f, &layout, i, bias_m / LIGHT_MS_M);
            match moved {
                Ok(m) => {
                    out.cells_faulted += m.cells;
                    out.rough_moved += usize::from(m.rough);
                    out.phase_dropped += m.phase_dropped;
                }
                Err(Move::Rough(rough_ms)) => {
                    return Err(MsmFaultError::RoughRange {
                        frame: k,
                        sat: s.id,
                        bias_m,
                        rough_ms,
                    })
                }
                Err(Move::Fine) => {
                    return Err(MsmFaultError::FineRange {
                        frame: k,
                        sat: s.id,
                        bias_m,
                    })
                }
            }
        }
        let len = f.len() - 3;
        let crc = CRC24Q.checksum(&f[..len]);
        f[len..].copy_from_slice(&crc.to_be_bytes()[1..]);
        out.msm_faulted += 1;
        out.bytes.extend_from_slice(&f);
    }
    out.bytes.extend_from_slice(&bytes[copied..]);
    Ok(out)
}

/// [`bias_stream`] with the faults of `plan` (`FaultPlan::apply`).
pub fn fault_stream(
    bytes: &[u8],
    plan: &raim_gnss::faults::FaultPlan,
) -> Result<FaultedStream, MsmFaultError> {
    bias_stream(bytes, |t, sats| {
        plan.apply(t, sats);
    })
}

struct Moved {
    cells: usize,
    rough: bool,
    phase_dropped: usize,
}

enum Move {
    Rough(f64),
    Fine,
}

/// Moves satellite `i`'s pseudoranges by `delta_ms`.
fn move_satellite(f: &mut [u8], l: &Layout, i: usize, delta_ms: f64) -> Result<Moved, Move> {
    let cells: Vec<usize> = (0..l.cells.len()).filter(|&c| l.cells[c] == i).collect();
    let (int_at, mod_at) = l.rough_at(i);
    let int_ms = get_bits(f, int_at, 8);
    let mut moved = Moved {
        cells: 0,
        rough: false,
        phase_dropped: 0,
    };
    if int_ms == 255 {
        // No rough range: the satellite has no pseudorange.
        return Ok(moved);
    }
    let fits = |v: i64, width: usize| v.abs() < (1 << (width - 1));
    let valid_pr = |f: &[u8], c: usize| {
        let (at, w, _) = l.fine_pr(c);
        let v = get_signed(f, at, w);
        (v != -(1 << (w - 1))).then_some(v)
    };
    // First try the fine fields alone.
    let direct: Option<Vec<(usize, i64)>> = cells
        .iter()
        .filter_map(|&c| valid_pr(f, c).map(|v| (c, v)))
        .map(|(c, v)| {
            let (_, w, res) = l.fine_pr(c);
            let nv = v + (delta_ms / res).round() as i64;
            fits(nv, w).then_some((c, nv))
        })
        .collect();
    let (writes, shift_units) = match direct {
        Some(w) => (w, 0i64),
        None => {
            let k = (delta_ms * 1024.0).round() as i64;
            let rest_ms = delta_ms - k as f64 / 1024.0;
            let rough = int_ms as i64 * 1024 + get_bits(f, mod_at, 10) as i64 + k;
            if !(0..255 * 1024).contains(&rough) {
                return Err(Move::Rough(rough as f64 / 1024.0));
            }
            set_bits(f, int_at, 8, (rough / 1024) as u64);
            set_bits(f, mod_at, 10, (rough % 1024) as u64);
            moved.rough = true;
            let mut w = Vec::new();
            for &c in &cells {
                if let Some(v) = valid_pr(f, c) {
                    let (_, width, res) = l.fine_pr(c);
                    let nv = v + (rest_ms / res).round() as i64;
                    if !fits(nv, width) {
                        return Err(Move::Fine);
                    }
                    w.push((c, nv));
                }
            }
            (w, k)
        }
    };
    for (c, v) in writes {
        let (at, w, _) = l.fine_pr(c);
        set_signed(f, at, w, v);
        moved.cells += 1;
    }
    if shift_units != 0 {
        for &c in &cells {
            let (at, w, res) = l.fine_phase(c);
            let v = get_signed(f, at, w);
            let invalid = -(1i64 << (w - 1));
            if v == invalid {
                continue;
            }
            // 2^-10 ms in phase units: exact (a power of two).
            let per_unit = (2f64.powi(-10) / res) as i64;
            let nv = v - shift_units * per_unit;
            if fits(nv, w) {
                set_signed(f, at, w, nv);
            } else {
                set_signed(f, at, w, invalid);
                moved.phase_dropped += 1;
            }
        }
    }
    Ok(moved)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_round_trip() {
        let mut f = vec![0u8; 8];
        set_signed(&mut f, 5, 20, -12345);
        assert_eq!(get_signed(&f, 5, 20), -12345);
        set_bits(&mut f, 30, 10, 1023);
        assert_eq!(get_bits(&f, 30, 10), 1023);
        assert_eq!(get_signed(&f, 5, 20), -12345);
    }

    /// A GLONASS time of day joins the GPS epoch 3 h ahead less whole
    /// leap seconds (18 s in 2020, 0-60 s), across the day's end; a
    /// millisecond off, or 61 s, does not.
    #[test]
    fn glonass_time_of_day_joins_its_gps_epoch() {
        let gps = 3.0 * 86_400.0 + 100.0;
        let tod = |leap_s: i64| (100_000 + MOSCOW_MS - 1000 * leap_s).rem_euclid(DAY_MS);
        assert!(same_epoch(gps, tod(18)));
        assert!(same_epoch(gps, tod(0)));
        assert!(same_epoch(gps, tod(60)));
        assert!(!same_epoch(gps, tod(61)));
        assert!(!same_epoch(gps, tod(18) + 1));
        // 23:59:50 GPS is 02:59:32 Moscow time of the next day.
        let late = 86_400.0 - 10.0;
        assert!(same_epoch(late, (86_390_000 + MOSCOW_MS - 18_000) % DAY_MS));
    }

    #[test]
    fn the_clock_counts_weeks() {
        let mut c = Clock::default();
        assert_eq!(c.at(604_790.0), 604_790.0);
        assert_eq!(c.at(5.0), 604_805.0);
        assert_eq!(c.at(604_799.0), 604_799.0);
        assert_eq!(c.at(6.0), 604_806.0);
    }
}

/// A constellation-wide fault with a displaced solution (ARAIM's
/// constellation fault mode; `raim replay --araim-const-fault`): from
/// `start_s` (stream time, as the fault plan's) to `end_s`, every satellite
/// of `system` gets `raim_gnss::faults::constellation_bias` with the common
/// error `common_m` and the constellation's solution displaced by
/// `shift_enu_m` (east, north, up) at the receiver.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstellationShift {
    pub system: System,
    pub common_m: f64,
    pub shift_enu_m: [f64; 3],
    pub start_s: f64,
    pub end_s: Option<f64>,
}

/// Biases keyed by (stream time ms, satellite).
pub type BiasTable = std::collections::BTreeMap<(i64, SatId), f64>;

/// The stream time's key in a [`BiasTable`].
pub fn time_key(t_s: f64) -> i64 {
    (t_s * 1000.0).round() as i64
}

/// The biases of `faults` at each epoch of `bytes` (read whole,
/// `crate::read_all`: its ephemerides and station position), keyed by
/// stream time (`first_msm_gps_s`'s scale): each satellite's position from
/// the broadcast ephemeris at its transmit time (raim-gnss's preparation,
/// the stream codes, no elevation mask) and the line of sight from the
/// station (RTCM 1005/1006). A satellite the stream has no ephemeris for
/// gets no bias (no receiver could use it). Refused: a stream without a
/// station position.
pub fn constellation_table(
    bytes: &[u8],
    faults: &[ConstellationShift],
) -> Result<BiasTable, ConstellationError> {
    let mut table = BiasTable::new();
    if faults.is_empty() {
        return Ok(table);
    }
    let first = first_msm_gps_s(bytes).ok_or(ConstellationError::Msm(MsmFaultError::NoMsm))?;
    let rec = crate::read_all(crate::Format::Rtcm3, bytes, "stream".into())
        .map_err(|e| ConstellationError::Read(e.to_string()))?;
    let station = rec
        .obs
        .approx_position_m
        .ok_or(ConstellationError::NoStation)?;
    let Some(e0) = rec.obs.epochs.first() else {
        return Ok(table);
    };
    // The reader's GPS times against the stream's: a whole number of weeks.
    let weeks = ((e0.time_gps_s - first) / WEEK_S).round() * WEEK_S;
    let rot = raim_core::frames::enu_rotation(&raim_core::frames::ecef_to_geodetic(station));
    let opts = raim_gnss::ranging::RangingOptions {
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
        elevation_mask_rad: -core::f64::consts::FRAC_PI_2,
        iono: false,
        tropo: true,
        group_delay: true,
        glonass_sigma: None,
    };
    for e in &rec.obs.epochs {
        let t = e.time_gps_s - weeks;
        let active: Vec<&ConstellationShift> = faults
            .iter()
            .filter(|f| t >= f.start_s && f.end_s.is_none_or(|end| t < end))
            .collect();
        if active.is_empty() {
            continue;
        }
        let prepared = raim_gnss::ranging::prepare_epoch(&rec.nav, e, &opts, Some(station));
        let mut sats = prepared.observations();
        for f in active {
            let shift = raim_core::frames::unrotate(&rot, f.shift_enu_m);
            for (id, b) in raim_gnss::faults::constellation_bias(
                &mut sats, f.system, station, f.common_m, shift,
            ) {
                *table.entry((time_key(t), id)).or_default() += b;
            }
        }
    }
    Ok(table)
}

/// Why a constellation fault could not be placed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConstellationError {
    #[error("a constellation fault needs the receiver position: the stream has no station position (RTCM 1005/1006)")]
    NoStation,
    #[error("reading the stream: {0}")]
    Read(String),
    #[error(transparent)]
    Msm(#[from] MsmFaultError),
}

/// [`fault_stream`] with the constellation biases of `table` added
/// ([`constellation_table`]).
pub fn fault_stream_with(
    bytes: &[u8],
    plan: &raim_gnss::faults::FaultPlan,
    table: &BiasTable,
) -> Result<FaultedStream, MsmFaultError> {
    bias_stream(bytes, |t, sats| {
        plan.apply(t, sats);
        for s in sats.iter_mut() {
            if let Some(b) = table.get(&(time_key(t), s.id)) {
                s.pseudorange_m += b;
            }
        }
    })
}
