//! Fuzz the whole protocol server (decoder + engine + NMEA writer) as the
//! firmware runs it: arbitrary bytes, then a valid status request. Must
//! never panic, and the status must still be answered: the firmware keeps
//! answering on any byte stream.
//!
//! `cd fuzz && cargo +nightly fuzz run server corpus-tmp/server corpus/frame_decoder`
#![no_main]

use libfuzzer_sys::fuzz_target;
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
    for &b in data.iter().chain(&[0u8]).chain(&status) {
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
    assert!(std::str::from_utf8(&nmea.0).is_ok());
});
