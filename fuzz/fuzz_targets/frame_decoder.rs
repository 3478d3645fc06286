//! Fuzz the firmware's frame decoder: arbitrary bytes through
//! `FrameReceiver` (COBS, envelope, CRC) and the request decoder, as the
//! firmware's server does. Must never panic; every chunk yields at most one
//! event; a payload that decodes re-encodes to a frame that decodes to the
//! same request (compared as bytes, so NaN fields compare too).
//!
//! `cd fuzz && cargo +nightly fuzz run frame_decoder corpus/frame_decoder -- -runs=10000000`
#![no_main]

use libfuzzer_sys::fuzz_target;
use raim_proto::frame::{encode, FrameReceiver};
use raim_proto::message::Request;
use raim_proto::MAX_REQUEST_FRAME;

fuzz_target!(|data: &[u8]| {
    let mut rx = FrameReceiver::<MAX_REQUEST_FRAME>::new();
    let mut events = 0usize;
    for &b in data {
        let Some(ev) = rx.push(b) else { continue };
        events += 1;
        let Ok(payload) = ev else { continue };
        let Ok(req) = postcard::from_bytes::<Request>(payload) else {
            continue;
        };
        let mut a = [0u8; 4 * MAX_REQUEST_FRAME];
        let Ok(bytes) = postcard::to_slice(&req, &mut a) else {
            panic!("a decoded request does not re-encode")
        };
        let bytes = bytes.to_vec();
        let mut scratch = [0u8; 4 * MAX_REQUEST_FRAME];
        let mut out = [0u8; 4 * MAX_REQUEST_FRAME];
        let frame = encode(&req, &mut scratch, &mut out)
            .expect("encode")
            .to_vec();
        let mut rx2 = FrameReceiver::<{ 4 * MAX_REQUEST_FRAME }>::new();
        let mut again: Vec<Vec<u8>> = Vec::new();
        for &b in &frame {
            if let Some(r) = rx2.push(b) {
                again.push(r.expect("own frame").to_vec());
            }
        }
        assert_eq!(again, vec![bytes]);
    }
    // One event per delimiter at most (plus one per overflow, whose chunk
    // then yields nothing more).
    let delimiters = data.iter().filter(|&&b| b == 0).count();
    assert!(
        events <= delimiters + data.len() / MAX_REQUEST_FRAME + 1,
        "{events} events, {delimiters} delimiters"
    );
});
