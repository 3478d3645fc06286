//! raim-recv: receiver streams as replay sources, on the host.
//!
//! A receiver's binary stream (RTCM 3 from a reference station or a
//! receiver, u-blox UBX) is read from a file, a TCP connection or a serial
//! port ([`source`]), framed and decoded ([`rtcm`], [`ubx`]) into the same
//! types the RINEX reader gives (`raim_gnss::ObsEpoch`, `Kepler`
//! ephemerides, Klobuchar coefficients), so that the replay runs them
//! through the same corrections and monitors. Every frame that fails its
//! checksum, every byte between frames and every message type not used is
//! counted ([`Counts`]); a cut last message ends the stream cleanly.
//! docs/RECEIVERS.md describes the formats, the sources and the choices.

pub mod lnav;
pub mod msm_fault;
pub mod rtcm;
pub mod source;
pub mod ubx;

use std::collections::BTreeMap;
use std::io::Read;
use std::path::PathBuf;

use raim_core::SatId;
use raim_gnss::ephemeris::Kepler;
use raim_gnss::glonass::GlonassEphemeris;
use raim_gnss::iono::Klobuchar;
use raim_gnss::{NavData, ObsData, ObsEpoch};
use serde::Serialize;

/// The stream formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Format {
    /// RTCM 3.x.
    Rtcm3,
    /// u-blox UBX.
    Ubx,
}

impl Format {
    pub fn name(self) -> &'static str {
        match self {
            Format::Rtcm3 => "RTCM 3",
            Format::Ubx => "UBX",
        }
    }

    /// The messages that carry ephemerides, for "no ephemeris" messages.
    pub fn ephemeris_messages(self) -> &'static str {
        match self {
            Format::Rtcm3 => "RTCM 1019/1020/1042/1044/1045/1046",
            Format::Ubx => "UBX RXM-SFRB or RXM-SFRBX GPS subframes 1-3",
        }
    }

    /// A fresh decoder for this format.
    pub fn decoder(self) -> Box<dyn Decoder + Send> {
        match self {
            Format::Rtcm3 => Box::new(rtcm::Rtcm3::default()),
            Format::Ubx => Box::new(ubx::Ubx::default()),
        }
    }
}

/// One decoded item, in stream order.
#[derive(Debug, Clone, PartialEq)]
pub enum Item {
    /// A complete observation epoch (absolute GPS time).
    Epoch(ObsEpoch),
    /// A broadcast ephemeris (toc in absolute GPS time).
    Ephemeris(Kepler),
    /// GPS Klobuchar coefficients (LNAV subframe 4 page 18).
    Klobuchar(Klobuchar),
    /// The station's antenna reference point, ECEF, m (RTCM 1005/1006).
    Station([f64; 3]),
    /// A GLONASS ephemeris (RTCM 1020), t_b placed in GPS time.
    Glonass(GlonassEphemeris),
    /// The GLONASS ephemerides given so far were placed with another GPS -
    /// UTC count than the stream's 1013 now gives: drop them (the stream
    /// resends its 1020s, placed with the new count).
    GlonassWithdrawn,
}

/// What a decoder read and what it skipped.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Counts {
    /// Bytes read.
    pub bytes: u64,
    /// Frames whose checksum (CRC-24Q, Fletcher) holds.
    pub frames: u64,
    /// Frame-like headers whose checksum fails (skipped).
    pub bad_checksum: u64,
    /// Bytes outside any good frame (skipped).
    pub garbage_bytes: u64,
    /// Bytes of a last frame cut by the end of the stream.
    pub truncated_tail_bytes: u64,
    /// Good frames whose contents could not be decoded.
    pub undecodable: u64,
    /// Frames read but not used, by message type.
    pub ignored: BTreeMap<String, u64>,
    /// Observation epochs.
    pub epochs: u64,
    /// Ephemerides decoded.
    pub ephemerides: u64,
}

impl std::fmt::Display for Counts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} bytes, {} frames, {} epochs, {} ephemerides; skipped: {} bad checksums, {} bytes between frames, {} undecodable, {} bytes of a cut last frame",
            self.bytes,
            self.frames,
            self.epochs,
            self.ephemerides,
            self.bad_checksum,
            self.garbage_bytes,
            self.undecodable,
            self.truncated_tail_bytes
        )?;
        if !self.ignored.is_empty() {
            let list: Vec<String> = self
                .ignored
                .iter()
                .map(|(k, v)| format!("{k} x{v}"))
                .collect();
            write!(f, "; not used: {}", list.join(", "))?;
        }
        Ok(())
    }
}

/// A stream decoder: bytes in, items out.
pub trait Decoder {
    /// Decode what `bytes` completes; a partial frame waits for more.
    fn push(&mut self, bytes: &[u8], out: &mut Vec<Item>);
    /// The end of the stream: a partial last frame is counted and dropped.
    fn finish(&mut self, out: &mut Vec<Item>);
    fn counts(&self) -> &Counts;
    /// Epochs held until the stream's week is known (RTCM before its
    /// first ephemeris).
    fn waiting_epochs(&self) -> usize;
}

/// Add an ephemeris to `nav` unless the same one (toe, toc, issue of data)
/// is there already; each satellite's list stays sorted by toc. `nav`'s
/// Keplerian orbits are then a stream's, evaluated on their arcs
/// (`NavData::orbit_arcs`), as the unit's receiver evaluates them.
pub fn add_ephemeris(nav: &mut NavData, k: Kepler) {
    // A stream's Keplerian orbits on their arcs, as the unit's receiver
    // takes them (`raim_nav::arc`).
    nav.orbit_arcs = true;
    let list = nav
        .ephemerides
        .entry(SatId::new(k.system, k.prn))
        .or_default();
    let same =
        |o: &Kepler| o.toe_sow_s == k.toe_sow_s && o.toc_gps_s == k.toc_gps_s && o.iod == k.iod;
    if !list.iter().any(same) {
        list.push(k);
        list.sort_by(|a, b| a.toc_gps_s.total_cmp(&b.toc_gps_s));
    }
}

/// Add a GLONASS ephemeris to `nav` unless the same one is there already
/// (1020 repeats a message every cycle); each slot's list stays sorted by
/// t_b.
pub fn add_glonass(nav: &mut NavData, g: GlonassEphemeris) {
    let list = nav
        .glonass
        .entry(SatId::new(raim_core::System::Glonass, g.slot))
        .or_default();
    if !list.contains(&g) {
        list.push(g);
        list.sort_by(|a, b| a.tb_gps_s.total_cmp(&b.tb_gps_s));
    }
}

/// A whole recording, decoded.
#[derive(Debug, Clone)]
pub struct Recording {
    pub format: Format,
    /// The epochs; `approx_position_m` is the station position (RTCM
    /// 1005/1006) when the stream has one.
    pub obs: ObsData,
    /// Every ephemeris in the stream (GLONASS in `nav.glonass`), and
    /// Klobuchar when broadcast.
    pub nav: NavData,
    pub counts: Counts,
}

/// Apply one item to the growing recording.
pub fn apply(item: Item, obs: &mut ObsData, nav: &mut NavData) {
    match item {
        Item::Epoch(e) => obs.epochs.push(e),
        Item::Ephemeris(k) => add_ephemeris(nav, k),
        Item::Klobuchar(kb) => nav.klobuchar = Some(kb),
        Item::Station(p) => obs.approx_position_m = Some(p),
        Item::Glonass(g) => add_glonass(nav, g),
        Item::GlonassWithdrawn => nav.glonass.clear(),
    }
}

/// Read a whole stream to its end and decode it.
pub fn read_all(
    format: Format,
    mut reader: impl Read,
    name: PathBuf,
) -> std::io::Result<Recording> {
    let mut dec = format.decoder();
    let mut obs = ObsData {
        path: name,
        approx_position_m: None,
        epochs: Vec::new(),
    };
    let mut nav = NavData::default();
    let mut items = Vec::new();
    let mut chunk = vec![0u8; 1 << 16];
    loop {
        let n = match reader.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        dec.push(chunk.get(..n).unwrap_or(&[]), &mut items);
        for it in items.drain(..) {
            apply(it, &mut obs, &mut nav);
        }
    }
    dec.finish(&mut items);
    for it in items.drain(..) {
        apply(it, &mut obs, &mut nav);
    }
    obs.epochs
        .sort_by(|a, b| a.time_gps_s.total_cmp(&b.time_gps_s));
    Ok(Recording {
        format,
        obs,
        nav,
        counts: dec.counts().clone(),
    })
}
