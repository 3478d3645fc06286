//! Fuzz ARAIM in the protocol server: a valid ISM frame is put
//! in force first, so that ARAIM epochs in the input reach the engine and
//! its FDE; then arbitrary bytes (ISM frames, ARAIM epochs, anything), then
//! a valid status request. Must never panic, and the status must still be
//! answered: every answer decodes, nothing is lost.
//!
//! `cd fuzz && cargo +nightly fuzz run araim_server corpus-tmp/araim_server corpus/araim_server`
#![no_main]

use libfuzzer_sys::fuzz_target;
use raim_core::{SatId, System};
use raim_proto::araim_msg::{AraimCommandRef, IsmFrameRef, IsmSat, WireAraimConfig};
use raim_proto::frame::{encode, FrameReceiver};
use raim_proto::message::{CommandRef, RequestRef, Response, ResponseBody};
use raim_proto::MAX_RESPONSE_FRAME;
use raim_server::{NoPlatform, Server};

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

/// GPS 1-6 and Galileo 1-6, the ADD's nominal ISM values.
fn ism_frame() -> Vec<u8> {
    let sats: Vec<IsmSat> = (0..12u8)
        .map(|i| IsmSat {
            id: SatId::new(
                if i % 2 == 0 {
                    System::Gps
                } else {
                    System::Galileo
                },
                i / 2 + 1,
            ),
            sigma_ura_m: 0.75,
            sigma_ure_m: 0.5,
            b_nom_m: 0.5,
            p_sat: 1e-5,
        })
        .collect();
    let mut p_const = [None; 5];
    p_const[System::Gps.index()] = Some(1e-4);
    p_const[System::Galileo.index()] = Some(1e-4);
    let req = RequestRef {
        seq: 0,
        command: CommandRef::Araim(AraimCommandRef::Ism(IsmFrameRef {
            config: WireAraimConfig::default(),
            p_const,
            sats: &sats,
        })),
    };
    let mut scratch = vec![0u8; 4096];
    let mut out = vec![0u8; 4096];
    encode(&req, &mut scratch, &mut out).unwrap().to_vec()
}

fuzz_target!(|data: &[u8]| {
    let mut server = Box::new(Server::new());
    let (mut link, mut nmea) = (Sink(Vec::new()), Sink(Vec::new()));
    let mut scratch = [0u8; 256];
    let mut out = [0u8; 256];
    let status = encode(
        &RequestRef {
            seq: 0xABCD,
            command: CommandRef::Status,
        },
        &mut scratch,
        &mut out,
    )
    .unwrap()
    .to_vec();
    for &b in ism_frame().iter().chain(data).chain(&[0u8]).chain(&status) {
        let _ = server.on_byte(b, &mut link, &mut nmea, &mut NoPlatform);
    }
    let mut rx = Box::new(FrameReceiver::<MAX_RESPONSE_FRAME>::new());
    let mut last = None;
    for &b in &link.0 {
        if let Some(p) = rx.push(b) {
            last = Some(
                postcard::from_bytes::<Response>(p.expect("the firmware's own frames are valid"))
                    .expect("decodable"),
            );
        }
    }
    let last = last.expect("an answer");
    assert_eq!(last.seq, Some(0xABCD));
    assert!(matches!(last.body, ResponseBody::Status(_)));
});
