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
