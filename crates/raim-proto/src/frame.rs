//! Framing: `COBS(postcard(Envelope { payload, crc32 }))` followed by the
//! 0x00 delimiter.
//!
//! The payload is the postcard encoding of a message ([`crate::message`]);
//! the CRC is CRC-32/ISO-HDLC (the Ethernet/zlib CRC) of the payload bytes.
//! Encoding is postcard's serialiser into a COBS stage written here with
//! checked accesses (`CobsSlice`, the bytes of postcard's `to_slice_cobs`,
//! compared by a property test); the CRC is the `crc` crate's.
//! On the receive side the chunk is gathered and COBS-decoded here, with
//! every access checked ([`FrameReceiver`], `decode_cobs_in_place`), so
//! that the frame decoder links no panic path (docs/EVIDENCE.md "Panic
//! sites"); it answers exactly as postcard's `CobsAccumulator` did (a test
//! compares the two on random streams). What this module adds is the
//! policy: a chunk longer than the receive buffer is reported once and
//! skipped up to the next delimiter, an empty chunk (a lone delimiter) is
//! a sync byte and not a frame, and every other chunk yields either a
//! verified payload or a typed [`FrameError`].

use crc::{Crc, CRC_32_ISO_HDLC};
use serde::{Deserialize, Serialize};

/// CRC-32/ISO-HDLC (poly 0x04C11DB7 reflected, init and xorout 0xFFFFFFFF):
/// check value 0xCBF43926 for "123456789".
pub const CRC32: Crc<u32> = Crc::<u32>::new(&CRC_32_ISO_HDLC);

/// What travels inside the COBS encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Envelope<'a> {
    /// postcard bytes of one message.
    #[serde(borrow)]
    pub payload: &'a [u8],
    /// CRC-32/ISO-HDLC of `payload`.
    pub crc32: u32,
}

/// A chunk between delimiters that is not a valid frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FrameError {
    /// The chunk did not fit the receive buffer of `capacity` bytes; bytes
    /// up to the next delimiter are discarded.
    Overflow {
        /// The receive buffer's size, bytes.
        capacity: u32,
    },
    /// Not valid COBS, or not an envelope; `len` bytes including the delimiter.
    Undecodable {
        /// Length of the chunk, bytes (delimiter included).
        len: u32,
    },
    /// The envelope decoded but its CRC does not match its payload.
    BadCrc {
        /// CRC-32 computed over the payload.
        computed: u32,
        /// CRC-32 the envelope carried.
        received: u32,
    },
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            FrameError::Overflow { capacity } => write!(
                f,
                "frame longer than the {capacity}-byte receive buffer (skipped to the next delimiter)"
            ),
            FrameError::Undecodable { len } => {
                write!(f, "a {len}-byte chunk is not a valid COBS envelope")
            }
            FrameError::BadCrc { computed, received } => write!(
                f,
                "CRC mismatch: computed {computed:#010x}, received {received:#010x}"
            ),
        }
    }
}

impl core::error::Error for FrameError {}

/// Encode one message as a complete frame (delimiter included) into `out`,
/// using `scratch` for the postcard payload. The bytes are postcard's
/// `to_slice_cobs` bytes, and a too-small `out` is the same
/// `SerializeBufferFull`; the COBS stage is `CobsSlice`, whose every
/// access is checked (a property test compares the two).
pub fn encode<'o, T: Serialize + ?Sized>(
    msg: &T,
    scratch: &mut [u8],
    out: &'o mut [u8],
) -> Result<&'o mut [u8], postcard::Error> {
    let payload = postcard::to_slice(msg, scratch)?;
    let env = Envelope {
        crc32: CRC32.checksum(payload),
        payload,
    };
    postcard::serialize_with_flavor(&env, CobsSlice::try_new(out)?)
}

/// A postcard serialisation flavour that COBS-encodes into a slice and
/// appends the 0x00 delimiter: the encoding of postcard's `Cobs<Slice>`
/// flavour (the `cobs` crate's `EncoderState`: a code byte k stands for
/// the k - 1 data bytes after it and a zero, except 0xFF, which stands for
/// 254 data bytes and no zero and is followed by a new code byte at once),
/// written with checked accesses only, so that the answer path links no
/// panic path (docs/EVIDENCE.md "Panic sites"). postcard's flavour writes
/// its code bytes through an unchecked `IndexMut`.
struct CobsSlice<'a> {
    buf: &'a mut [u8],
    /// Bytes written, the pending code byte's placeholder included.
    len: usize,
    /// Index of the pending code byte.
    code_idx: usize,
    /// The pending code byte's value: 1 + the data bytes after it so far.
    code: u8,
}

impl<'a> CobsSlice<'a> {
    /// Reserves the first code byte; `SerializeBufferFull` if `buf` is empty.
    fn try_new(buf: &'a mut [u8]) -> postcard::Result<Self> {
        let mut s = CobsSlice {
            buf,
            len: 0,
            code_idx: 0,
            code: 1,
        };
        s.append(0)?;
        Ok(s)
    }

    fn append(&mut self, byte: u8) -> postcard::Result<()> {
        let slot = self
            .buf
            .get_mut(self.len)
            .ok_or(postcard::Error::SerializeBufferFull)?;
        *slot = byte;
        self.len += 1;
        Ok(())
    }

    /// Writes the pending code byte and reserves the next one.
    fn close_block(&mut self) -> postcard::Result<()> {
        let slot = self
            .buf
            .get_mut(self.code_idx)
            .ok_or(postcard::Error::SerializeBufferFull)?;
        *slot = self.code;
        self.code_idx = self.len;
        self.code = 1;
        self.append(0)
    }
}

impl<'a> postcard::ser_flavors::Flavor for CobsSlice<'a> {
    type Output = &'a mut [u8];

    fn try_push(&mut self, data: u8) -> postcard::Result<()> {
        if data == 0 {
            return self.close_block();
        }
        self.append(data)?;
        // `code` is at most 0xFE here: a block closes when it reaches 0xFF.
        self.code = self.code.wrapping_add(1);
        if self.code == 0xFF {
            self.close_block()?;
        }
        Ok(())
    }

    fn finalize(mut self) -> postcard::Result<Self::Output> {
        let slot = self
            .buf
            .get_mut(self.code_idx)
            .ok_or(postcard::Error::SerializeBufferFull)?;
        *slot = self.code;
        self.append(0)?;
        let CobsSlice { buf, len, .. } = self;
        buf.get_mut(..len)
            .ok_or(postcard::Error::SerializeBufferFull)
    }
}

/// Turns a byte stream into verified payloads. `B` is the receive buffer,
/// the largest frame (delimiter included) that can be received.
pub struct FrameReceiver<const B: usize> {
    /// The current chunk's bytes, `buf[..pending]`.
    buf: [u8; B],
    /// Bytes of the current chunk so far (delimiter excluded).
    pending: usize,
    /// After an overflow: drop bytes up to the next delimiter.
    discarding: bool,
}

impl<const B: usize> Default for FrameReceiver<B> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const B: usize> FrameReceiver<B> {
    /// An empty receiver.
    pub const fn new() -> Self {
        FrameReceiver {
            buf: [0; B],
            pending: 0,
            discarding: false,
        }
    }

    /// Between chunks: no byte of a chunk is held and no overflowed chunk
    /// is being skipped, so the next byte is the first of a frame.
    pub fn is_idle(&self) -> bool {
        self.pending == 0 && !self.discarding
    }

    /// Whether [`push`](Self::push)`(byte)` would return `Some`, without
    /// feeding it: a delimiter that ends a non-empty chunk, or a byte that
    /// overflows the buffer (the accumulator holds exactly `pending` bytes).
    pub fn completes_chunk(&self, byte: u8) -> bool {
        !self.discarding
            && if byte == 0 {
                self.pending > 0
            } else {
                self.pending + 1 > B
            }
    }

    /// Feed one byte. Returns `None` while a frame is incomplete (and for
    /// empty chunks and the rest of an overflowed chunk), `Some(Ok(payload))`
    /// for a frame whose CRC matches, and `Some(Err(_))` once per bad chunk.
    pub fn push(&mut self, byte: u8) -> Option<Result<&[u8], FrameError>> {
        if self.discarding {
            if byte == 0 {
                self.discarding = false;
            }
            return None;
        }
        if byte == 0 && self.pending == 0 {
            return None;
        }
        let len = self.pending + 1;
        if byte != 0 {
            // A chunk longer than the buffer (the delimiter counts):
            // reported once, the rest skipped up to the next delimiter.
            let Some(slot) = self.buf.get_mut(self.pending) else {
                self.pending = 0;
                self.discarding = true;
                return Some(Err(FrameError::Overflow { capacity: B as u32 }));
            };
            *slot = byte;
            self.pending = len;
            return None;
        }
        // The delimiter: it must fit in the buffer too.
        let body = self.pending;
        self.pending = 0;
        if len > B {
            return Some(Err(FrameError::Overflow { capacity: B as u32 }));
        }
        let undecodable = FrameError::Undecodable { len: len as u32 };
        let chunk = self.buf.get_mut(..body)?;
        let Some(n) = decode_cobs_in_place(chunk) else {
            return Some(Err(undecodable));
        };
        let Ok(data) = postcard::from_bytes::<Envelope<'_>>(chunk.get(..n)?) else {
            return Some(Err(undecodable));
        };
        let computed = CRC32.checksum(data.payload);
        if data.payload.is_empty() {
            // No message is empty, and the CRC of nothing is 0: a chunk of
            // noise can decode as (empty, 0).
            Some(Err(undecodable))
        } else if computed == data.crc32 {
            Some(Ok(data.payload))
        } else {
            Some(Err(FrameError::BadCrc {
                computed,
                received: data.crc32,
            }))
        }
    }
}

/// COBS-decodes `chunk` (a frame's bytes without its delimiter) in place and
/// returns the decoded length; `None` when it is not valid COBS. Each code
/// byte k is followed by k - 1 data bytes and stands for a zero after them
/// unless k is 0xFF or the chunk ends there. The rules of the `cobs`
/// crate's `decode_in_place` that postcard applies: an empty chunk is
/// invalid, a zero ends the chunk early, and a code running past the end is
/// invalid unless it is 1. Written with checked accesses only: the decoder
/// of every byte from the host links no panic path.
fn decode_cobs_in_place(chunk: &mut [u8]) -> Option<usize> {
    if chunk.is_empty() {
        return None;
    }
    let end = chunk.iter().position(|&b| b == 0).unwrap_or(chunk.len());
    let (mut src, mut dst) = (0usize, 0usize);
    while src < end {
        let code = usize::from(*chunk.get(src)?);
        if src + code > end && code != 1 {
            return None;
        }
        src += 1;
        for _ in 1..code {
            let b = *chunk.get(src)?;
            *chunk.get_mut(dst)? = b;
            src += 1;
            dst += 1;
        }
        if code != 0xFF && src < end {
            *chunk.get_mut(dst)? = 0;
            dst += 1;
        }
    }
    Some(dst)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::message::{Command, Request, RequestRef};
    use crate::{CAPACITY, MAX_REQUEST_FRAME};
    use raim_core::{RangeObservation, SatId, System};
    use std::vec::Vec;

    type Rx = FrameReceiver<MAX_REQUEST_FRAME>;

    fn frame_of(req: &RequestRef<'_>) -> Vec<u8> {
        let mut scratch = [0u8; 4096];
        let mut out = [0u8; 4096];
        encode(req, &mut scratch, &mut out).unwrap().to_vec()
    }

    fn feed_all<const B: usize>(
        rx: &mut FrameReceiver<B>,
        bytes: &[u8],
    ) -> Vec<Result<Vec<u8>, FrameError>> {
        bytes
            .iter()
            .filter_map(|&b| rx.push(b).map(|r| r.map(|p| p.to_vec())))
            .collect()
    }

    fn sats(n: usize) -> Vec<RangeObservation> {
        (0..n)
            .map(|i| RangeObservation {
                id: SatId::new(System::Galileo, i as u8 + 1),
                pseudorange_m: 2.1e7 + i as f64,
                position_m: [-1.5e7, 2.2e7, 1.3e7 + i as f64],
                sigma_m: Some(1.25),
            })
            .collect()
    }

    #[test]
    fn crc_is_the_standard_crc32() {
        // The catalogue check value of CRC-32/ISO-HDLC.
        assert_eq!(CRC32.checksum(b"123456789"), 0xCBF4_3926);
    }

    /// Verifies: SPEC-11
    #[test]
    fn round_trip_and_one_answer_per_frame() {
        let s = sats(9);
        let a = frame_of(&RequestRef::ranges(7, 12.5, Some([1.0, 2.0, 3.0]), &s));
        let b = frame_of(&RequestRef {
            seq: 8,
            command: crate::message::CommandRef::Status,
        });
        assert_eq!(*a.last().unwrap(), 0);
        assert!(
            !a[..a.len() - 1].contains(&0),
            "COBS leaves no zero inside a frame"
        );
        let mut rx = Rx::new();
        let mut stream = std::vec![0u8, 0];
        stream.extend(&a);
        stream.extend(&b);
        let got = feed_all(&mut rx, &stream);
        assert_eq!(got.len(), 2);
        let req: Request = postcard::from_bytes(got[0].as_ref().unwrap()).unwrap();
        assert_eq!(req.seq, 7);
        match req.command {
            Command::Ranges(e) => {
                assert_eq!(e.time_s, 12.5);
                assert_eq!(e.apriori_m, Some([1.0, 2.0, 3.0]));
                assert_eq!(e.sats.declared, 9);
                assert_eq!(&e.sats.items[..], &s[..]);
            }
            other => panic!("{other:?}"),
        }
        let req: Request = postcard::from_bytes(got[1].as_ref().unwrap()).unwrap();
        assert_eq!((req.seq, req.command), (8, Command::Status));
    }

    #[test]
    fn largest_request_fits() {
        let s = sats(CAPACITY);
        let f = frame_of(&RequestRef::ranges(u32::MAX, 1e9, Some([1.0; 3]), &s));
        assert!(
            f.len() <= crate::max_request_frame(CAPACITY),
            "{} bytes",
            f.len()
        );
        assert_eq!(f.len(), 1425, "documented size in lib.rs and PROTOCOL.md");
        let got = feed_all(&mut Rx::new(), &f);
        assert!(matches!(got.as_slice(), [Ok(_)]));
    }

    #[test]
    fn every_single_byte_flip_is_caught() {
        // CRC-32 detects every error burst of <= 32 bits, so no flip of one
        // byte of the payload can pass; a flip elsewhere breaks COBS or the
        // envelope. Each corrupted frame gives exactly one error, never Ok.
        let s = sats(6);
        let f = frame_of(&RequestRef::ranges(3, 1.0, None, &s));
        for i in 0..f.len() - 1 {
            for flip in [0x01u8, 0x80, 0xFF] {
                let mut g = f.clone();
                g[i] ^= flip;
                let mut rx = Rx::new();
                let mut got = feed_all(&mut rx, &g);
                // A flip that makes a zero splits the frame in two chunks.
                got.extend(feed_all(&mut rx, &[0]));
                assert!(
                    !got.is_empty() && got.iter().all(|r| r.is_err()),
                    "byte {i} ^ {flip:#x}: {got:?}"
                );
            }
        }
    }

    /// Verifies: WIRE-BadCrc
    #[test]
    fn bad_crc_is_reported_with_both_values() {
        let payload = [1u8, 2, 3];
        let env = Envelope {
            payload: &payload,
            crc32: 0xDEAD_BEEF,
        };
        let mut out = [0u8; 64];
        let f = postcard::to_slice_cobs(&env, &mut out).unwrap().to_vec();
        let got = feed_all(&mut Rx::new(), &f);
        assert_eq!(
            got,
            std::vec![Err(FrameError::BadCrc {
                computed: CRC32.checksum(&payload),
                received: 0xDEAD_BEEF
            })]
        );
    }

    #[test]
    fn truncated_and_garbage_chunks_are_errors_and_the_next_frame_is_received() {
        let s = sats(5);
        let f = frame_of(&RequestRef::ranges(1, 0.0, None, &s));
        let mut stream = f[..f.len() / 2].to_vec();
        stream.push(0); // truncated frame
        stream.extend([0x13, 0x37, 0x42, 0x00]); // garbage
        stream.extend(&f);
        let got = feed_all(&mut Rx::new(), &stream);
        assert_eq!(got.len(), 3, "{got:?}");
        assert!(got[0].is_err() && got[1].is_err());
        assert!(got[2].is_ok());
    }

    /// Verifies: WIRE-Overflow
    #[test]
    fn overflow_is_one_error_and_resynchronises_on_the_delimiter() {
        let mut stream = std::vec![0x55u8; 3 * MAX_REQUEST_FRAME + 17];
        stream.push(0);
        let s = sats(4);
        let f = frame_of(&RequestRef::ranges(2, 0.0, None, &s));
        stream.extend(&f);
        let got = feed_all(&mut Rx::new(), &stream);
        assert_eq!(
            got[0],
            Err(FrameError::Overflow {
                capacity: MAX_REQUEST_FRAME as u32
            })
        );
        assert_eq!(got.len(), 2, "{got:?}");
        assert!(got[1].is_ok());
        // A chunk of exactly the buffer size (delimiter included) still fits.
        let mut rx = FrameReceiver::<64>::new();
        let env_payload = [7u8; 50];
        let env = Envelope {
            payload: &env_payload,
            crc32: CRC32.checksum(&env_payload),
        };
        let mut out = [0u8; 64];
        let g = postcard::to_slice_cobs(&env, &mut out).unwrap().to_vec();
        assert!(g.len() <= 64);
        assert!(matches!(feed_all(&mut rx, &g).as_slice(), [Ok(_)]));
    }

    /// The receiver as postcard's `CobsAccumulator` drove it (the
    /// implementation this module had): the oracle for the checked one.
    struct Oracle<const B: usize> {
        acc: postcard::accumulator::CobsAccumulator<B>,
        pending: usize,
        discarding: bool,
    }

    impl<const B: usize> Oracle<B> {
        fn push(&mut self, byte: u8) -> Option<Result<Vec<u8>, FrameError>> {
            use postcard::accumulator::FeedResult;
            if self.discarding {
                if byte == 0 {
                    self.discarding = false;
                }
                return None;
            }
            if byte == 0 && self.pending == 0 {
                return None;
            }
            let len = self.pending + 1;
            self.pending = if byte == 0 { 0 } else { len };
            match self.acc.feed_ref::<Envelope<'_>>(&[byte]) {
                FeedResult::Consumed => None,
                FeedResult::OverFull(_) => {
                    self.pending = 0;
                    self.discarding = byte != 0;
                    Some(Err(FrameError::Overflow { capacity: B as u32 }))
                }
                FeedResult::DeserError(_) => Some(Err(FrameError::Undecodable { len: len as u32 })),
                FeedResult::Success { data, .. } => {
                    let computed = CRC32.checksum(data.payload);
                    if data.payload.is_empty() {
                        Some(Err(FrameError::Undecodable { len: len as u32 }))
                    } else if computed == data.crc32 {
                        Some(Ok(data.payload.to_vec()))
                    } else {
                        Some(Err(FrameError::BadCrc {
                            computed,
                            received: data.crc32,
                        }))
                    }
                }
            }
        }
    }

    /// Byte streams of valid frames (some with a flipped byte), random
    /// bytes, runs of zeros and chunks longer than the buffer: the checked
    /// receiver answers every byte exactly as postcard's accumulator did.
    fn same_as_the_accumulator<const B: usize>(stream: &[u8]) {
        let mut rx = FrameReceiver::<B>::new();
        let mut oracle = Oracle::<B> {
            acc: postcard::accumulator::CobsAccumulator::new(),
            pending: 0,
            discarding: false,
        };
        for (i, &b) in stream.iter().enumerate() {
            let got = rx.push(b).map(|r| r.map(|p| p.to_vec()));
            assert_eq!(got, oracle.push(b), "byte {i} ({b:#04x}) of {stream:02x?}");
        }
    }

    fn stream_of(parts: &[(u8, Vec<u8>)]) -> Vec<u8> {
        let mut out = Vec::new();
        for (kind, bytes) in parts {
            match kind % 5 {
                0 | 4 => {
                    // A valid frame of these payload bytes (non-empty), or
                    // of a run of 254 non-zero bytes and more (COBS code
                    // 0xFF blocks).
                    let payload = if *kind % 5 == 4 {
                        (0..254 + bytes.len())
                            .map(|i| (i % 255 + 1) as u8)
                            .collect()
                    } else if bytes.is_empty() {
                        std::vec![1]
                    } else {
                        bytes.clone()
                    };
                    let env = Envelope {
                        payload: &payload,
                        crc32: CRC32.checksum(&payload),
                    };
                    let mut buf = [0u8; 1024];
                    out.extend(postcard::to_slice_cobs(&env, &mut buf).unwrap().iter());
                }
                1 => {
                    // The same with one byte changed.
                    let payload = if bytes.is_empty() {
                        std::vec![9]
                    } else {
                        bytes.clone()
                    };
                    let env = Envelope {
                        payload: &payload,
                        crc32: CRC32.checksum(&payload),
                    };
                    let mut buf = [0u8; 1024];
                    let mut f = postcard::to_slice_cobs(&env, &mut buf).unwrap().to_vec();
                    let k = bytes.len() % f.len();
                    f[k] ^= 0x5A;
                    out.extend(f);
                }
                2 => out.extend(bytes),
                _ => out.extend(std::iter::repeat_n(0u8, bytes.len() % 3)),
            }
        }
        out
    }

    /// An envelope's bytes with postcard's `to_slice_cobs` and with the
    /// checked [`CobsSlice`] stage, into an output buffer of `room` bytes:
    /// the same frame, or the same error.
    fn same_as_postcards_cobs(payload: &[u8], crc32: u32, room: usize) {
        let env = Envelope { payload, crc32 };
        let mut a = std::vec![0xAAu8; room];
        let mut b = std::vec![0x55u8; room];
        let want = postcard::to_slice_cobs(&env, &mut a).map(|f| f.to_vec());
        let got = CobsSlice::try_new(&mut b)
            .and_then(|flavor| postcard::serialize_with_flavor(&env, flavor))
            .map(|f| f.to_vec());
        assert_eq!(
            got, want,
            "payload {payload:02x?}, crc {crc32:#x}, {room} B"
        );
    }

    /// Payload bytes with long runs free of zeros (COBS's 0xFF blocks, at
    /// and around 254 bytes) as well as dense zeros.
    fn payload_of(parts: &[(u16, bool)]) -> Vec<u8> {
        let mut out = Vec::new();
        for (i, &(n, zero_after)) in parts.iter().enumerate() {
            out.extend((0..n).map(|k| (usize::from(k) + i) as u8 % 255 + 1));
            if zero_after {
                out.push(0);
            }
        }
        out
    }

    #[test]
    fn checked_cobs_stage_matches_postcard_at_block_edges() {
        for n in [0u16, 1, 252, 253, 254, 255, 256, 507, 508, 509, 600] {
            for zero_after in [false, true] {
                let p = payload_of(&[(n, zero_after)]);
                for crc in [0u32, 0xFF, 0x0100_0000, 0xDEAD_BEEF] {
                    for room in [0, 1, 2, p.len(), p.len() + 4, p.len() + 16] {
                        same_as_postcards_cobs(&p, crc, room);
                    }
                }
            }
        }
    }

    /// Verifies: SPEC-11
    #[test]
    fn encoded_request_is_postcards_frame() {
        let s = sats(CAPACITY);
        let req = RequestRef::ranges(u32::MAX, 1e9, Some([1.0; 3]), &s);
        let mut scratch = [0u8; 4096];
        let payload = postcard::to_slice(&req, &mut scratch).unwrap().to_vec();
        let env = Envelope {
            payload: &payload,
            crc32: CRC32.checksum(&payload),
        };
        let mut want = [0u8; 4096];
        let want = postcard::to_slice_cobs(&env, &mut want).unwrap().to_vec();
        assert_eq!(frame_of(&req), want);
        // One byte short of the frame: the same error as postcard's.
        let mut scratch = [0u8; 4096];
        let mut out = std::vec![0u8; want.len() - 1];
        assert_eq!(
            encode(&req, &mut scratch, &mut out),
            Err(postcard::Error::SerializeBufferFull)
        );
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(512))]
        /// Verifies: SPEC-11
        #[test]
        fn checked_cobs_stage_answers_as_postcards(
            parts in proptest::collection::vec((0u16..600, proptest::prelude::any::<bool>()), 0..6),
            crc32 in proptest::prelude::any::<u32>(),
            slack in 0usize..8,
            short in proptest::prelude::any::<bool>(),
        ) {
            let p = payload_of(&parts);
            // Room for the frame with some slack, or short of it by up to 8.
            let full = p.len() + p.len() / 254 + 12;
            let room = if short { full.saturating_sub(12 + slack) } else { full + slack };
            same_as_postcards_cobs(&p, crc32, room);
        }

        /// Verifies: WIRE-Overflow, WIRE-Undecodable, WIRE-BadCrc
        #[test]
        fn checked_receiver_answers_as_postcards_accumulator(
            parts in proptest::collection::vec(
                (0u8..5, proptest::collection::vec(proptest::prelude::any::<u8>(), 0..90)),
                0..12,
            )
        ) {
            let stream = stream_of(&parts);
            same_as_the_accumulator::<16>(&stream);
            same_as_the_accumulator::<64>(&stream);
            same_as_the_accumulator::<{ MAX_REQUEST_FRAME }>(&stream);
        }
    }
}
