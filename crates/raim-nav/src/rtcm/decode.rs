//! The firmware's RTCM 3 decoder: the fields the stream receiver uses, read
//! straight from a frame's bits, with small stack frames.
//!
//! Why not `rtcm-rs` on the device: its `Message` enum holds every decoded
//! message by value (6.7 KB with the MSM types alone) and each message
//! type's decode result has its own stack slot, so decoding one frame took
//! about 20 KB of stack whatever the frame (about 45 KB for an MSM7),
//! measured under QEMU (mps2-an386), against the firmware's 16 KiB stack
//! goal (BENCHMARKS.md "Stack"). This decoder keeps an MSM as its header
//! and bit offsets ([`Msm`]) and yields one signal at a time
//! ([`MsmSignals`]). The host's reader (`raim-recv`) keeps `rtcm-rs`,
//! which decodes every message type; the host tests check that both give
//! the same values to the bit on every frame of a real stream and on
//! random messages of `rtcm-rs`'s encoder.
//!
//! What it reads (RTCM 10403.3):
//! - The frame (§4): preamble 0xD3, 10-bit length, CRC-24Q.
//! - MSM4-MSM7 of GPS (1074-1077), GLONASS (1084-1087), Galileo
//!   (1094-1097), QZSS (1114-1117) and BeiDou (1124-1127) (Table 3.5-78
//!   header: a 30-bit time of week, GPS DF004, Galileo DF248, QZSS DF428,
//!   BeiDou DF427 (BDT), GLONASS DF416 + DF034; DF394-DF396 masks,
//!   satellite data DF397, extended info, DF398, DF399, signal data
//!   DF400/DF405, DF403/DF408 and DF404, the rest of the cell's fields
//!   skipped): pseudorange = (DF397 + DF398 + fine range) ms x c / 1000,
//!   phase-range rate = DF399 + DF404 m/s (MSM5/MSM7 only), the signal's
//!   RINEX band and attribute (Tables 3.5-91 GPS, 3.5-96 GLONASS, 3.5-99
//!   Galileo, 3.5-105 QZSS, 3.5-108 BeiDou).
//! - The Keplerian ephemerides 1019 (GPS), 1042 (BeiDou), 1044 (QZSS),
//!   1045 (Galileo F/NAV) and 1046 (Galileo I/NAV) into [`KeplerFields`]
//!   ([`KeplerMessage`], the week as sent), 1020 (GLONASS, sign-magnitude
//!   fields) into [`GlonassIcdFields`]; 1005/1006 antenna reference point
//!   (DF025-DF027, 0.0001 m); 1013 system parameters (DF051 MJD, DF052
//!   UTC seconds of day, DF054 GPS - UTC leap seconds).
//! - Any other message: [`Message::Other`].
//!
//! Each value is computed with the operations `rtcm-rs` uses (the
//! integer, times the field's resolution, in the field's float type), so
//! the host and the device agree to the bit.

use crc::{Crc, NoTable, CRC_24_LTE_A};

use raim_core::System;

use crate::glonass::GlonassIcdFields;

use super::bits::{BitReader, BitsError};
use super::fields::{KeplerFields, LIGHT_MS_M};

/// CRC-24Q, the RTCM 3 frame check (poly 0x864CFB, init 0, not reflected,
/// no xorout: the catalogue's CRC-24/LTE-A).
const CRC24Q: Crc<u32, NoTable> = Crc::<u32, NoTable>::new(&CRC_24_LTE_A);

/// Largest MSM cell mask (DF396): Nsat x Nsig <= 64.
const MAX_CELLS: u32 = 64;

/// Why a frame was not taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameError {
    /// Fewer bytes than the frame's header and CRC, or than its length.
    Incomplete { len: usize, need: usize },
    /// The first byte is not the preamble 0xD3.
    Preamble { byte: u8 },
    /// The CRC-24Q does not match.
    Crc { computed: u32, received: u32 },
}

/// Why a message did not decode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DecodeError {
    /// A field runs past the payload.
    Bits(BitsError),
    /// An MSM whose cell mask would have no cell or more than 64.
    CellCount { satellites: u32, signals: u32 },
    /// An MSM cell whose signal ID has no code in the system's table.
    SignalId { message: u16, signal_id: u8 },
    /// A message number that is not an MSM of the five systems.
    NotMsm { message: u16 },
    /// A message number that is not a Keplerian ephemeris (1019, 1042,
    /// 1044, 1045, 1046).
    NotKepler { message: u16 },
}

impl From<BitsError> for DecodeError {
    fn from(e: BitsError) -> Self {
        DecodeError::Bits(e)
    }
}

impl core::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            DecodeError::Bits(e) => write!(f, "{e}"),
            DecodeError::CellCount {
                satellites,
                signals,
            } => write!(
                f,
                "MSM with {satellites} satellites x {signals} signals: not 1..=64 cells"
            ),
            DecodeError::SignalId { message, signal_id } => {
                write!(
                    f,
                    "{message}: signal ID {signal_id} not in the signal table"
                )
            }
            DecodeError::NotMsm { message } => write!(f, "{message} is not an MSM"),
            DecodeError::NotKepler { message } => {
                write!(f, "{message} is not a Keplerian ephemeris message")
            }
        }
    }
}

/// A checked RTCM 3 frame: its payload and message number.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    payload: &'a [u8],
    number: Option<u16>,
}

impl<'a> Frame<'a> {
    /// Check one frame (preamble to CRC; bytes after its length are not
    /// part of it). The message number is read when the slice has the 8
    /// bytes of a frame with a 2-byte payload, as `rtcm-rs` reads it.
    pub fn new(frame: &'a [u8]) -> Result<Self, FrameError> {
        let len = frame.len();
        let (Some(&b0), Some(&b1), Some(&b2)) = (frame.first(), frame.get(1), frame.get(2)) else {
            return Err(FrameError::Incomplete { len, need: 6 });
        };
        if len < 6 {
            return Err(FrameError::Incomplete { len, need: 6 });
        }
        if b0 != 0xD3 {
            return Err(FrameError::Preamble { byte: b0 });
        }
        let n = (usize::from(b1 & 0b11) << 8) | usize::from(b2);
        let (Some(body), Some(crc)) = (frame.get(..n + 3), frame.get(n + 3..n + 6)) else {
            return Err(FrameError::Incomplete { len, need: n + 6 });
        };
        let received = crc.iter().fold(0u32, |acc, &b| (acc << 8) | u32::from(b));
        let computed = CRC24Q.checksum(body);
        if computed != received {
            return Err(FrameError::Crc { computed, received });
        }
        let number = match (len >= 8, frame.get(3), frame.get(4)) {
            (true, Some(&h), Some(&l)) => Some((u16::from(h) << 4) | (u16::from(l) >> 4)),
            _ => None,
        };
        Ok(Frame {
            payload: body.get(3..).unwrap_or(&[]),
            number,
        })
    }

    /// The message number (DF002).
    pub fn number(&self) -> Option<u16> {
        self.number
    }

    /// The payload (after the 3 header bytes, before the CRC).
    pub fn payload(&self) -> &'a [u8] {
        self.payload
    }

    /// Decode the message: the types the receiver uses, else
    /// [`Message::Other`].
    pub fn message(&self) -> Result<Message<'a>, DecodeError> {
        let Some(n) = self.number else {
            return Ok(Message::Other(None));
        };
        match n {
            1074..=1077 | 1084..=1087 | 1094..=1097 | 1114..=1117 | 1124..=1127 => {
                Msm::new(self.payload, n).map(Message::Msm)
            }
            1019 => msg1019(self.payload).map(Message::Kepler),
            1042 => msg1042(self.payload).map(Message::Kepler),
            1044 => msg1044(self.payload).map(Message::Kepler),
            1045 | 1046 => msg1045_1046(self.payload, n == 1046).map(Message::Kepler),
            1020 => msg1020(self.payload)
                .map(|(fields, tb_tod_s)| Message::Glo1020 { fields, tb_tod_s }),
            1005 | 1006 => {
                station(self.payload, n == 1006).map(|ecef_m| Message::Station { ecef_m })
            }
            1013 => msg1013(self.payload),
            _ => Ok(Message::Other(Some(n))),
        }
    }
}

/// Decode a Keplerian ephemeris message (1019, 1042, 1044, 1045, 1046)
/// from its payload (the message number DF002 on, as
/// [`Frame::payload`]); the same decoding as [`Frame::message`]. The
/// ephemeris store keeps each set as this payload and decodes it when
/// an epoch uses it ([`crate::store::EphemerisStore`]). Another message
/// is [`DecodeError::NotKepler`].
pub fn kepler_message(payload: &[u8]) -> Result<KeplerMessage, DecodeError> {
    let number = BitReader::at(payload, 0).u(12)? as u16;
    match number {
        1019 => msg1019(payload),
        1042 => msg1042(payload),
        1044 => msg1044(payload),
        1045 | 1046 => msg1045_1046(payload, number == 1046),
        _ => Err(DecodeError::NotKepler { message: number }),
    }
}

/// A decoded message.
#[derive(Debug, Clone)]
pub enum Message<'a> {
    /// MSM4-MSM7 of GPS, GLONASS, Galileo, QZSS or BeiDou.
    Msm(Msm<'a>),
    /// 1019, 1042, 1044, 1045 or 1046.
    Kepler(KeplerMessage),
    /// 1020: the ICD fields (t_b not yet placed: `tb_gps_s` 0) and t_b as
    /// seconds of the Moscow day.
    Glo1020 {
        fields: GlonassIcdFields,
        tb_tod_s: f64,
    },
    /// 1005/1006: the antenna reference point, ECEF, m.
    Station { ecef_m: [f64; 3] },
    /// 1013 (system parameters): the station's UTC date and time and the
    /// GPS - UTC leap seconds (DF054; None when sent as 255, unknown).
    SystemParameters {
        /// DF051, the Modified Julian Day of UTC.
        mjd: u16,
        /// DF052, seconds of the UTC day.
        utc_sod_s: u32,
        /// DF054, GPS - UTC, s.
        gps_minus_utc_s: Option<u8>,
    },
    /// A message this decoder does not read (its number, if the frame has
    /// one).
    Other(Option<u16>),
}

/// A Keplerian ephemeris message: the satellite, the week as sent (in
/// the system's own week count, [`super::fields::gps_week_of`] places it)
/// and the fields in the units of [`KeplerFields`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeplerMessage {
    /// 1019, 1042, 1044, 1045 or 1046.
    pub number: u16,
    pub system: System,
    /// GPS DF009, BeiDou DF488 (PRN), QZSS DF429 (satellite ID 1-10, PRN
    /// 193-202), Galileo DF252 (SVID).
    pub prn: u8,
    /// GPS DF076 and QZSS DF452 (GPS week modulo 1024), Galileo DF289 (GST
    /// week modulo 4096), BeiDou DF489 (BDT week modulo 8192).
    pub week_sent: u16,
    pub fields: KeplerFields,
}

/// The MSM's system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MsmSystem {
    Gps,
    Glonass,
    Galileo,
    Qzss,
    Beidou,
}

impl MsmSystem {
    /// The system of MSM message `number` (107x GPS, 108x GLONASS, 109x
    /// Galileo, 111x QZSS, 112x BeiDou), if one of those.
    pub fn of_message(number: u16) -> Option<Self> {
        Some(match number / 10 {
            107 => MsmSystem::Gps,
            108 => MsmSystem::Glonass,
            109 => MsmSystem::Galileo,
            111 => MsmSystem::Qzss,
            112 => MsmSystem::Beidou,
            _ => return None,
        })
    }

    /// The navigation system.
    pub fn system(self) -> System {
        match self {
            MsmSystem::Gps => System::Gps,
            MsmSystem::Glonass => System::Glonass,
            MsmSystem::Galileo => System::Galileo,
            MsmSystem::Qzss => System::Qzss,
            MsmSystem::Beidou => System::Beidou,
        }
    }
}

/// An MSM4-MSM7 of GPS, GLONASS, Galileo, QZSS or BeiDou, checked: its
/// header, masks and where its fields are. The signals are read from the
/// payload as they are iterated ([`Msm::signals`]).
#[derive(Debug, Clone, Copy)]
pub struct Msm<'a> {
    payload: &'a [u8],
    /// The message number (1074-1077, 1084-1087, 1094-1097, 1114-1117,
    /// 1124-1127).
    pub number: u16,
    pub system: MsmSystem,
    /// DF003.
    pub station_id: u16,
    /// The system's time of week, ms: GPS DF004, Galileo DF248 (GST,
    /// aligned with GPS time), QZSS DF428 (QZSST = GPS time), BeiDou DF427
    /// (BDT = GPS - 14 s). GLONASS: DF034, the GLONASS time of day, ms (the
    /// day of the week, DF416, is `glonass_day`).
    pub epoch_ms: u32,
    /// DF416 (GLONASS; 7 = unknown), 0 for the other systems.
    pub glonass_day: u8,
    /// DF393: more messages of this epoch follow.
    pub more: bool,
    sat_mask: u64,
    sig_mask: u32,
    cell_mask: u64,
    n_sat: u32,
    n_sig: u32,
    /// Bit offset of the satellite data.
    sat_at: usize,
    /// Bit offset of the signal data.
    sig_at: usize,
    /// MSM5/MSM7 (extended satellite info and rates).
    extended: bool,
    /// MSM6/MSM7 (DF405 fine ranges of 20 bits).
    high_res: bool,
}

/// One signal of an MSM cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MsmSignal {
    /// Satellite number (1-based position in DF394: PRN, GLONASS slot).
    pub sat_id: u8,
    /// RTCM signal ID (1-based position in DF395).
    pub signal_id: u8,
    /// RINEX 3 band digit (1, 2, 5).
    pub band: u8,
    /// RINEX 3 attribute letter (ASCII).
    pub attribute: u8,
    /// (DF397 + DF398 + DF400/DF405) x c / 1000, m; `None` when the rough
    /// or the fine range is marked invalid.
    pub pseudorange_m: Option<f64>,
    /// The signal's C/N0, dB-Hz: DF403 (MSM4/5, 1 dB-Hz) or DF408
    /// (MSM6/7, 2^-4 dB-Hz); `None` when the field says 0 ("not
    /// computed").
    pub cnr_dbhz: Option<f64>,
    /// The signal's phase-range rate, m/s: the satellite's rough rate
    /// DF399 (14 bits, 1 m/s) plus the signal's fine rate DF404 (15 bits,
    /// 0.0001 m/s), MSM5 and MSM7 only (RTCM 10403.3 Tables 3.5-82,
    /// 3.5-86, 3.5-90, 3.5-91); positive for a receding satellite (the
    /// Doppler shift times -lambda). `None` for MSM4/MSM6 (they carry
    /// no rate) or when either field holds its invalid mark (DF399
    /// -8192, DF404 -16384).
    pub phase_range_rate_m_s: Option<f64>,
}

/// A set bit's 1-based position, counted from the most significant of
/// `width` bits: the `n`-th (0-based) set one.
fn nth_set(mask: u64, width: u32, n: u32) -> Option<u8> {
    let mut seen = 0;
    for p in 0..width {
        if (mask >> (width - 1 - p)) & 1 == 1 {
            if seen == n {
                return u8::try_from(p + 1).ok();
            }
            seen += 1;
        }
    }
    None
}

/// RTCM 10403.3 Table 3.5-91 (GPS signal IDs): band and attribute.
fn gps_signal(id: u8) -> Option<(u8, u8)> {
    Some(match id {
        2 => (1, b'C'),
        3 => (1, b'P'),
        4 => (1, b'W'),
        8 => (2, b'C'),
        9 => (2, b'P'),
        10 => (2, b'W'),
        15 => (2, b'S'),
        16 => (2, b'L'),
        17 => (2, b'X'),
        22 => (5, b'I'),
        23 => (5, b'Q'),
        24 => (5, b'X'),
        30 => (1, b'S'),
        31 => (1, b'L'),
        32 => (1, b'X'),
        _ => return None,
    })
}

/// RTCM 10403.3 Table 3.5-96 (GLONASS signal IDs): band and attribute.
fn glonass_signal(id: u8) -> Option<(u8, u8)> {
    Some(match id {
        2 => (1, b'C'),
        3 => (1, b'P'),
        8 => (2, b'C'),
        9 => (2, b'P'),
        _ => return None,
    })
}

/// RTCM 10403.3 Table 3.5-99 (Galileo signal IDs): band and attribute
/// (E1 1, E6 6, E5b 7, E5a+b 8, E5a 5).
fn galileo_signal(id: u8) -> Option<(u8, u8)> {
    Some(match id {
        2 => (1, b'C'),
        3 => (1, b'A'),
        4 => (1, b'B'),
        5 => (1, b'X'),
        6 => (1, b'Z'),
        8 => (6, b'C'),
        9 => (6, b'A'),
        10 => (6, b'B'),
        11 => (6, b'X'),
        12 => (6, b'Z'),
        14 => (7, b'I'),
        15 => (7, b'Q'),
        16 => (7, b'X'),
        18 => (8, b'I'),
        19 => (8, b'Q'),
        20 => (8, b'X'),
        22 => (5, b'I'),
        23 => (5, b'Q'),
        24 => (5, b'X'),
        _ => return None,
    })
}

/// RTCM 10403.3 Table 3.5-105 (QZSS signal IDs): band and attribute
/// (L1 1, LEX/L6 6, L2 2, L5 5).
fn qzss_signal(id: u8) -> Option<(u8, u8)> {
    Some(match id {
        2 => (1, b'C'),
        9 => (6, b'S'),
        10 => (6, b'L'),
        11 => (6, b'X'),
        15 => (2, b'S'),
        16 => (2, b'L'),
        17 => (2, b'X'),
        22 => (5, b'I'),
        23 => (5, b'Q'),
        24 => (5, b'X'),
        30 => (1, b'S'),
        31 => (1, b'L'),
        32 => (1, b'X'),
        _ => return None,
    })
}

/// RTCM 10403.3 Table 3.5-108 (BeiDou signal IDs): band and attribute
/// (B1I 2, B3I 6, B2I/B2b 7, B2a 5, B1C 1).
fn beidou_signal(id: u8) -> Option<(u8, u8)> {
    Some(match id {
        2 => (2, b'I'),
        3 => (2, b'Q'),
        4 => (2, b'X'),
        8 => (6, b'I'),
        9 => (6, b'Q'),
        10 => (6, b'X'),
        14 => (7, b'I'),
        15 => (7, b'Q'),
        16 => (7, b'X'),
        22 => (5, b'D'),
        23 => (5, b'P'),
        24 => (5, b'X'),
        25 => (7, b'D'),
        30 => (1, b'D'),
        31 => (1, b'P'),
        32 => (1, b'X'),
        _ => return None,
    })
}

impl<'a> Msm<'a> {
    /// Check an MSM4-MSM7 payload of message `number`: the header (Table
    /// 3.5-78: DF002 12, DF003 12, the epoch time 30 (GPS DF004; GLONASS
    /// DF416 3 + DF034 27), DF393 1, DF409 3, DF001 7, DF411 2, DF412 2,
    /// DF417 1, DF418 3), the masks (DF394 64, DF395 32, DF396 Nsat x Nsig
    /// bits: 1..=64 cells), every cell's signal ID, and that the payload
    /// holds all the satellite and signal data.
    pub fn new(payload: &'a [u8], number: u16) -> Result<Self, DecodeError> {
        let system =
            MsmSystem::of_message(number).ok_or(DecodeError::NotMsm { message: number })?;
        let kind = number % 10;
        let extended = kind == 5 || kind == 7;
        let high_res = kind == 6 || kind == 7;
        let mut r = BitReader::at(payload, 12);
        let station_id = r.u(12)? as u16;
        let (glonass_day, epoch_ms) = match system {
            MsmSystem::Glonass => (r.u8(3)?, r.u32(27)?),
            _ => (0, r.u32(30)?),
        };
        let more = r.u(1)? == 1;
        // DF409, DF001 (7), DF411, DF412, DF417, DF418.
        r.skip(3 + 7 + 2 + 2 + 1 + 3)?;
        let sat_mask = r.u(64)?;
        let sig_mask = r.u32(32)?;
        let n_sat = sat_mask.count_ones();
        let n_sig = sig_mask.count_ones();
        let cells = n_sat * n_sig;
        if cells == 0 || cells > MAX_CELLS {
            return Err(DecodeError::CellCount {
                satellites: n_sat,
                signals: n_sig,
            });
        }
        let cell_mask = r.u(cells)?;
        let sat_at = r.position_bits();
        let sat_bits: usize = if extended { 8 + 4 + 10 + 14 } else { 8 + 10 };
        let cell_bits: usize = match (high_res, extended) {
            (false, false) => 15 + 22 + 4 + 1 + 6,
            (false, true) => 15 + 22 + 4 + 1 + 6 + 15,
            (true, false) => 20 + 24 + 10 + 1 + 10,
            (true, true) => 20 + 24 + 10 + 1 + 10 + 15,
        };
        let n_cell = cell_mask.count_ones() as usize;
        let sig_at = sat_at + sat_bits * n_sat as usize;
        let data_bits = sat_bits * n_sat as usize + cell_bits * n_cell;
        if !r.has(data_bits) {
            return Err(DecodeError::Bits(BitsError::PastEnd {
                offset_bits: sat_at,
                width_bits: u32::try_from(data_bits).unwrap_or(u32::MAX),
                len_bits: r.len_bits(),
            }));
        }
        let m = Msm {
            payload,
            number,
            system,
            station_id,
            epoch_ms,
            glonass_day,
            more,
            sat_mask,
            sig_mask,
            cell_mask,
            n_sat,
            n_sig,
            sat_at,
            sig_at,
            extended,
            high_res,
        };
        for c in 0..cells {
            if (cell_mask >> (cells - 1 - c)) & 1 == 1 {
                // n_sig >= 1 whenever there is a cell (cells = n_sat n_sig).
                let j = c.checked_rem(n_sig).unwrap_or(0);
                let signal_id = nth_set(u64::from(sig_mask), 32, j).unwrap_or(0);
                if m.code(signal_id).is_none() {
                    return Err(DecodeError::SignalId {
                        message: number,
                        signal_id,
                    });
                }
            }
        }
        Ok(m)
    }

    fn code(&self, signal_id: u8) -> Option<(u8, u8)> {
        match self.system {
            MsmSystem::Gps => gps_signal(signal_id),
            MsmSystem::Glonass => glonass_signal(signal_id),
            MsmSystem::Galileo => galileo_signal(signal_id),
            MsmSystem::Qzss => qzss_signal(signal_id),
            MsmSystem::Beidou => beidou_signal(signal_id),
        }
    }

    /// Satellites (DF394 bits set).
    pub fn satellites(&self) -> u32 {
        self.n_sat
    }

    /// The signals in cell order (satellite, then signal, by mask
    /// position), each read from the payload as it is reached.
    pub fn signals(&self) -> MsmSignals<'_, 'a> {
        MsmSignals {
            msm: self,
            cell: 0,
            k: 0,
        }
    }

    /// The C/N0 of cell `k` (0-based among the set cells), dB-Hz: the
    /// signal data hold each field for every cell in turn (RTCM 10403.3
    /// Tables 3.5-85 to 3.5-91: fine range, fine phase, lock time,
    /// half-cycle, then the C/N0), so DF403 (6 bits, 1 dB-Hz) or DF408 (10
    /// bits, 2^-4 dB-Hz) of cell `k` follows the first four fields of all
    /// the cells. 0 is "not computed": `None`.
    fn cnr_dbhz(&self, k: usize) -> Result<Option<f64>, BitsError> {
        let n_cell = self.cell_mask.count_ones() as usize;
        let v = if self.high_res {
            let at = self.sig_at + (20 + 24 + 10 + 1) * n_cell + 10 * k;
            f64::from(BitReader::at(self.payload, at).u32(10)?) * (1.0 / 16.0)
        } else {
            let at = self.sig_at + (15 + 22 + 4 + 1) * n_cell + 6 * k;
            f64::from(BitReader::at(self.payload, at).u8(6)?)
        };
        Ok((v > 0.0).then_some(v))
    }

    /// The phase-range rate of cell `k` (0-based among the set cells) of
    /// satellite `i` (0-based among the set satellites), m/s: MSM5/MSM7
    /// only. The satellite data hold DF397 for every satellite, then the
    /// extended info (4 bits), DF398 (10 bits) and DF399 (14 bits) for
    /// every satellite in turn; the signal data hold DF404 (15 bits) of
    /// every cell after its other fields (RTCM 10403.3 Tables 3.5-78 to
    /// 3.5-91). The value is `rtcm-rs`'s: DF399 as an integer in f64, plus
    /// DF404's integer times 0.0001 in f64.
    fn phase_range_rate_m_s(&self, i: usize, k: usize) -> Result<Option<f64>, BitsError> {
        if !self.extended {
            return Ok(None);
        }
        let n = self.n_sat as usize;
        let n_cell = self.cell_mask.count_ones() as usize;
        let p = self.payload;
        let rough = BitReader::at(p, self.sat_at + (8 + 4 + 10) * n + 14 * i).i(14)?;
        let before_rate = if self.high_res {
            20 + 24 + 10 + 1 + 10
        } else {
            15 + 22 + 4 + 1 + 6
        };
        let fine = BitReader::at(p, self.sig_at + before_rate * n_cell + 15 * k).i(15)?;
        if rough == -0x2000 || fine == -0x4000 {
            return Ok(None);
        }
        Ok(Some(rough as f64 + fine as f64 * 0.0001))
    }

    /// The pseudorange of cell `k` (0-based among the set cells) of
    /// satellite `i` (0-based among the set satellites).
    fn pseudorange_m(&self, i: usize, k: usize) -> Result<Option<f64>, BitsError> {
        let n = self.n_sat as usize;
        let p = self.payload;
        // DF397: integer milliseconds, 0xFF = invalid.
        let int_ms = BitReader::at(p, self.sat_at + 8 * i).u8(8)?;
        // DF398 after DF397 (and the 4-bit extended info of MSM5/7).
        let mod_at = self.sat_at + if self.extended { 12 } else { 8 } * n + 10 * i;
        let mod1ms_ms = BitReader::at(p, mod_at).u(10)? as f64 * (1.0 / 1024.0);
        let fine_ms = if self.high_res {
            // DF405: 2^-29 ms, the minimum = invalid.
            let v = BitReader::at(p, self.sig_at + 20 * k).i(20)?;
            (v != -0x8_0000).then(|| v as f64 * (1.0 / (512.0 * 1024.0 * 1024.0)))
        } else {
            // DF400: 2^-24 ms, the minimum = invalid.
            let v = BitReader::at(p, self.sig_at + 15 * k).i(15)?;
            (v != -0x4000).then(|| v as f64 * (1.0 / (16.0 * 1024.0 * 1024.0)))
        };
        if int_ms == 0xFF {
            return Ok(None);
        }
        let rough_ms = f64::from(int_ms) + mod1ms_ms;
        Ok(fine_ms.map(|fine_ms| (rough_ms + fine_ms) * LIGHT_MS_M))
    }
}

/// The signals of an [`Msm`], in cell order.
#[derive(Debug, Clone)]
pub struct MsmSignals<'m, 'a> {
    msm: &'m Msm<'a>,
    /// Next position in the cell mask.
    cell: u32,
    /// Set cells passed.
    k: usize,
}

impl Iterator for MsmSignals<'_, '_> {
    type Item = MsmSignal;

    fn next(&mut self) -> Option<MsmSignal> {
        let m = self.msm;
        let cells = m.n_sat * m.n_sig;
        while self.cell < cells {
            let c = self.cell;
            self.cell += 1;
            if (m.cell_mask >> (cells - 1 - c)) & 1 == 0 {
                continue;
            }
            let k = self.k;
            self.k += 1;
            // n_sig >= 1 whenever there is a cell (cells = n_sat n_sig).
            let i = c.checked_div(m.n_sig)?;
            let sat_id = nth_set(m.sat_mask, 64, i)?;
            let signal_id = nth_set(u64::from(m.sig_mask), 32, c.checked_rem(m.n_sig)?)?;
            let (band, attribute) = m.code(signal_id)?;
            // Checked in `Msm::new`: the payload holds every cell.
            let pseudorange_m = m.pseudorange_m(i as usize, k).ok()?;
            let cnr_dbhz = m.cnr_dbhz(k).ok()?;
            let phase_range_rate_m_s = m.phase_range_rate_m_s(i as usize, k).ok()?;
            return Some(MsmSignal {
                sat_id,
                signal_id,
                band,
                attribute,
                pseudorange_m,
                cnr_dbhz,
                phase_range_rate_m_s,
            });
        }
        None
    }
}

/// The multiple-message bit (DF393) of an MSM frame: bit 54 of the
/// payload, after DF002 (12 bits), DF003 (12) and the epoch time (30;
/// RTCM 10403.3 Table 3.5-78), the payload starting at byte 3.
pub fn msm_more_bit(frame: &[u8]) -> Option<bool> {
    frame.get(3 + 54 / 8).map(|b| b & (0x80 >> (54 % 8)) != 0)
}

/// A two's complement field times its resolution, in f64.
fn f64_i(r: &mut BitReader<'_>, width: u32, res: f64) -> Result<f64, BitsError> {
    Ok(r.i(width)? as f64 * res)
}

/// An unsigned field times its resolution, in f64.
fn f64_u(r: &mut BitReader<'_>, width: u32, res: f64) -> Result<f64, BitsError> {
    Ok(r.u(width)? as f64 * res)
}

/// A two's complement field (at most 24 bits, exact in f32) times its
/// resolution in f32 (the fields `rtcm-rs` holds as f32), widened.
fn f32_i(r: &mut BitReader<'_>, width: u32, res: f32) -> Result<f64, BitsError> {
    Ok(f64::from(r.i(width)? as f32 * res))
}

/// An unsigned field (at most 24 bits, exact in f32) times its resolution
/// in f32.
fn f32_u(r: &mut BitReader<'_>, width: u32, res: f32) -> Result<f64, BitsError> {
    Ok(f64::from(r.u(width)? as f32 * res))
}

/// A sign-magnitude field times its resolution, in f64.
fn f64_sm(r: &mut BitReader<'_>, width: u32, res: f64) -> Result<f64, BitsError> {
    Ok(r.sm(width)? as f64 * res)
}

/// A sign-magnitude field (at most 16 bits) times its resolution in f32.
fn f32_sm(r: &mut BitReader<'_>, width: u32, res: f32) -> Result<f64, BitsError> {
    Ok(f64::from(r.sm(width)? as f32 * res))
}

/// 2^-n as f64 and f32.
const P2_19: f64 = 1.0 / (1024.0 * 512.0);
const P2_31: f64 = 1.0 / (1024.0 * 1024.0 * 1024.0 * 2.0);
const P2_33: f64 = 1.0 / (1024.0 * 1024.0 * 1024.0 * 8.0);
const P2_43: f64 = 1.0 / (1024.0 * 1024.0 * 1024.0 * 1024.0 * 8.0);
const P2_5_F: f32 = 1.0 / 32.0;
const P2_29_F: f32 = 1.0 / (1024.0 * 1024.0 * 512.0);
const P2_31_F: f32 = 1.0 / (1024.0 * 1024.0 * 1024.0 * 2.0);
const P2_43_F: f32 = 1.0 / (1024.0 * 1024.0 * 1024.0 * 1024.0 * 8.0);
const P2_55_F: f32 = 1.0 / (1024.0 * 1024.0 * 1024.0 * 1024.0 * 1024.0 * 32.0);

/// 1019 (RTCM 10403.3 §3.5.11, 488 bits): DF002 12, DF009 6, DF076 10,
/// DF077 4, DF078 2, DF079 IDOT 14 (2^-43 sc/s), DF071 IODE 8, DF081 toc
/// 16 (2^4 s), DF082 af2 8 (2^-55), DF083 af1 16 (2^-43), DF084 af0 22
/// (2^-31), DF085 IODC 10, DF086 Crs 16 (2^-5 m), DF087 delta n 16
/// (2^-43 sc/s), DF088 M0 32 (2^-31 sc), DF089 Cuc 16 (2^-29 rad), DF090 e
/// 32 (2^-33), DF091 Cus 16, DF092 sqrt A 32 (2^-19), DF093 toe 16 (2^4
/// s), DF094 Cic 16, DF095 Omega0 32 (2^-31), DF096 Cis 16, DF097 i0 32,
/// DF098 Crc 16 (2^-5 m), DF099 omega 32, DF100 Omega dot 24 (2^-43),
/// DF101 TGD 8 (2^-31 s), DF102 health 6, DF103 1, DF137 1.
fn msg1019(payload: &[u8]) -> Result<KeplerMessage, DecodeError> {
    let mut r = BitReader::at(payload, 12);
    let prn = r.u8(6)?;
    let week_mod1024 = r.u(10)? as u16;
    r.skip(4 + 2)?;
    let idot_sc = f64_i(&mut r, 14, P2_43)?;
    let iode = r.u32(8)?;
    let toc_s = f32_u(&mut r, 16, 16.0)?;
    let af2 = f32_i(&mut r, 8, P2_55_F)?;
    let af1 = f32_i(&mut r, 16, P2_43_F)?;
    let af0 = f64_i(&mut r, 22, P2_31)?;
    r.skip(10)?;
    let crs = f32_i(&mut r, 16, P2_5_F)?;
    let delta_n_sc = f32_i(&mut r, 16, P2_43_F)?;
    let m0_sc = f64_i(&mut r, 32, P2_31)?;
    let cuc = f32_i(&mut r, 16, P2_29_F)?;
    let e = f64_u(&mut r, 32, P2_33)?;
    let cus = f32_i(&mut r, 16, P2_29_F)?;
    let sqrt_a = f64_u(&mut r, 32, P2_19)?;
    let toe_s = f32_u(&mut r, 16, 16.0)?;
    let cic = f32_i(&mut r, 16, P2_29_F)?;
    let omega0_sc = f64_i(&mut r, 32, P2_31)?;
    let cis = f32_i(&mut r, 16, P2_29_F)?;
    let i0_sc = f64_i(&mut r, 32, P2_31)?;
    let crc = f32_i(&mut r, 16, P2_5_F)?;
    let omega_sc = f64_i(&mut r, 32, P2_31)?;
    let omega_dot_sc = f64_i(&mut r, 24, P2_43)?;
    let tgd = f32_i(&mut r, 8, P2_31_F)?;
    let health = r.u32(6)?;
    r.skip(1 + 1)?;
    Ok(KeplerMessage {
        number: 1019,
        system: System::Gps,
        prn,
        week_sent: week_mod1024,
        fields: KeplerFields {
            toc_s,
            toe_s,
            af0,
            af1,
            af2,
            sqrt_a,
            e,
            i0_sc,
            omega0_sc,
            omega_sc,
            m0_sc,
            delta_n_sc,
            omega_dot_sc,
            idot_sc,
            cuc,
            cus,
            crc,
            crs,
            cic,
            cis,
            tgd,
            tgd2: 0.0,
            health,
            iod: iode,
        },
    })
}

/// More 2^-n resolutions as f64 and f32, and BeiDou's 0.1 ns (DF513) in
/// f32, each as `rtcm-rs` writes it.
const P2_34: f64 = 1.0 / (1024.0 * 1024.0 * 1024.0 * 16.0);
const P2_46: f64 = 1.0 / (1024.0 * 1024.0 * 1024.0 * 1024.0 * 64.0);
const P2_50: f64 = 1.0 / (1024.0 * 1024.0 * 1024.0 * 1024.0 * 1024.0);
const P2_6_F: f32 = 1.0 / 64.0;
const P2_32_F: f32 = 1.0 / (1024.0 * 1024.0 * 1024.0 * 4.0);
const P2_59_F: f32 = 1.0 / (1024.0 * 1024.0 * 1024.0 * 1024.0 * 1024.0 * 512.0);
const P2_66_F: f32 = 1.0 / (1024.0 * 1024.0 * 1024.0 * 1024.0 * 1024.0 * 1024.0 * 64.0);
const TENTH_NS_F: f32 = 1.0 / 10_000_000_000.0;

/// 1045 (Galileo F/NAV, RTCM 10403.3 §3.5.14, 496 bits) and 1046
/// (Galileo I/NAV, 504 bits): DF252 SVID 6, DF289 GST week 12, DF290
/// IODnav 10, DF291/DF286 SISA 8, DF292 IDOT 14 (2^-43 sc/s), DF293 toc 14
/// (60 s), DF294 af2 6 (2^-59), DF295 af1 21 (2^-46), DF296 af0 31
/// (2^-34), DF297 Crs 16 (2^-5 m), DF298 delta n 16 (2^-43), DF299 M0 32
/// (2^-31), DF300 Cuc 16 (2^-29), DF301 e 32 (2^-33), DF302 Cus 16,
/// DF303 sqrt A 32 (2^-19), DF304 toe 14 (60 s), DF305 Cic 16, DF306
/// Omega0 32, DF307 Cis 16, DF308 i0 32, DF309 Crc 16, DF310 omega 32,
/// DF311 Omega dot 24 (2^-43), DF312 BGD(E1,E5a) 10 (2^-32 s); 1045:
/// DF314 E5a health 2, DF315 E5a data validity 1, 7 reserved; 1046: DF313
/// BGD(E1,E5b) 10, DF316 E5b health 2, DF317 E5b validity 1, DF287 E1-B
/// health 2, DF288 E1-B validity 1, 2 reserved. Group delays and health
/// as the host's reader takes them (`fields::msg1045_fields`,
/// `fields::msg1046_fields`): F/NAV's clock is the E1/E5a pair's, so its
/// BGD(E1,E5a) serves E1 alone and the pair; the health word packs the
/// signal health and data validity bits of the message.
fn msg1045_1046(payload: &[u8], inav: bool) -> Result<KeplerMessage, DecodeError> {
    let mut r = BitReader::at(payload, 12);
    let prn = r.u8(6)?;
    let week_sent = r.u(12)? as u16;
    let iod = r.u32(10)?;
    r.skip(8)?;
    let idot_sc = f32_i(&mut r, 14, P2_43_F)?;
    let toc_s = f32_u(&mut r, 14, 60.0)?;
    let af2 = f32_i(&mut r, 6, P2_59_F)?;
    let af1 = f64_i(&mut r, 21, P2_46)?;
    let af0 = f64_i(&mut r, 31, P2_34)?;
    let crs = f32_i(&mut r, 16, P2_5_F)?;
    let delta_n_sc = f32_i(&mut r, 16, P2_43_F)?;
    let m0_sc = f64_i(&mut r, 32, P2_31)?;
    let cuc = f32_i(&mut r, 16, P2_29_F)?;
    let e = f64_u(&mut r, 32, P2_33)?;
    let cus = f32_i(&mut r, 16, P2_29_F)?;
    let sqrt_a = f64_u(&mut r, 32, P2_19)?;
    let toe_s = f32_u(&mut r, 14, 60.0)?;
    let cic = f32_i(&mut r, 16, P2_29_F)?;
    let omega0_sc = f64_i(&mut r, 32, P2_31)?;
    let cis = f32_i(&mut r, 16, P2_29_F)?;
    let i0_sc = f64_i(&mut r, 32, P2_31)?;
    let crc = f32_i(&mut r, 16, P2_5_F)?;
    let omega_sc = f64_i(&mut r, 32, P2_31)?;
    let omega_dot_sc = f64_i(&mut r, 24, P2_43)?;
    let bgd_e1_e5a = f32_i(&mut r, 10, P2_32_F)?;
    let (tgd, health) = if inav {
        let bgd_e1_e5b = f32_i(&mut r, 10, P2_32_F)?;
        let e5b_health = r.u32(2)?;
        let e5b_validity = r.u32(1)?;
        let e1b_health = r.u32(2)?;
        let e1b_validity = r.u32(1)?;
        r.skip(2)?;
        (
            bgd_e1_e5b,
            e1b_health | (e1b_validity << 2) | (e5b_health << 3) | (e5b_validity << 5),
        )
    } else {
        let e5a_health = r.u32(2)?;
        let e5a_validity = r.u32(1)?;
        r.skip(7)?;
        (bgd_e1_e5a, e5a_health | (e5a_validity << 2))
    };
    Ok(KeplerMessage {
        number: if inav { 1046 } else { 1045 },
        system: System::Galileo,
        prn,
        week_sent,
        fields: KeplerFields {
            toc_s,
            toe_s,
            af0,
            af1,
            af2,
            sqrt_a,
            e,
            i0_sc,
            omega0_sc,
            omega_sc,
            m0_sc,
            delta_n_sc,
            omega_dot_sc,
            idot_sc,
            cuc,
            cus,
            crc,
            crs,
            cic,
            cis,
            tgd,
            tgd2: bgd_e1_e5a,
            health,
            iod,
        },
    })
}

/// 1042 (BeiDou, RTCM 10403.3 §3.5.15, 511 bits): DF488 PRN 6, DF489 BDT
/// week 13, DF490 URA 4, DF491 IDOT 14 (2^-43 sc/s), DF492 AODE 5, DF493
/// toc 17 (8 s, BDT), DF494 a2 11 (2^-66), DF495 a1 22 (2^-50), DF496 a0
/// 24 (2^-33), DF497 AODC 5, DF498 Crs 18 (2^-6 m), DF499 delta n 16
/// (2^-43), DF500 M0 32 (2^-31), DF501 Cuc 18 (2^-31), DF502 e 32
/// (2^-33), DF503 Cus 18, DF504 sqrt A 32 (2^-19), DF505 toe 17 (8 s),
/// DF506 Cic 18, DF507 Omega0 32, DF508 Cis 18, DF509 i0 32, DF510 Crc 18
/// (2^-6 m), DF511 omega 32, DF512 Omega dot 24 (2^-43), DF513 TGD1 10
/// (0.1 ns), DF514 TGD2 10, DF515 health 1. TGD1 is the B1I group delay
/// the ranging applies; AODE is the issue of data.
fn msg1042(payload: &[u8]) -> Result<KeplerMessage, DecodeError> {
    let mut r = BitReader::at(payload, 12);
    let prn = r.u8(6)?;
    let week_sent = r.u(13)? as u16;
    r.skip(4)?;
    let idot_sc = f64_i(&mut r, 14, P2_43)?;
    let iod = r.u32(5)?;
    let toc_s = f32_u(&mut r, 17, 8.0)?;
    let af2 = f32_i(&mut r, 11, P2_66_F)?;
    let af1 = f64_i(&mut r, 22, P2_50)?;
    let af0 = f64_i(&mut r, 24, P2_33)?;
    r.skip(5)?;
    let crs = f32_i(&mut r, 18, P2_6_F)?;
    let delta_n_sc = f32_i(&mut r, 16, P2_43_F)?;
    let m0_sc = f64_i(&mut r, 32, P2_31)?;
    let cuc = f32_i(&mut r, 18, P2_31_F)?;
    let e = f64_u(&mut r, 32, P2_33)?;
    let cus = f32_i(&mut r, 18, P2_31_F)?;
    let sqrt_a = f64_u(&mut r, 32, P2_19)?;
    let toe_s = f32_u(&mut r, 17, 8.0)?;
    let cic = f32_i(&mut r, 18, P2_31_F)?;
    let omega0_sc = f64_i(&mut r, 32, P2_31)?;
    let cis = f32_i(&mut r, 18, P2_31_F)?;
    let i0_sc = f64_i(&mut r, 32, P2_31)?;
    let crc = f32_i(&mut r, 18, P2_6_F)?;
    let omega_sc = f64_i(&mut r, 32, P2_31)?;
    let omega_dot_sc = f64_i(&mut r, 24, P2_43)?;
    let tgd = f32_i(&mut r, 10, TENTH_NS_F)?;
    r.skip(10)?;
    let health = r.u32(1)?;
    Ok(KeplerMessage {
        number: 1042,
        system: System::Beidou,
        prn,
        week_sent,
        fields: KeplerFields {
            toc_s,
            toe_s,
            af0,
            af1,
            af2,
            sqrt_a,
            e,
            i0_sc,
            omega0_sc,
            omega_sc,
            m0_sc,
            delta_n_sc,
            omega_dot_sc,
            idot_sc,
            cuc,
            cus,
            crc,
            crs,
            cic,
            cis,
            tgd,
            tgd2: 0.0,
            health,
            iod,
        },
    })
}

/// 1044 (QZSS, RTCM 10403.3 §3.5.13, 485 bits): DF429 satellite ID 4,
/// DF430 toc 16 (2^4 s), DF431 af2 8 (2^-55), DF432 af1 16 (2^-43), DF433
/// af0 22 (2^-31), DF434 IODE 8, DF435 Crs 16 (2^-5 m), DF436 delta n 16
/// (2^-43), DF437 M0 32 (2^-31), DF438 Cuc 16 (2^-29), DF439 e 32
/// (2^-33), DF440 Cus 16, DF441 sqrt A 32 (2^-19), DF442 toe 16 (2^4 s),
/// DF443 Cic 16, DF444 Omega0 32, DF445 Cis 16, DF446 i0 32, DF447 Crc 16,
/// DF448 omega 32, DF449 Omega dot 24 (2^-43), DF450 IDOT 14 (2^-43),
/// DF451 L2 codes 2, DF452 week 10, DF453 URA 4, DF454 health 6, DF455
/// TGD 8 (2^-31 s), DF456 IODC 10, DF457 fit interval 1.
fn msg1044(payload: &[u8]) -> Result<KeplerMessage, DecodeError> {
    let mut r = BitReader::at(payload, 12);
    let prn = r.u8(4)?;
    let toc_s = f32_u(&mut r, 16, 16.0)?;
    let af2 = f32_i(&mut r, 8, P2_55_F)?;
    let af1 = f32_i(&mut r, 16, P2_43_F)?;
    let af0 = f64_i(&mut r, 22, P2_31)?;
    let iod = r.u32(8)?;
    let crs = f32_i(&mut r, 16, P2_5_F)?;
    let delta_n_sc = f32_i(&mut r, 16, P2_43_F)?;
    let m0_sc = f64_i(&mut r, 32, P2_31)?;
    let cuc = f32_i(&mut r, 16, P2_29_F)?;
    let e = f64_u(&mut r, 32, P2_33)?;
    let cus = f32_i(&mut r, 16, P2_29_F)?;
    let sqrt_a = f64_u(&mut r, 32, P2_19)?;
    let toe_s = f32_u(&mut r, 16, 16.0)?;
    let cic = f32_i(&mut r, 16, P2_29_F)?;
    let omega0_sc = f64_i(&mut r, 32, P2_31)?;
    let cis = f32_i(&mut r, 16, P2_29_F)?;
    let i0_sc = f64_i(&mut r, 32, P2_31)?;
    let crc = f32_i(&mut r, 16, P2_5_F)?;
    let omega_sc = f64_i(&mut r, 32, P2_31)?;
    let omega_dot_sc = f64_i(&mut r, 24, P2_43)?;
    let idot_sc = f64_i(&mut r, 14, P2_43)?;
    r.skip(2)?;
    let week_sent = r.u(10)? as u16;
    r.skip(4)?;
    let health = r.u32(6)?;
    let tgd = f32_i(&mut r, 8, P2_31_F)?;
    r.skip(10 + 1)?;
    Ok(KeplerMessage {
        number: 1044,
        system: System::Qzss,
        prn,
        week_sent,
        fields: KeplerFields {
            toc_s,
            toe_s,
            af0,
            af1,
            af2,
            sqrt_a,
            e,
            i0_sc,
            omega0_sc,
            omega_sc,
            m0_sc,
            delta_n_sc,
            omega_dot_sc,
            idot_sc,
            cuc,
            cus,
            crc,
            crs,
            cic,
            cis,
            tgd,
            tgd2: 0.0,
            health,
            iod,
        },
    })
}

/// 1020 (RTCM 10403.3 §3.5.12, 360 bits): DF038 slot 6, DF040 channel 5
/// (k + 7), DF104, DF105, DF106 2, DF107 t_k 12, DF108 the MSB of B_n,
/// DF109, DF110 t_b 7 (15 min), then sign-magnitude: DF111/114/117
/// velocity 24 (2^-20 km/s), DF112/115/118 position 27 (2^-11 km),
/// DF113/116/119 acceleration 5 (2^-30 km/s^2); DF120, DF121 gamma_n 11
/// (2^-40), DF122 2, DF123 l_n (third string), DF124 tau_n 22 (2^-30 s),
/// and the GLONASS-M fields to the end (DF125-DF136, 7 reserved bits).
/// The fields as `fields::glonass_fields` (feature `rtcm-rs`) gives them from
/// `rtcm-rs`'s 1020, and t_b as seconds of the Moscow day.
fn msg1020(payload: &[u8]) -> Result<(GlonassIcdFields, f64), DecodeError> {
    let mut r = BitReader::at(payload, 12);
    let slot = r.u8(6)?;
    let frequency_channel = r.u8(5)? as i8 - 7;
    // DF104, DF105, DF106, DF107.
    r.skip(1 + 1 + 2 + 12)?;
    let bn_msb = r.u(1)?;
    r.skip(1)?;
    let tb_min = r.u(7)? as u16 * 15;
    const V: f64 = 1.0 / (1024.0 * 1024.0);
    const X: f64 = 1.0 / (1024.0 * 2.0);
    const A: f32 = 1.0 / (1024.0 * 1024.0 * 1024.0);
    let vx_km_s = f64_sm(&mut r, 24, V)?;
    let x_km = f64_sm(&mut r, 27, X)?;
    let ax_km_s2 = f32_sm(&mut r, 5, A)?;
    let vy_km_s = f64_sm(&mut r, 24, V)?;
    let y_km = f64_sm(&mut r, 27, X)?;
    let ay_km_s2 = f32_sm(&mut r, 5, A)?;
    let vz_km_s = f64_sm(&mut r, 24, V)?;
    let z_km = f64_sm(&mut r, 27, X)?;
    let az_km_s2 = f32_sm(&mut r, 5, A)?;
    r.skip(1)?;
    let gamma_n = f32_sm(&mut r, 11, 1.0 / (1024.0 * 1024.0 * 1024.0 * 1024.0))?;
    r.skip(2)?;
    let ln3 = r.u(1)?;
    let tau_n_s = f64_sm(&mut r, 22, 1.0 / (1024.0 * 1024.0 * 1024.0))?;
    // DF125 5, DF126 5, DF127 1, DF128 4, DF129 11, DF130 2, DF131 1,
    // DF132 11, DF133 32, DF134 5, DF135 22, DF136 1, reserved 7.
    r.skip(5 + 5 + 1 + 4 + 11 + 2 + 1 + 11 + 32 + 5 + 22 + 1 + 7)?;
    let fields = GlonassIcdFields {
        slot,
        frequency_channel,
        tb_gps_s: 0.0,
        x_km,
        y_km,
        z_km,
        vx_km_s,
        vy_km_s,
        vz_km_s,
        ax_km_s2,
        ay_km_s2,
        az_km_s2,
        tau_n_s,
        gamma_n,
        unhealthy: bn_msb != 0 || ln3 != 0,
    };
    Ok((fields, f64::from(tb_min) * 60.0))
}

/// 1013 (RTCM 10403.3 §3.5.6, Table 3.5-14): DF003 12, DF051 16, DF052
/// 17, DF053 5 (N), DF054 8 (255: not known), then N announcements of 29
/// bits (DF055 12, DF056 1, DF057 16), which must all be there (as
/// `rtcm-rs` requires) and are not used.
fn msg1013(payload: &[u8]) -> Result<Message<'static>, DecodeError> {
    let mut r = BitReader::at(payload, 12);
    r.skip(12)?;
    let mjd = r.u(16)? as u16;
    let utc_sod_s = r.u32(17)?;
    let n = r.u32(5)?;
    let leap = r.u8(8)?;
    r.skip(29 * n)?;
    Ok(Message::SystemParameters {
        mjd,
        utc_sod_s,
        gps_minus_utc_s: (leap != 255).then_some(leap),
    })
}

/// 1005/1006 (RTCM 10403.3 §3.5.3, 152/168 bits): DF003 12, DF021 6,
/// DF022-DF024, DF141, DF025 38, DF142, DF001, DF026 38, DF364 2, DF027
/// 38 (0.0001 m, two's complement), 1006: DF028 16.
fn station(payload: &[u8], height: bool) -> Result<[f64; 3], DecodeError> {
    const RES_M: f64 = 0.0001;
    let mut r = BitReader::at(payload, 12);
    r.skip(12 + 6 + 1 + 1 + 1 + 1)?;
    let x = f64_i(&mut r, 38, RES_M)?;
    r.skip(1 + 1)?;
    let y = f64_i(&mut r, 38, RES_M)?;
    r.skip(2)?;
    let z = f64_i(&mut r, 38, RES_M)?;
    if height {
        r.skip(16)?;
    }
    Ok([x, y, z])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame around `payload` (header and CRC-24Q).
    fn frame(payload: &[u8]) -> std::vec::Vec<u8> {
        let n = payload.len();
        let mut f = std::vec![0xD3, (n >> 8) as u8, n as u8];
        f.extend_from_slice(payload);
        let c = CRC24Q.checksum(&f);
        f.extend_from_slice(&[(c >> 16) as u8, (c >> 8) as u8, c as u8]);
        f
    }

    /// Fields packed most significant bit first.
    struct Bits(std::vec::Vec<u8>, usize);

    impl Bits {
        fn put(&mut self, v: i64, width: u32) -> &mut Self {
            for b in (0..width).rev() {
                if self.1.is_multiple_of(8) {
                    self.0.push(0);
                }
                // Beyond 64 bits, the sign extension (a wide zero field).
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

    /// A GPS MSM4 (1074): satellites 3 and 17, signals 2 (1C) and
    /// `second_signal`; cells (3, 1C), (17, 1C), (17, second).
    fn msm4(second_signal: u32) -> std::vec::Vec<u8> {
        let mut b = Bits(std::vec::Vec::new(), 0);
        b.put(1074, 12).put(7, 12).put(345_600_000, 30).put(1, 1);
        b.put(0, 3 + 7 + 2 + 2 + 1 + 3);
        b.put(1 << 61 | 1 << 47, 64);
        b.put(1 << 30 | 1 << (32 - second_signal), 32);
        b.put(0b1011, 4);
        // DF397, DF398 per satellite.
        b.put(70, 8).put(75, 8).put(512, 10).put(100, 10);
        // DF400 per cell (the second invalid), then DF401, DF402 and
        // DF420 per cell, then DF403 per cell (45 dB-Hz, 0 = not
        // computed, 38 dB-Hz): each field for every cell in turn (RTCM
        // 10403.3 Table 3.5-85).
        b.put(1000, 15).put(-0x4000, 15).put(-5, 15);
        b.put(0, 3 * 22).put(0, 3 * 4).put(0, 3);
        b.put(45, 6).put(0, 6).put(38, 6);
        frame(&b.0)
    }

    #[test]
    fn msm4_signals_ranges_and_invalid_marks() {
        let f = msm4(15);
        let Ok(Ok(Message::Msm(m))) = Frame::new(&f).map(|x| x.message()) else {
            panic!("not an MSM");
        };
        assert_eq!(
            (m.system, m.station_id, m.epoch_ms, m.more, m.satellites()),
            (MsmSystem::Gps, 7, 345_600_000, true, 2)
        );
        let s: std::vec::Vec<MsmSignal> = m.signals().collect();
        let want_3 = (70.0 + 512.0 / 1024.0 + 1000.0 / 16_777_216.0) * LIGHT_MS_M;
        let want_17 = (75.0 + 100.0 / 1024.0 - 5.0 / 16_777_216.0) * LIGHT_MS_M;
        assert_eq!(
            s,
            [
                MsmSignal {
                    sat_id: 3,
                    signal_id: 2,
                    band: 1,
                    attribute: b'C',
                    pseudorange_m: Some(want_3),
                    cnr_dbhz: Some(45.0),
                    phase_range_rate_m_s: None,
                },
                MsmSignal {
                    sat_id: 17,
                    signal_id: 2,
                    band: 1,
                    attribute: b'C',
                    pseudorange_m: None,
                    cnr_dbhz: None,
                    phase_range_rate_m_s: None,
                },
                MsmSignal {
                    sat_id: 17,
                    signal_id: 15,
                    band: 2,
                    attribute: b'S',
                    pseudorange_m: Some(want_17),
                    cnr_dbhz: Some(38.0),
                    phase_range_rate_m_s: None,
                },
            ]
        );
    }

    /// A GPS MSM5 (`high_res` false, 1075) or MSM7 (true, 1077):
    /// satellites 3 and 17, signals 2 (1C) and 10 (2W), all four cells,
    /// with the rough rates `rough` (DF399) and the fine rates `fine`
    /// (DF404, cell order), every other field distinct from them.
    fn msm57(high_res: bool, rough: [i64; 2], fine: [i64; 4]) -> std::vec::Vec<u8> {
        let mut b = Bits(std::vec::Vec::new(), 0);
        b.put(if high_res { 1077 } else { 1075 }, 12);
        b.put(7, 12).put(345_600_000, 30).put(0, 1);
        b.put(0, 3 + 7 + 2 + 2 + 1 + 3);
        b.put(1 << 61 | 1 << 47, 64);
        b.put(1 << 30 | 1 << 22, 32);
        b.put(0b1111, 4);
        // DF397, extended info, DF398, DF399: each for both satellites.
        b.put(70, 8).put(75, 8).put(0b1010, 4).put(0b0101, 4);
        b.put(512, 10)
            .put(100, 10)
            .put(rough[0], 14)
            .put(rough[1], 14);
        let (fr, ph, lock, cnr) = if high_res {
            (20, 24, 10, 10)
        } else {
            (15, 22, 4, 6)
        };
        for v in [1000, -2000, 3000, -4000] {
            b.put(v, fr);
        }
        for v in [-1, 1, -3, 3] {
            b.put(v, ph);
        }
        b.put(0b1011, 4 * lock).put(0b1001, 4);
        for v in [40, 41, 42, 43] {
            b.put(v, cnr);
        }
        for v in fine {
            b.put(v, 15);
        }
        frame(&b.0)
    }

    /// The phase-range rate DF399 + DF404 (RTCM 10403.3 Tables 3.5-82,
    /// 3.5-86, 3.5-90, 3.5-91) of MSM5 and MSM7, each cell with its own
    /// satellite's rough rate and its own fine rate, the invalid marks of
    /// both fields giving `None`; the ranges and C/N0 read as without
    /// rates (the rate fields are the last of their blocks). MSM4 carries
    /// none (`msm4_signals_ranges_and_invalid_marks`).
    ///
    /// Verifies: RX-DOPPLER
    #[test]
    fn msm5_and_msm7_phase_range_rates() {
        for high_res in [false, true] {
            let f = msm57(high_res, [-512, 700], [1234, -0x4000, -5678, 16_383]);
            let Ok(Ok(Message::Msm(m))) = Frame::new(&f).map(|x| x.message()) else {
                panic!("not an MSM");
            };
            let s: std::vec::Vec<MsmSignal> = m.signals().collect();
            let got: std::vec::Vec<_> = s
                .iter()
                .map(|x| (x.sat_id, x.band, x.phase_range_rate_m_s))
                .collect();
            assert_eq!(
                got,
                [
                    (3, 1, Some(-512.0 + 1234.0 * 0.0001)),
                    (3, 2, None),
                    (17, 1, Some(700.0 - 5678.0 * 0.0001)),
                    (17, 2, Some(700.0 + 16_383.0 * 0.0001)),
                ],
                "high_res {high_res}"
            );
            let cn0: std::vec::Vec<_> = s.iter().map(|x| x.cnr_dbhz).collect();
            let unit = if high_res { 1.0 / 16.0 } else { 1.0 };
            assert_eq!(
                cn0,
                [40.0, 41.0, 42.0, 43.0].map(|v| Some(v * unit)),
                "high_res {high_res}"
            );
            let fine_ms = if high_res {
                1000.0 / 536_870_912.0
            } else {
                1000.0 / 16_777_216.0
            };
            let want = (70.0 + 0.5 + fine_ms) * LIGHT_MS_M;
            assert_eq!(s[0].pseudorange_m, Some(want));
            // An invalid rough rate: neither of the satellite's cells has
            // a rate.
            let f = msm57(high_res, [-0x2000, 1], [1, 2, 3, 4]);
            let Ok(Ok(Message::Msm(m))) = Frame::new(&f).map(|x| x.message()) else {
                panic!("not an MSM");
            };
            let rates: std::vec::Vec<_> = m.signals().map(|x| x.phase_range_rate_m_s).collect();
            assert_eq!(
                rates,
                [
                    None,
                    None,
                    Some(1.0 + 3.0 * 0.0001),
                    Some(1.0 + 4.0 * 0.0001)
                ]
            );
        }
    }

    /// Verifies: RX-DECODE
    #[test]
    fn msm_errors_are_typed() {
        // Signal ID 1 is not in Table 3.5-91.
        let f = msm4(1);
        assert_eq!(
            Frame::new(&f).map(|x| x.message().map(|_| ())),
            Ok(Err(DecodeError::SignalId {
                message: 1074,
                signal_id: 1
            }))
        );
        // Cut inside the signal data.
        let f = msm4(15);
        let payload = &f[3..f.len() - 3];
        let cut = frame(&payload[..payload.len() - 4]);
        assert!(matches!(
            Frame::new(&cut).map(|x| x.message().map(|_| ())),
            Ok(Err(DecodeError::Bits(BitsError::PastEnd { .. })))
        ));
        // 9 satellites x 8 signals: 72 cells.
        let mut b = Bits(std::vec::Vec::new(), 0);
        b.put(1077, 12).put(0, 12 + 30 + 1 + 18);
        b.put(0x1FF, 64).put(0xFF, 32).put(0, 64);
        let f = frame(&b.0);
        assert_eq!(
            Frame::new(&f).map(|x| x.message().map(|_| ())),
            Ok(Err(DecodeError::CellCount {
                satellites: 9,
                signals: 8
            }))
        );
    }

    #[test]
    fn crc24q_check_value() {
        assert_eq!(CRC24Q.checksum(b"123456789"), 0xCDE703);
    }

    #[test]
    fn frames_are_checked() {
        let f = frame(&[0x3E, 0xD0, 0, 0]);
        let ok = Frame::new(&f).map(|x| x.number());
        assert_eq!(ok, Ok(Some(1005)));
        let mut bad = f.clone();
        bad[4] ^= 1;
        assert!(matches!(Frame::new(&bad), Err(FrameError::Crc { .. })));
        assert_eq!(
            Frame::new(&f[..f.len() - 1]).map(|x| x.number()),
            Err(FrameError::Incomplete { len: 9, need: 10 })
        );
        assert_eq!(
            Frame::new(&[0xD2, 0, 0, 0, 0, 0]).map(|x| x.number()),
            Err(FrameError::Preamble { byte: 0xD2 })
        );
        // A 1005 of 4 bytes is too short for its fields.
        let m = Frame::new(&f).map(|x| x.message());
        assert!(matches!(m, Ok(Err(DecodeError::Bits(_)))));
    }
}

#[cfg(test)]
#[path = "decode_cov_tests.rs"]
mod decode_cov_tests;

#[cfg(test)]
#[path = "decode_cov2_tests.rs"]
mod decode_cov2_tests;
