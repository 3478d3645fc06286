//! Server paths the other tests leave out (issue 37, structural coverage,
//! second pass): an ARAIM epoch's host sigma that is not a positive
//! finite number passes the admission's bound check and is the engine's
//! own typed refusal, with its index and value.
extern crate std;

use std::boxed::Box;
use std::vec::Vec;

use raim_core::measurement::MAX_SYSTEMS;
use raim_core::{Config, LinearObservation, SatId, System};
use raim_proto::araim_msg::{AraimCommandRef, IsmFrameRef, IsmSat, WireAraimConfig};
use raim_proto::frame::{encode, FrameReceiver};
use raim_proto::message::{CommandRef, RequestRef, Response, ResponseBody};

use crate::{NoPlatform, Server, WireError, MAX_RESPONSE_FRAME};

#[derive(Default)]
struct Sink(Vec<u8>);
impl embedded_io::ErrorType for Sink {
    type Error = core::convert::Infallible;
}
impl embedded_io::Write for Sink {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.0.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// The one answer of `server` to `command`.
fn ask(server: &mut Server, seq: u32, command: CommandRef<'_>) -> Response {
    let mut scratch = std::vec![0u8; 8192];
    let mut out = std::vec![0u8; 8192];
    let bytes = encode(&RequestRef { seq, command }, &mut scratch, &mut out)
        .unwrap()
        .to_vec();
    let (mut link, mut nmea) = (Sink::default(), Sink::default());
    for &b in &bytes {
        server
            .on_byte(b, &mut link, &mut nmea, &mut NoPlatform)
            .unwrap();
    }
    let mut rx = FrameReceiver::<MAX_RESPONSE_FRAME>::new();
    let answers: Vec<Response> = link
        .0
        .iter()
        .filter_map(|&b| {
            rx.push(b)
                .map(|p| postcard::from_bytes(p.unwrap()).unwrap())
        })
        .collect();
    assert_eq!(answers.len(), 1, "{answers:?}");
    answers.into_iter().next().unwrap()
}

/// Eight GPS satellites over the sky, unit host sigmas, small residuals;
/// their ISM entries (sigma_URA 0.75 m, sigma_URE 0.5 m, b_nom 0.5 m,
/// P_sat 1e-5).
fn sky() -> (Vec<IsmSat>, Vec<LinearObservation>) {
    let mut ism = Vec::new();
    let mut obs = Vec::new();
    for i in 0..8u8 {
        let id = SatId::new(System::Gps, i + 1);
        let az = f64::from(i) * 45.0;
        let el = 15.0 + f64::from(i % 4) * 20.0;
        let mut o = LinearObservation::from_az_el(
            id,
            az.to_radians(),
            el.to_radians(),
            0.1 * f64::from(i) - 0.3,
        );
        o.sigma_m = Some(1.0);
        obs.push(o);
        ism.push(IsmSat {
            id,
            sigma_ura_m: 0.75,
            sigma_ure_m: 0.5,
            b_nom_m: 0.5,
            p_sat: 1e-5,
        });
    }
    (ism, obs)
}

/// A host sigma of NaN, +infinity, 0 or below on an ARAIM epoch is not
/// for the bound check (`SigmaOutOfRange` is for positive finite sigmas
/// outside `config_bounds::SIGMA_M`): the ARAIM monitor refuses it
/// `NonPositiveSigma` with the satellite's index and the value received
/// (raim-core araim/monitor.rs), and a unit sigma is answered.
///
/// Verifies: WIRE-NonPositiveSigma
#[test]
fn an_araim_sigma_that_is_no_positive_number_is_the_engines_refusal() {
    let mut s = Box::new(Server::new());
    s.take_runtime_config(Config::default()).unwrap();
    let (ism, obs) = sky();
    let mut p_const = [None; MAX_SYSTEMS];
    p_const[System::Gps.index()] = Some(1e-4);
    let r = ask(
        &mut s,
        0,
        CommandRef::Araim(AraimCommandRef::Ism(IsmFrameRef {
            config: WireAraimConfig::default(),
            p_const,
            sats: &ism,
        })),
    );
    assert!(!matches!(r.body, ResponseBody::Error(_)), "{r:?}");
    let epoch = |s: &mut Server, seq: u32, sats: &[LinearObservation]| {
        ask(
            s,
            seq,
            CommandRef::Araim(AraimCommandRef::Epoch { time_s: 1.0, sats }),
        )
    };
    let r = epoch(&mut s, 1, &obs);
    assert!(
        matches!(r.body, ResponseBody::Araim(_)),
        "a clean epoch is answered: {r:?}"
    );
    for (k, bad) in [f64::NAN, f64::INFINITY, -1.0, 0.0].into_iter().enumerate() {
        let mut sats = obs.clone();
        sats[3].sigma_m = Some(bad);
        let r = epoch(&mut s, 2 + k as u32, &sats);
        match r.body {
            ResponseBody::Error(WireError::NonPositiveSigma { index: 3, sigma_m })
                if sigma_m.to_bits() == bad.to_bits() => {}
            other => panic!("sigma {bad}: {other:?}"),
        }
    }
}

/// GMSD7's frames (`/work/shared/data/GMSD7_20121014.rtcm3`) by the RTCM
/// 10403.3 framing, up to its 25th epoch (the frames before the 26th
/// GPS MSM7, 1077).
fn gmsd7_25_epochs() -> Vec<Vec<u8>> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/GMSD7_20121014.rtcm3"
    );
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let (mut out, mut i, mut epochs) = (Vec::new(), 0, 0);
    while i + 6 <= bytes.len() {
        if bytes[i] != 0xD3 {
            i += 1;
            continue;
        }
        let len = (usize::from(bytes[i + 1] & 0x03) << 8) | usize::from(bytes[i + 2]);
        let f = bytes[i..i + 6 + len].to_vec();
        if (u16::from(f[3]) << 4 | u16::from(f[4]) >> 4) == 1077 {
            if epochs == 25 {
                break;
            }
            epochs += 1;
        }
        out.push(f);
        i += 6 + len;
    }
    out
}

/// An RTCM 3 frame around `payload`: header and CRC-24Q (polynomial
/// 0x864CFB, initial value 0; written out here, not the receiver's).
fn rtcm_frame(payload: &[u8]) -> Vec<u8> {
    let mut f = std::vec![0xD3, (payload.len() >> 8) as u8 & 0x03, payload.len() as u8];
    f.extend_from_slice(payload);
    let mut crc = 0u32;
    for &b in &f {
        crc ^= u32::from(b) << 16;
        for _ in 0..8 {
            crc <<= 1;
            if crc & 0x0100_0000 != 0 {
                crc ^= 0x0186_4CFB;
            }
        }
    }
    f.extend_from_slice(&[(crc >> 16) as u8, (crc >> 8) as u8, crc as u8]);
    f
}

/// GMSD7 with its first GPS ephemeris (1019) sent in the unit's pivot
/// week (DF076, payload bits 18..28, the week modulo 1024; the earliest
/// week the unit places a stream in, a year before its build) is dated
/// there, with no RTCM 1013: `Status` reports the leap-second table's
/// count, 18 s (every date since 2017-01-01, IERS Bulletin C 52), while
/// the table is in force at that date (it expires 2027-06-28), and
/// `TableExpired` past it.
///
/// Verifies: RX-LEAP
#[test]
fn a_stream_dated_within_the_table_reports_its_count() {
    use raim_proto::message::StreamLeapSeconds;
    let mut frames = gmsd7_25_epochs();
    let at = frames
        .iter()
        .position(|f| (u16::from(f[3]) << 4 | u16::from(f[4]) >> 4) == 1019)
        .unwrap();
    let mut p = frames[at][3..frames[at].len() - 3].to_vec();
    let week = (crate::stream::PIVOT_WEEK % 1024) as u16;
    for (i, k) in (18..28).enumerate() {
        let bit = ((week >> (9 - i)) & 1) as u8;
        p[k / 8] = (p[k / 8] & !(0x80 >> (k % 8))) | (bit << (7 - k % 8));
    }
    frames[at] = rtcm_frame(&p);

    let mut s = Box::new(Server::new());
    s.take_runtime_config(Config::default()).unwrap();
    let (mut link, mut nmea) = (Sink::default(), Sink::default());
    for &b in frames.concat().iter() {
        s.on_byte(b, &mut link, &mut nmea, &mut NoPlatform).unwrap();
    }
    s.on_line_idle(&mut link, &mut nmea, &mut NoPlatform)
        .unwrap();
    let r = ask(&mut s, 0, CommandRef::Status);
    let ResponseBody::Status(st) = r.body else {
        panic!("{r:?}")
    };
    // The first epoch's GPS time: GMSD7 starts 16 s before the end of
    // its week (604,784 s), its epochs one second apart.
    let t_gps_s = crate::stream::PIVOT_WEEK as f64 * 604_800.0 + 604_784.0;
    let expires_gps_s = raim_nav::time::LEAP_TABLE_EXPIRES_GPS_S;
    let want = if t_gps_s + 60.0 < expires_gps_s {
        StreamLeapSeconds::Table {
            gps_minus_utc_s: 18,
        }
    } else {
        StreamLeapSeconds::TableExpired
    };
    assert_eq!(st.stream_leap_seconds, want);
}
