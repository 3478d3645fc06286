//! One link, two framings: the project's COBS frames ([`crate::frame`]) and
//! RTCM 3 frames from a GNSS receiver wired to the same UART.
//!
//! An RTCM 3 frame (RTCM 10403, "Transport layer") is the preamble 0xD3, six
//! reserved bits that must be 0, a 10-bit payload length `N` (0..=1023), `N`
//! payload bytes and a 24-bit CRC-24Q of everything before it: 6..=1029
//! bytes. RTCM payloads contain zeros, so an RTCM frame cannot pass through
//! the COBS receiver; [`LinkReceiver`] takes it out of the byte stream first.
//!
//! Where an RTCM frame may start: only where a COBS frame could start, i.e.
//! when the COBS receiver is between chunks ([`FrameReceiver::is_idle`]).
//! A 0xD3 there opens an RTCM *candidate*; the bytes that follow go to the
//! candidate buffer, zeros included, until one of two things decides it:
//!
//! - the second byte has a reserved bit set: not RTCM;
//! - `N + 6` bytes are in: RTCM if the CRC-24Q matches, not RTCM otherwise
//!   (counted in [`LinkCounts::rtcm_bad_crc`]).
//!
//! A candidate that is not RTCM is *replayed*, byte by byte and in order,
//! into the COBS receiver, because a COBS frame may itself start with 0xD3
//! (the code byte of a frame whose first zero is 210 bytes in). Replayed
//! bytes are never looked at as RTCM again, so every byte is examined as an
//! RTCM candidate at most once and the work per byte is bounded.
//!
//! Which candidates are ambiguous: a valid project frame that starts with
//! 0xD3 has its first 210 envelope bytes non-zero (COBS code 211). A
//! payload under 128 bytes makes an envelope of at most 133 bytes (length
//! varint 1, CRC varint at most 5), so the payload has 128 bytes or more
//! and the frame's second byte, the first byte of the payload's length
//! varint, has the continuation bit 0x80 set. Such a frame is rejected by
//! the reserved-bit test at its second byte: a replay of two bytes, and the
//! frame is received exactly as by [`FrameReceiver`] alone.
//!
//! A candidate that passes the header test and fails the CRC is therefore
//! never the start of a valid project frame: it is a corrupted RTCM frame
//! or noise (a stray 0xD3 followed by a byte in 0..=3). After its replay
//! the COBS receiver may be inside a chunk, the *tail* (the bytes after the
//! candidate's last zero):
//!
//! - If the replay yielded a CRC-verified COBS frame, the window held COBS
//!   traffic and the tail is kept open: most likely a frame that continues
//!   past the window.
//! - Otherwise the tail is ended there as if a delimiter had followed (one
//!   framing-error event, or the frame if the tail is a whole one), so that
//!   the chunk after a corrupted RTCM frame, a COBS frame or the next RTCM
//!   frame, starts clean. The tail is kept in the buffer with the bytes that
//!   follow it; at the next delimiter, if the chunk that ends there is not
//!   a verified frame, the joined chunk (tail + those bytes) is tried too
//!   and reported if it is one. A frame cut by the end of a noise window is
//!   so received late but not lost, unless the byte after the window is a
//!   0xD3 (a new candidate takes the buffer) or the joined chunk exceeds
//!   [`RTCM_MAX_FRAME`] bytes. Only verified frames come out of the joined
//!   chunk: its errors were already reported as the two chunks'.
//!
//! A candidate holds its bytes back until it is decided, up to
//! [`RTCM_MAX_FRAME`] bytes: a request behind a stray 0xD3 waits for the
//! bytes that follow it, or for [`LinkReceiver::line_idle`], which a caller
//! with an idle-line interrupt or a timeout calls on a pause (an RTCM frame
//! arrives in one burst).
//!
//! Resynchronisation: a byte that is neither COBS nor RTCM (line noise)
//! just before an RTCM frame puts the frame's preamble inside a COBS chunk,
//! and the following back-to-back RTCM frames are read as COBS chunks
//! until one ends with a zero byte at a frame boundary (test
//! `a_stray_byte_costs_rtcm_frames_until_a_boundary`).
//!
//! # Resynchronisation on a host frame
//!
//! A candidate whose header declares a long frame holds the bytes that
//! follow it, so a stray 0xD3 with a plausible header (`D3 03 FF`: 1029
//! bytes declared) followed by a few bytes of noise would swallow the host
//! frames that come next, until the candidate fills or the line pauses,
//! and then answer them all as one unreadable chunk (issue 35). So at
//! every zero byte inside a candidate the receiver asks whether a host
//! frame has just ended: whether some suffix of the candidate, ending at
//! that zero, is a CRC-verified COBS frame. Its start lies after the
//! candidate's previous zero (a COBS frame has no zero before its
//! delimiter); a start is tried only if its chain of COBS code bytes lands
//! exactly on the zero, at most
//! [`MAX_RESYNC_TRIES`] starts per zero, longest suffix first. If one
//! verifies, the candidate is not RTCM: its bytes before the frame are
//! reported as [`LinkEvent::TruncatedRtcm`] (how many, and the length the
//! header declared), then the frame itself, and the receiver is between
//! frames again.
//!
//! Zero bytes are ordinary inside an RTCM payload, so a zero alone
//! releases nothing: the candidate keeps every byte until a verified frame
//! ends in it, it completes (CRC-24Q), or the line pauses. A genuine RTCM
//! frame is given up only if a suffix of it passes the CRC-32 of a host
//! envelope (and its COBS and envelope structure) by chance, about 2^-32
//! per try; that costs one RTCM frame (a stream epoch, whose absence the
//! time-to-alert catches) and yields a verified frame that must still
//! decode as a request. A frame behind more than [`MAX_RESYNC_TRIES`]
//! plausible starts of noise is received at the pause as before.
//!
//! # Events
//!
//! One byte can complete several COBS frames (a replay), so events come out
//! of two calls: [`LinkReceiver::push`] feeds one byte and returns the first
//! event, [`LinkReceiver::poll`] returns the following ones, and returns
//! `None` once the byte is fully processed. After every `push`, call `poll`
//! until it returns `None`:
//!
//! ```
//! use raim_proto::link::{LinkEvent, LinkReceiver};
//! let mut rx = LinkReceiver::<2048>::new();
//! # let bytes = [0u8; 4];
//! for &b in &bytes {
//!     let mut event = rx.push(b);
//!     while let Some(ev) = event {
//!         match ev {
//!             LinkEvent::Frame(_payload_or_error) => {}
//!             LinkEvent::Rtcm(_frame) => {}
//!             LinkEvent::TruncatedRtcm { .. } => {}
//!         }
//!         event = rx.poll();
//!     }
//! }
//! ```
//!
//! A `push` while events are still pending first completes the pending
//! replay, dropping its events; they are counted in
//! [`LinkCounts::unpolled_events`] (0 for a caller that polls as above).
//!
//! Size: `FrameReceiver<B>` plus [`RTCM_MAX_FRAME`] bytes and a few words.

use crate::frame::{FrameError, FrameReceiver};
use crc::{Crc, NoTable, CRC_24_LTE_A};

/// CRC-24Q, the RTCM 3 frame check (poly 0x864CFB, init 0, not reflected,
/// no xorout: the catalogue's CRC-24/LTE-A), check value 0xCDE703 for
/// "123456789". Bitwise (`NoTable`): no 1 KiB table in flash for a check
/// run once per RTCM frame.
pub const CRC24Q: Crc<u32, NoTable> = Crc::<u32, NoTable>::new(&CRC_24_LTE_A);

/// The RTCM 3 preamble.
pub const RTCM_PREAMBLE: u8 = 0xD3;

/// Largest RTCM 3 payload, bytes (10-bit length field).
pub const RTCM_MAX_PAYLOAD: usize = 1023;

/// Largest RTCM 3 frame: 3 header bytes, the payload, 3 CRC bytes.
pub const RTCM_MAX_FRAME: usize = RTCM_MAX_PAYLOAD + 6;

/// What one byte (or a replay) completed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkEvent<'a> {
    /// A COBS chunk: exactly what [`FrameReceiver::push`] yields.
    Frame(Result<&'a [u8], FrameError>),
    /// A whole RTCM 3 frame, preamble to CRC inclusive, CRC verified.
    Rtcm(&'a [u8]),
    /// The first `received` bytes of an RTCM candidate whose header
    /// declared a frame of `declared` bytes (N + 6), dropped because a
    /// CRC-verified host frame ended inside the candidate
    /// ([resynchronisation](self#resynchronisation-on-a-host-frame));
    /// that frame is the next event.
    TruncatedRtcm {
        /// Bytes dropped, the 0xD3 included.
        received: u32,
        /// The frame length the candidate's header declared, bytes.
        declared: u32,
    },
}

/// What the link receiver took out of the stream besides COBS chunks.
/// Counters wrap.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkCounts {
    /// RTCM frames reported ([`LinkEvent::Rtcm`]).
    pub rtcm_frames: u32,
    /// Candidates with a plausible header (reserved bits 0) whose CRC-24Q
    /// failed once all `N + 6` bytes were in; their bytes were replayed.
    pub rtcm_bad_crc: u32,
    /// Events dropped because `push` was called before `poll` had returned
    /// `None` (a caller that does not follow the module's event contract).
    pub unpolled_events: u32,
}

/// Where the receiver is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// Bytes go to the COBS receiver.
    Cobs,
    /// Bytes go to the RTCM candidate buffer (`len` bytes so far).
    Candidate,
    /// `buf[cursor..len]` still has to go to the COBS receiver.
    Replay {
        /// After the bytes, end an open COBS chunk with a delimiter.
        close_tail: bool,
        /// The replay has yielded a CRC-verified COBS frame.
        saw_frame: bool,
    },
    /// A delimiter ended the chunk that followed a closed tail; unless
    /// that chunk was a verified frame, the joined chunk `buf[..alt_len]`
    /// is tried next.
    Rejoin,
}

/// At most this many suffixes of a candidate are tried as a host frame at
/// each zero byte inside it (the cost of one try: a pass of the suffix
/// through the COBS receiver). The tries of all the zeros of a candidate
/// pass at most `MAX_RESYNC_TRIES x RTCM_MAX_FRAME` bytes through it, and
/// finding the plausible starts takes at most `RTCM_MAX_FRAME^2 / 2`
/// steps of an add and a compare.
pub const MAX_RESYNC_TRIES: usize = 16;

/// Splits one byte stream into COBS frames and RTCM 3 frames (module
/// documentation). `B` is the COBS receive buffer, as in [`FrameReceiver`].
pub struct LinkReceiver<const B: usize> {
    frames: FrameReceiver<B>,
    buf: [u8; RTCM_MAX_FRAME],
    /// Bytes of the candidate in `buf`.
    len: usize,
    /// Next byte of `buf` to replay.
    cursor: usize,
    mode: Mode,
    /// After a closed tail: `buf[..alt_len]` is the tail and the bytes
    /// that followed it, the chunk the COBS receiver would have had without
    /// the closing; 0 when there is none.
    alt_len: usize,
    /// The chunk that ended the alternative was a verified frame.
    alt_was_frame: bool,
    counts: LinkCounts,
}

impl<const B: usize> Default for LinkReceiver<B> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const B: usize> LinkReceiver<B> {
    /// An empty receiver, between frames.
    pub const fn new() -> Self {
        LinkReceiver {
            frames: FrameReceiver::new(),
            buf: [0; RTCM_MAX_FRAME],
            len: 0,
            cursor: 0,
            mode: Mode::Cobs,
            alt_len: 0,
            alt_was_frame: false,
            counts: LinkCounts {
                rtcm_frames: 0,
                rtcm_bad_crc: 0,
                unpolled_events: 0,
            },
        }
    }

    /// The counters so far.
    pub fn counts(&self) -> LinkCounts {
        self.counts
    }

    /// Feed one byte; returns the first event it completes. Call
    /// [`poll`](Self::poll) until `None` before the next `push`.
    pub fn push(&mut self, byte: u8) -> Option<LinkEvent<'_>> {
        if matches!(self.mode, Mode::Replay { .. } | Mode::Rejoin) {
            while self.poll().is_some() {
                self.counts.unpolled_events = self.counts.unpolled_events.wrapping_add(1);
            }
        }
        if self.mode == Mode::Cobs {
            if byte == RTCM_PREAMBLE && self.frames.is_idle() {
                // The candidate needs the buffer: a pending alternative is
                // given up (a joined chunk would have had a 0xD3 here).
                self.alt_len = 0;
                self.buf[0] = byte;
                self.len = 1;
                self.mode = Mode::Candidate;
                return None;
            }
            if self.alt_len > 0 {
                return self.push_alt(byte);
            }
            return self.frames.push(byte).map(LinkEvent::Frame);
        }
        // A candidate: `len < RTCM_MAX_FRAME` here, since a candidate is
        // decided at `N + 6 <= RTCM_MAX_FRAME` bytes.
        let Some(slot) = self.buf.get_mut(self.len) else {
            return self.replay(false);
        };
        *slot = byte;
        self.len += 1;
        if self.len == 2 && byte & 0xFC != 0 {
            return self.replay(false);
        }
        if self.len < 3 {
            return None;
        }
        let total = self.frame_len();
        let complete = self.len >= total;
        if complete {
            let (Some(body), Some(crc)) =
                (self.buf.get(..total - 3), self.buf.get(total - 3..total))
            else {
                return self.replay(false);
            };
            let received = crc.iter().fold(0u32, |acc, &b| (acc << 8) | u32::from(b));
            if CRC24Q.checksum(body) == received {
                self.counts.rtcm_frames = self.counts.rtcm_frames.wrapping_add(1);
                self.mode = Mode::Cobs;
                return self.buf.get(..total).map(LinkEvent::Rtcm);
            }
            self.counts.rtcm_bad_crc = self.counts.rtcm_bad_crc.wrapping_add(1);
        }
        // Not RTCM (yet): a host frame may have ended at this zero.
        if byte == 0 {
            if let Some(event) = self.resync(total) {
                return Some(event);
            }
        }
        if complete {
            return self.replay(true);
        }
        None
    }

    /// A zero byte ended the candidate's `len` bytes so far: if a
    /// CRC-verified host frame ends with it, the candidate is given up:
    /// its bytes before the frame are reported dropped
    /// ([`LinkEvent::TruncatedRtcm`]) and the frame follows at the next
    /// `poll`. `declared` is the header's N + 6.
    fn resync(&mut self, declared: usize) -> Option<LinkEvent<'static>> {
        let start = self.frame_suffix()?;
        // The frame, `buf[start..len]`, is replayed into the idle COBS
        // receiver at the next `poll`: its delimiter completes it.
        self.cursor = start;
        self.mode = Mode::Replay {
            close_tail: false,
            saw_frame: false,
        };
        // Both at most `RTCM_MAX_FRAME`: exact in a u32.
        Some(LinkEvent::TruncatedRtcm {
            received: start as u32,
            declared: declared as u32,
        })
    }

    /// The start of the longest suffix of the candidate that is a
    /// CRC-verified COBS frame ending at its last byte (a zero), if one of
    /// the first [`MAX_RESYNC_TRIES`] plausible starts is. A frame has no
    /// zero before its delimiter, so a start lies after the candidate's
    /// previous zero (and after the 0xD3, which a valid frame cannot start
    /// with here: module documentation); a start is plausible when its
    /// chain of COBS code bytes lands exactly on the delimiter (followed
    /// from each start: at most `len^2 / 2` steps of an add and a compare
    /// per candidate, all zeros together). The COBS receiver is idle
    /// during a candidate and is idle again after each try (its chunk ends
    /// at the delimiter).
    fn frame_suffix(&mut self) -> Option<usize> {
        let z = self.len.checked_sub(1)?;
        let Self { buf, frames, .. } = self;
        let chunk = buf.get(..=z)?;
        let first = chunk
            .get(..z)?
            .iter()
            .rposition(|&b| b == 0)
            .map_or(1, |p| p + 1);
        let mut tries = 0;
        for s in first..z {
            let mut k = s;
            while let Some(&code) = chunk.get(k).filter(|_| k < z) {
                k += usize::from(code);
            }
            if k != z {
                continue;
            }
            tries += 1;
            if tries > MAX_RESYNC_TRIES {
                return None;
            }
            let mut verified = false;
            for &b in chunk.get(s..)? {
                if let Some(event) = frames.push(b) {
                    verified = event.is_ok();
                }
            }
            if verified {
                return Some(s);
            }
        }
        None
    }

    /// The line went quiet (a UART idle-line interrupt, a timeout). A
    /// candidate holds back up to [`RTCM_MAX_FRAME`] bytes until it is
    /// decided, and a receiver sends an RTCM frame in one burst, so a
    /// candidate still open at a pause is not RTCM: its bytes are replayed
    /// into the COBS receiver now rather than when `N + 6` bytes are in.
    /// A COBS chunk still open at a pause is ended as if its delimiter had
    /// come (a host sends a frame in one burst too): so a stray byte, or a
    /// receiver's frame cut at power-up, costs the frames up to the next
    /// pause (a receiver pauses between its epochs), not up to the next
    /// frame that happens to end in 0x00. Returns the first event; call
    /// [`poll`](Self::poll) until `None`.
    pub fn line_idle(&mut self) -> Option<LinkEvent<'_>> {
        match self.mode {
            Mode::Candidate => self.replay(true),
            Mode::Cobs if !self.frames.is_idle() => self.frames.push(0).map(LinkEvent::Frame),
            _ => None,
        }
    }

    /// The next event of the last [`push`](Self::push), `None` once there
    /// is none left.
    pub fn poll(&mut self) -> Option<LinkEvent<'_>> {
        if self.mode == Mode::Rejoin {
            return self.rejoin();
        }
        let Mode::Replay {
            close_tail,
            saw_frame,
        } = self.mode
        else {
            return None;
        };
        while self.cursor < self.len {
            let Some(&b) = self.buf.get(self.cursor) else {
                break;
            };
            self.cursor += 1;
            if self.frames.completes_chunk(b) {
                let event = self.frames.push(b);
                if matches!(event, Some(Ok(_))) {
                    self.mode = Mode::Replay {
                        close_tail,
                        saw_frame: true,
                    };
                }
                return event.map(LinkEvent::Frame);
            }
            // `completes_chunk` was false: no event to lose.
            let _none = self.frames.push(b);
        }
        self.mode = Mode::Cobs;
        let len = core::mem::take(&mut self.len);
        self.cursor = 0;
        if !close_tail || saw_frame || self.frames.is_idle() {
            return None;
        }
        if let Some(candidate) = self
            .buf
            .get(..len)
            .filter(|_| self.frames.completes_chunk(0))
        {
            // An open chunk: the bytes after the candidate's last zero,
            // moved to the front (`tail_start <= len <= RTCM_MAX_FRAME`),
            // with checked accesses (`copy_within`'s range check is one
            // the build keeps).
            let tail_start = candidate.iter().rposition(|&b| b == 0).map_or(0, |z| z + 1);
            self.alt_len = move_to_front(&mut self.buf, tail_start, len);
        }
        // Ends the open chunk (an event) or the skipping of an overflowed
        // one (none). A tail that is a whole frame needs no alternative.
        let event = self.frames.push(0);
        if matches!(event, Some(Ok(_))) {
            self.alt_len = 0;
        }
        event.map(LinkEvent::Frame)
    }

    /// A byte after a closed tail: to the COBS receiver, and kept after the
    /// tail until the next delimiter decides between the two chunks.
    fn push_alt(&mut self, byte: u8) -> Option<LinkEvent<'_>> {
        match self.buf.get_mut(self.alt_len) {
            Some(slot) => {
                *slot = byte;
                self.alt_len += 1;
            }
            None => self.alt_len = 0,
        }
        if byte != 0 {
            if self.frames.completes_chunk(byte) {
                // The chunk overflowed: no frame to join.
                self.alt_len = 0;
            }
            return self.frames.push(byte).map(LinkEvent::Frame);
        }
        if self.alt_len == 0 {
            return self.frames.push(byte).map(LinkEvent::Frame);
        }
        self.mode = Mode::Rejoin;
        if !self.frames.completes_chunk(0) {
            // An empty chunk: the tail was directly followed by this
            // delimiter.
            self.alt_was_frame = false;
            let _none = self.frames.push(0);
            return self.poll();
        }
        let event = self.frames.push(0);
        self.alt_was_frame = matches!(event, Some(Ok(_)));
        event.map(LinkEvent::Frame)
    }

    /// The joined chunk, tail + following bytes + delimiter, into the idle
    /// COBS receiver; reported only if it is a verified frame (its bytes
    /// were already reported as the two chunks' errors).
    fn rejoin(&mut self) -> Option<LinkEvent<'_>> {
        self.mode = Mode::Cobs;
        let n = core::mem::take(&mut self.alt_len);
        if self.alt_was_frame {
            return None;
        }
        let (&delimiter, body) = self.buf.get(..n)?.split_last()?;
        for &b in body {
            let _ = self.frames.push(b);
        }
        match self.frames.push(delimiter) {
            Some(Ok(payload)) => Some(LinkEvent::Frame(Ok(payload))),
            _ => None,
        }
    }

    /// Start replaying the candidate; returns its first event.
    fn replay(&mut self, close_tail: bool) -> Option<LinkEvent<'_>> {
        self.cursor = 0;
        self.mode = Mode::Replay {
            close_tail,
            saw_frame: false,
        };
        self.poll()
    }

    /// `N + 6` from the candidate's header (needs `len >= 3`).
    fn frame_len(&self) -> usize {
        let hi = usize::from(self.buf.get(1).copied().unwrap_or(0) & 0x03);
        let lo = usize::from(self.buf.get(2).copied().unwrap_or(0));
        ((hi << 8) | lo) + 6
    }
}

/// Moves `buf[start..end]` to the front of `buf` (a forward copy, so the
/// overlap is safe) and returns the bytes moved: `end - start` when the
/// range is in `buf`, as `copy_within(start..end, 0)` would; otherwise only
/// the bytes that exist (none when `start >= end`). Checked accesses only.
fn move_to_front(buf: &mut [u8], start: usize, end: usize) -> usize {
    let mut moved = 0;
    for src in start..end {
        let Some(&b) = buf.get(src) else {
            break;
        };
        let Some(slot) = buf.get_mut(moved) else {
            break;
        };
        *slot = b;
        moved += 1;
    }
    moved
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::frame::{encode, Envelope, CRC32};
    use crate::message::{CommandRef, RequestRef};
    use crate::MAX_REQUEST_FRAME;
    use proptest::prelude::*;
    use raim_core::{RangeObservation, SatId, System};
    use std::vec::Vec;

    type Rx = LinkReceiver<MAX_REQUEST_FRAME>;

    proptest! {
        /// The checked move of an open chunk's tail is `copy_within`'s.
        #[test]
        fn move_to_front_is_copy_within(
            bytes in proptest::collection::vec(any::<u8>(), 0..64),
            a in 0usize..70,
            b in 0usize..70,
        ) {
            let mut got = bytes.clone();
            let moved = move_to_front(&mut got, a, b);
            if a <= b && b <= bytes.len() {
                let mut want = bytes.clone();
                want.copy_within(a..b, 0);
                prop_assert_eq!(moved, b - a);
                prop_assert_eq!(got, want);
            } else {
                prop_assert_eq!(moved, b.min(bytes.len()).saturating_sub(a));
            }
        }
    }

    /// An owned [`LinkEvent`].
    #[derive(Debug, Clone, PartialEq, Eq)]
    enum Ev {
        Frame(Result<Vec<u8>, FrameError>),
        Rtcm(Vec<u8>),
        Truncated { received: u32, declared: u32 },
    }

    fn owned(ev: LinkEvent<'_>) -> Ev {
        match ev {
            LinkEvent::Frame(r) => Ev::Frame(r.map(<[u8]>::to_vec)),
            LinkEvent::Rtcm(f) => Ev::Rtcm(f.to_vec()),
            LinkEvent::TruncatedRtcm { received, declared } => Ev::Truncated { received, declared },
        }
    }

    /// Every event of `bytes`, following the push-then-poll contract.
    fn run<const B: usize>(rx: &mut LinkReceiver<B>, bytes: &[u8]) -> Vec<Ev> {
        let mut out = Vec::new();
        for &b in bytes {
            let mut event = rx.push(b).map(owned);
            while let Some(ev) = event {
                out.push(ev);
                event = rx.poll().map(owned);
            }
        }
        out
    }

    /// `run`, then a pause on the line.
    fn run_then_idle<const B: usize>(rx: &mut LinkReceiver<B>, bytes: &[u8]) -> Vec<Ev> {
        let mut out = run(rx, bytes);
        let mut event = rx.line_idle().map(owned);
        while let Some(ev) = event {
            out.push(ev);
            event = rx.poll().map(owned);
        }
        out
    }

    /// The RTCM 3 frame of `payload` (at most 1023 bytes).
    fn rtcm_frame(payload: &[u8]) -> Vec<u8> {
        let n = payload.len();
        assert!(n <= RTCM_MAX_PAYLOAD);
        let mut f = std::vec![RTCM_PREAMBLE, (n >> 8) as u8, n as u8];
        f.extend_from_slice(payload);
        let crc = CRC24Q.checksum(&f);
        f.extend_from_slice(&crc.to_be_bytes()[1..]);
        f
    }

    /// The COBS frame of a raw payload (any bytes, not a message).
    fn cobs_frame(payload: &[u8]) -> Vec<u8> {
        let env = Envelope {
            payload,
            crc32: CRC32.checksum(payload),
        };
        let mut out = std::vec![0u8; 2 * MAX_REQUEST_FRAME];
        postcard::to_slice_cobs(&env, &mut out).unwrap().to_vec()
    }

    /// (payload, frame) of a message.
    fn message_frame(req: &RequestRef<'_>) -> (Vec<u8>, Vec<u8>) {
        let mut scratch = [0u8; 4096];
        let mut out = [0u8; 4096];
        let frame = encode(req, &mut scratch, &mut out).unwrap().to_vec();
        let payload = postcard::to_slice(req, &mut scratch).unwrap().to_vec();
        (payload, frame)
    }

    fn status(seq: u32) -> (Vec<u8>, Vec<u8>) {
        message_frame(&RequestRef {
            seq,
            command: CommandRef::Status,
        })
    }

    /// `x` with every zero byte of its encoding set to 1 (a change in the
    /// mantissa only, for the magnitudes used here).
    fn no_zero_byte(x: f64) -> f64 {
        f64::from_le_bytes(x.to_le_bytes().map(|b| b.max(1)))
    }

    /// A 24-satellite range epoch whose COBS encoding starts with 0xD3: the
    /// envelope's first zero byte must be its 211th (index 210). Envelope
    /// bytes: payload length varint 2, seq varint 1, command 1, time 8,
    /// a-priori 1 + 24, list length 1, so satellite `j` starts at 38 + 43 j
    /// (system, PRN, pseudorange 8, position 24, sigma 1 + 8): index 210 is
    /// the system byte of satellite 4, and GPS encodes as 0. Every other
    /// byte before it is made non-zero.
    fn d3_ranges_epoch() -> (Vec<u8>, Vec<u8>) {
        let sats: Vec<RangeObservation> = (0..24u8)
            .map(|i| {
                let f = f64::from(i);
                RangeObservation {
                    id: SatId::new(if i == 4 { System::Gps } else { System::Galileo }, i + 1),
                    pseudorange_m: no_zero_byte(2.1e7 + 1234.567 * f),
                    position_m: [
                        no_zero_byte(-1.5e7 - 11.1 * f),
                        no_zero_byte(2.2e7 + 22.2 * f),
                        no_zero_byte(1.3e7 + 33.3 * f),
                    ],
                    sigma_m: Some(no_zero_byte(1.25 + 0.01 * f)),
                }
            })
            .collect();
        let apriori_m = Some([
            no_zero_byte(3.9e6),
            no_zero_byte(3.0e5),
            no_zero_byte(5.0e6),
        ]);
        message_frame(&RequestRef::ranges(
            5,
            no_zero_byte(12.345),
            apriori_m,
            &sats,
        ))
    }

    fn gmsd7() -> Option<Vec<u8>> {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/data/GMSD7_20121014.rtcm3"
        );
        match std::fs::read(path) {
            Ok(b) => Some(b),
            Err(e) => {
                std::println!("skipped: {path} not readable ({e})");
                None
            }
        }
    }

    /// The frames of `data` by `rtcm_rs`: at every 0xD3, a frame if
    /// `MessageFrame::new` accepts it (length and CRC), else the next byte;
    /// stops at an incomplete last frame.
    fn reference_frames(data: &[u8]) -> Vec<Vec<u8>> {
        let mut out = Vec::new();
        let mut i = 0;
        while i < data.len() {
            if data[i] != RTCM_PREAMBLE {
                i += 1;
                continue;
            }
            match rtcm_rs::MessageFrame::new(&data[i..]) {
                Ok(f) => {
                    out.push(f.frame_data().to_vec());
                    i += f.frame_len();
                }
                Err(rtcm_rs::rtcm_error::RtcmError::Incomplete) => break,
                Err(_) => i += 1,
            }
        }
        out
    }

    #[test]
    fn crc24q_is_the_catalogue_crc_and_checks_a_real_frame() {
        // Catalogue check value of CRC-24/LTE-A (= CRC-24Q).
        assert_eq!(CRC24Q.checksum(b"123456789"), 0x00CD_E703);
        // A frame built here is accepted by an independent RTCM reader.
        let f = rtcm_frame(&[0x3E, 0xD0, 0x00, 0x03, 0x8A]);
        let m = rtcm_rs::MessageFrame::new(&f).unwrap();
        assert_eq!(m.frame_len(), f.len());
        let Some(data) = gmsd7() else { return };
        // The file's first frame: header + payload, then its CRC.
        let n = (usize::from(data[1] & 3) << 8) | usize::from(data[2]);
        let crc = u32::from_be_bytes([0, data[n + 3], data[n + 4], data[n + 5]]);
        assert_eq!(CRC24Q.checksum(&data[..n + 3]), crc);
    }

    #[test]
    fn every_gmsd7_frame_comes_out_as_rtcm() {
        let Some(data) = gmsd7() else { return };
        let reference = reference_frames(&data);
        let mut rx = Rx::new();
        let got = run(&mut rx, &data);
        let expected: Vec<Ev> = reference.iter().cloned().map(Ev::Rtcm).collect();
        // The file is frames back to back: nothing else comes out.
        assert_eq!(got.len(), expected.len());
        assert!(got == expected, "the frames differ from rtcm-rs's");
        std::println!("GMSD7: {} RTCM frames", got.len());
        assert!(got.len() > 1000, "{} frames", got.len());
        let c = rx.counts();
        assert_eq!(c.rtcm_frames as usize, reference.len());
        assert_eq!((c.rtcm_bad_crc, c.unpolled_events), (0, 0));
    }

    #[test]
    fn the_d3_epoch_starts_with_the_preamble_and_stays_a_cobs_frame() {
        let (payload, frame) = d3_ranges_epoch();
        assert_eq!(frame[0], RTCM_PREAMBLE);
        assert!(frame[1] & 0xFC != 0, "second byte {:#04x}", frame[1]);
        let mut rx = Rx::new();
        assert_eq!(run(&mut rx, &frame), std::vec![Ev::Frame(Ok(payload))]);
        assert_eq!(rx.counts(), LinkCounts::default());
    }

    /// Verifies: RX-LINK
    #[test]
    fn gmsd7_interleaved_with_cobs_requests_comes_out_in_order() {
        let Some(data) = gmsd7() else { return };
        let reference = reference_frames(&data);
        let (d3_payload, d3_frame) = d3_ranges_epoch();
        assert_eq!(d3_frame[0], RTCM_PREAMBLE);
        let mut stream = Vec::new();
        let mut expected = Vec::new();
        for (k, f) in reference.iter().enumerate() {
            match k % 4 {
                0 => {
                    let (p, g) = status(k as u32);
                    stream.extend(&g);
                    expected.push(Ev::Frame(Ok(p)));
                }
                1 => {
                    stream.extend(&d3_frame);
                    expected.push(Ev::Frame(Ok(d3_payload.clone())));
                }
                2 => {
                    // Two frames in a row, then a sync byte.
                    for seq in [k as u32, k as u32 + 1] {
                        let (p, g) = status(seq);
                        stream.extend(&g);
                        expected.push(Ev::Frame(Ok(p)));
                    }
                    stream.push(0);
                }
                _ => {}
            }
            stream.extend(f);
            expected.push(Ev::Rtcm(f.clone()));
        }
        stream.extend(&d3_frame);
        expected.push(Ev::Frame(Ok(d3_payload)));
        let mut rx = Rx::new();
        let got = run(&mut rx, &stream);
        assert_eq!(got.len(), expected.len());
        assert!(got == expected, "events differ");
        let c = rx.counts();
        assert_eq!(c.rtcm_frames as usize, reference.len());
        assert_eq!((c.rtcm_bad_crc, c.unpolled_events), (0, 0));
    }

    /// `f` with bit `bit` of its payload flipped.
    fn flipped(f: &[u8], bit: usize) -> Vec<u8> {
        let mut g = f.to_vec();
        let n = f.len() - 6;
        g[3 + (bit / 8) % n] ^= 1 << (bit % 8);
        g
    }

    /// A corrupted frame, then a COBS frame, an intact RTCM frame and
    /// another COBS frame: the corrupted frame only gives framing errors.
    fn check_corrupted(bad: &[u8], good: &[u8]) {
        let (p1, f1) = status(1);
        let (p2, f2) = status(2);
        let mut stream = bad.to_vec();
        stream.extend(&f1);
        stream.extend(good);
        stream.extend(&f2);
        let mut rx = Rx::new();
        let got = run(&mut rx, &stream);
        let tail = [
            Ev::Frame(Ok(p1)),
            Ev::Rtcm(good.to_vec()),
            Ev::Frame(Ok(p2)),
        ];
        assert!(got.len() >= tail.len(), "{got:?}");
        let (junk, rest) = got.split_at(got.len() - tail.len());
        assert_eq!(rest, tail);
        assert!(
            junk.iter().all(|e| matches!(e, Ev::Frame(Err(_)))),
            "{junk:?}"
        );
        let c = rx.counts();
        assert_eq!((c.rtcm_frames, c.rtcm_bad_crc), (1, 1));
    }

    #[test]
    fn a_corrupted_rtcm_frame_is_not_rtcm_and_keeps_the_next_frames() {
        // Synthetic payloads with and without zeros, so that the replay
        // leaves an open chunk or none.
        let payloads: [Vec<u8>; 4] = [
            (0..200u32).map(|i| (i * 37 % 256) as u8).collect(),
            std::vec![0x5A; 40],
            std::vec![0; 12],
            (0..1023u32).map(|i| (i * 101 % 251) as u8).collect(),
        ];
        for p in &payloads {
            let f = rtcm_frame(p);
            for bit in [0, 7, 13, 8 * p.len() - 1] {
                check_corrupted(&flipped(&f, bit), &f);
            }
        }
        let Some(data) = gmsd7() else { return };
        let reference = reference_frames(&data);
        for (k, pair) in reference.windows(2).enumerate() {
            check_corrupted(&flipped(&pair[0], 8 * k + k % 8), &pair[1]);
        }
    }

    #[test]
    fn a_stray_header_is_given_up_at_the_first_frame_it_covers() {
        // A stray 0xD3 at a frame boundary, then 0x01 0x00: a plausible
        // header of a 256-byte payload (262-byte candidate). The status
        // frames that follow would be inside the candidate: the first one's
        // delimiter ends it (resynchronisation), the rest are received as
        // they come.
        let mut stream = std::vec![RTCM_PREAMBLE, 0x01, 0x00];
        let mut expected = std::vec![Ev::Truncated {
            received: 3,
            declared: 262
        }];
        let mut seq = 0x100;
        while stream.len() < 262 + 5 {
            let (p, f) = status(seq);
            stream.extend(&f);
            expected.push(Ev::Frame(Ok(p)));
            seq += 1;
        }
        let mut rx = Rx::new();
        assert_eq!(run(&mut rx, &stream), expected);
        assert_eq!(rx.counts().rtcm_bad_crc, 0);
        assert_eq!(rx.counts().unpolled_events, 0);
        // Without `poll`, the first frame (the second event of its
        // delimiter) is counted as dropped at the next push.
        let mut rx = Rx::new();
        let mut first = Vec::new();
        for &b in &stream {
            if let Some(ev) = rx.push(b) {
                first.push(owned(ev));
            }
        }
        assert_eq!(first.len(), expected.len() - 1, "{first:?}");
        assert_eq!(rx.counts().unpolled_events, 1);
    }

    #[test]
    fn a_frame_across_the_end_of_a_failed_candidate_comes_out_once() {
        // Junk "D3 01 01 <k bytes> 00" opens a 263-byte candidate (N =
        // 0x101); k is chosen so that the candidate ends after `cut` bytes
        // of the status frame that follows. The tail (those `cut` bytes) is
        // closed, the rest of the frame is a chunk of its own, and the two
        // joined are the frame.
        let (p, f) = status(0x0102_0304);
        for cut in 1..f.len() {
            let k = 259 - cut;
            let mut stream = std::vec![RTCM_PREAMBLE, 0x01, 0x01];
            stream.extend(std::iter::repeat_n(0x77u8, k));
            stream.push(0);
            assert_eq!(stream.len() + cut, 0x101 + 6);
            stream.extend(&f);
            let (q, g) = status(7);
            stream.extend(&g);
            let mut rx = Rx::new();
            let got = run(&mut rx, &stream);
            let oks: Vec<&Ev> = got
                .iter()
                .filter(|e| matches!(e, Ev::Frame(Ok(_))))
                .collect();
            if f[cut] == RTCM_PREAMBLE {
                // The documented loss: the byte after the candidate opens
                // a new one, which takes the buffer.
                assert_eq!(oks, [&Ev::Frame(Ok(q.clone()))], "cut {cut}");
            } else {
                assert_eq!(
                    oks,
                    [&Ev::Frame(Ok(p.clone())), &Ev::Frame(Ok(q.clone()))],
                    "cut {cut}: {got:?}"
                );
            }
            assert_eq!(got.last(), Some(&Ev::Frame(Ok(q))));
            let c = rx.counts();
            assert_eq!((c.rtcm_frames, c.rtcm_bad_crc), (0, 1));
        }
    }

    #[test]
    fn a_lone_d3_before_a_sync_byte_does_not_take_the_next_frame() {
        // "D3" then a delimiter: a plausible header (reserved bits 0) whose
        // length byte is the next frame's COBS code.
        let (p, f) = status(3);
        let (q, g) = status(4);
        let mut stream = std::vec![RTCM_PREAMBLE, 0];
        stream.extend(&f);
        stream.extend(&g);
        let got = run_then_idle(&mut Rx::new(), &stream);
        assert_eq!(
            verified(&got),
            [Ev::Frame(Ok(p)), Ev::Frame(Ok(q))],
            "{got:?}"
        );
    }

    #[test]
    fn a_pause_replays_an_open_candidate() {
        // The candidate (N = 0x100) would wait for 262 bytes; a pause on
        // the line decides it.
        // A frame whose delimiter has not come (a host that sends it
        // after the pause) ends at the pause too.
        let (p, f) = status(11);
        let mut stream = std::vec![RTCM_PREAMBLE, 0x01, 0x00];
        stream.extend(&f[..f.len() - 1]);
        let mut rx = Rx::new();
        assert_eq!(run(&mut rx, &stream), []);
        let got = run_then_idle(&mut rx, &[]);
        assert_eq!(
            got,
            [
                Ev::Frame(Err(FrameError::Undecodable { len: 3 })),
                Ev::Frame(Ok(p))
            ]
        );
        // Nothing open: a pause changes nothing.
        assert!(rx.line_idle().is_none());
        assert_eq!(rx.counts(), LinkCounts::default());
    }

    #[test]
    fn a_frame_cut_short_ends_at_the_pause_and_keeps_the_next_request() {
        // A receiver's frame cut after 40 bytes (its power went, or the
        // stream's file ends there), a pause, then a request: the cut
        // frame's bytes end as a chunk at the pause, the request comes
        // through whole.
        let Some(data) = gmsd7() else { return };
        let reference = reference_frames(&data);
        let cut = &reference[0][..40];
        let (p, f) = status(12);
        let mut rx = Rx::new();
        assert_eq!(run(&mut rx, cut), []);
        let at_pause = run_then_idle(&mut rx, &[]);
        assert!(
            at_pause.iter().all(|e| matches!(e, Ev::Frame(Err(_)))),
            "{at_pause:?}"
        );
        assert!(!at_pause.is_empty());
        assert_eq!(run(&mut rx, &f), [Ev::Frame(Ok(p))]);
        assert_eq!(rx.counts().rtcm_bad_crc, 0);
    }

    #[test]
    fn a_stray_byte_costs_rtcm_frames_until_a_boundary() {
        // A stray byte before frame k of GMSD7: frames are read as COBS
        // chunks until frame j, the first from k on whose last byte is 0;
        // every frame after j comes out again, in order.
        let Some(data) = gmsd7() else { return };
        let reference = reference_frames(&data);
        let mut lost = Vec::new();
        for k in (0..reference.len()).step_by(97) {
            let Some(j) = (k..reference.len()).find(|&i| reference[i].last() == Some(&0)) else {
                continue;
            };
            let mut stream = Vec::new();
            for (i, f) in reference.iter().enumerate() {
                if i == k {
                    stream.push(0x55);
                }
                stream.extend(f);
            }
            let got: Vec<Vec<u8>> = run(&mut Rx::new(), &stream)
                .into_iter()
                .filter_map(|e| match e {
                    Ev::Rtcm(f) => Some(f),
                    Ev::Frame(_) | Ev::Truncated { .. } => None,
                })
                .collect();
            let n_lost = reference.len() - got.len();
            assert!(n_lost <= j - k + 1, "k {k}: {n_lost} lost, j {j}");
            assert_eq!(got[..k], reference[..k]);
            let after = reference.len() - (j + 1);
            assert_eq!(got[got.len() - after..], reference[j + 1..]);
            lost.push(n_lost);
        }
        let ends_in_zero = reference.iter().filter(|f| f.last() == Some(&0)).count();
        std::println!(
            "GMSD7: {ends_in_zero} of {} frames end in 0; RTCM frames lost after one stray byte: {lost:?}",
            reference.len()
        );
    }

    /// Verifies: RX-LINK
    #[test]
    fn a_pause_between_epochs_resynchronises_after_a_stray_byte() {
        // GMSD7 as a receiver sends it: each epoch's frames in one burst
        // (up to the MSM whose multiple-message bit is 0), a pause after
        // it. A stray byte before frame k costs at most the rest of k's
        // burst: the pause ends the open COBS chunk, and the next burst's
        // first 0xD3 starts a candidate again.
        let Some(data) = gmsd7() else { return };
        let reference = reference_frames(&data);
        let ends_epoch = |f: &[u8]| {
            let n = (u16::from(f[3]) << 4) | (u16::from(f[4]) >> 4);
            (1071..=1137).contains(&n) && f[9] & 0x02 == 0
        };
        let bursts = reference.iter().filter(|f| ends_epoch(f)).count();
        assert!(bursts > 200, "{bursts} bursts");
        let mut lost = Vec::new();
        for k in (0..reference.len()).step_by(37) {
            let Some(end) = (k..reference.len()).find(|&i| ends_epoch(&reference[i])) else {
                continue;
            };
            let mut rx = Rx::new();
            let mut got = Vec::new();
            for (i, f) in reference.iter().enumerate() {
                let mut bytes = Vec::new();
                if i == k {
                    bytes.push(0x55);
                }
                bytes.extend(f);
                let evs = if ends_epoch(f) {
                    run_then_idle(&mut rx, &bytes)
                } else {
                    run(&mut rx, &bytes)
                };
                got.extend(evs.into_iter().filter_map(|e| match e {
                    Ev::Rtcm(f) => Some(f),
                    Ev::Frame(_) | Ev::Truncated { .. } => None,
                }));
            }
            let n_lost = reference.len() - got.len();
            assert!(
                n_lost <= end - k + 1,
                "k {k}: {n_lost} lost, burst ends at {end}"
            );
            assert_eq!(got[..k], reference[..k]);
            let after = reference.len() - (end + 1);
            assert_eq!(got[got.len() - after..], reference[end + 1..]);
            lost.push(n_lost);
        }
        std::println!("GMSD7 in epoch bursts: RTCM frames lost after one stray byte: {lost:?}");
    }

    #[test]
    fn reserved_bits_reject_a_candidate_at_its_second_byte() {
        // 0xD3 0x04: not RTCM, two bytes replayed into the open chunk.
        let (p, f) = status(9);
        let mut stream = std::vec![0u8, RTCM_PREAMBLE, 0x04, 0x00];
        stream.extend(&f);
        let mut rx = Rx::new();
        let got = run(&mut rx, &stream);
        assert_eq!(
            got,
            std::vec![
                Ev::Frame(Err(FrameError::Undecodable { len: 3 })),
                Ev::Frame(Ok(p))
            ]
        );
        assert_eq!(rx.counts(), LinkCounts::default());
    }

    #[test]
    fn rtcm_starts_only_between_cobs_chunks() {
        // An RTCM frame glued to the end of an open chunk is COBS bytes.
        let r = rtcm_frame(&[1, 2, 3, 4]);
        let mut stream = std::vec![0x11u8, 0x22];
        stream.extend(&r);
        let mut rx = Rx::new();
        let got = run(&mut rx, &stream);
        assert!(got.iter().all(|e| matches!(e, Ev::Frame(Err(_)))));
        assert_eq!(rx.counts().rtcm_frames, 0);
        // After the next delimiter the same frame is recognised.
        let mut stream = std::vec![0x11u8, 0x22, 0x00];
        stream.extend(&r);
        let got = run(&mut Rx::new(), &stream);
        assert_eq!(got.last(), Some(&Ev::Rtcm(r)));
        // The shortest frame: an empty payload.
        let e = rtcm_frame(&[]);
        assert_eq!(e.len(), 6);
        assert_eq!(run(&mut Rx::new(), &e), std::vec![Ev::Rtcm(e.clone())]);
    }

    /// Issue 35, the link that lost a frame: `D3 03 FF` (an RTCM header
    /// declaring 1023 payload bytes) and 10 bytes of noise, no delimiter,
    /// then a host request. The request is answered at its own delimiter,
    /// not at the next pause or 1029 bytes later, and the noise before it
    /// is reported first, with what is known of it: 13 bytes of a
    /// 1029-byte frame.
    ///
    /// Verifies: SAFE-LINK-RESYNC
    #[test]
    fn a_host_frame_after_a_cut_rtcm_header_is_not_lost() {
        let (payload, frame) = status(7);
        let mut stream = std::vec![RTCM_PREAMBLE, 0x03, 0xFF];
        stream.extend([0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88, 0x99, 0xAA]);
        stream.extend(&frame);
        let mut rx = Rx::new();
        assert_eq!(
            run(&mut rx, &stream),
            std::vec![
                Ev::Truncated {
                    received: 13,
                    declared: 1029
                },
                Ev::Frame(Ok(payload.clone())),
            ]
        );
        // The receiver is between frames again: the next request and an
        // RTCM frame with zeros in its payload come out as they are.
        let rtcm = rtcm_frame(&[0, 1, 0, 0, 2, 0, 3]);
        let (p2, f2) = status(8);
        let mut next = rtcm.clone();
        next.extend(&f2);
        assert_eq!(
            run(&mut rx, &next),
            std::vec![Ev::Rtcm(rtcm), Ev::Frame(Ok(p2))]
        );
        assert_eq!(rx.counts().unpolled_events, 0);
    }

    #[derive(Debug, Clone)]
    enum Item {
        Cobs(Vec<u8>),
        Rtcm(Vec<u8>),
        /// An RTCM frame of this payload with payload bit `.1` flipped.
        BadRtcm(Vec<u8>, usize),
        Sync,
    }

    fn item() -> impl Strategy<Value = Item> {
        prop_oneof![
            3 => prop::collection::vec(any::<u8>(), 1..300).prop_map(Item::Cobs),
            // A payload whose COBS frame starts with 0xD3: non-zero bytes
            // with a zero at payload index 208 (envelope index 210).
            1 => (
                prop::collection::vec(1u8..=255, 209..600),
                prop::collection::vec(any::<u8>(), 0..200)
            )
                .prop_map(|(mut p, rest)| {
                    p[208] = 0;
                    p.extend(rest);
                    Item::Cobs(p)
                }),
            3 => prop::collection::vec(any::<u8>(), 0..=RTCM_MAX_PAYLOAD).prop_map(Item::Rtcm),
            1 => (prop::collection::vec(any::<u8>(), 1..=RTCM_MAX_PAYLOAD), any::<usize>())
                .prop_map(|(p, bit)| Item::BadRtcm(p, bit)),
            1 => Just(Item::Sync),
        ]
    }

    /// A junk chunk (delimiter included); with `rtcm_like` it starts with
    /// 0xD3 and a byte in 0..=3, a plausible RTCM header.
    fn junk(rtcm_like: bool) -> impl Strategy<Value = Vec<u8>> {
        (prop::collection::vec(1u8..=255, 0..40), 0u8..=3).prop_map(move |(mut g, b1)| {
            if rtcm_like {
                g.splice(0..0, [RTCM_PREAMBLE, b1]);
                g.retain(|&b| b != 0);
                if b1 == 0 {
                    g.truncate(1);
                }
            } else if g.first() == Some(&RTCM_PREAMBLE) && g.get(1).is_none_or(|&b| b <= 3) {
                g[0] = 0x55;
            }
            g.push(0);
            g
        })
    }

    fn frames_alone(stream: &[u8]) -> Vec<Ev> {
        let mut fr = FrameReceiver::<MAX_REQUEST_FRAME>::new();
        stream
            .iter()
            .filter_map(|&b| fr.push(b).map(|r| Ev::Frame(r.map(<[u8]>::to_vec))))
            .collect()
    }

    fn verified(events: &[Ev]) -> Vec<Ev> {
        events
            .iter()
            .filter(|e| !matches!(e, Ev::Frame(Err(_)) | Ev::Truncated { .. }))
            .cloned()
            .collect()
    }

    proptest! {

        /// Every COBS frame and RTCM frame comes out, in order; a corrupted
        /// RTCM frame gives framing errors only and takes nothing with it.
        #[test]
        fn interleavings_round_trip_in_order(items in prop::collection::vec(item(), 0..12)) {
            let mut stream = Vec::new();
            let mut expected = Vec::new();
            let (mut n_rtcm, mut n_bad) = (0u32, 0u32);
            for it in &items {
                match it {
                    Item::Cobs(p) => {
                        let f = cobs_frame(p);
                        if p.len() >= 209 && p[..208].iter().all(|&b| b != 0) && p[208] == 0 {
                            prop_assert_eq!(f[0], RTCM_PREAMBLE);
                        }
                        stream.extend(&f);
                        expected.push(Ev::Frame(Ok(p.clone())));
                    }
                    Item::Rtcm(p) => {
                        let f = rtcm_frame(p);
                        let m = rtcm_rs::MessageFrame::new(&f);
                        prop_assert!(m.is_ok_and(|m| m.frame_len() == f.len()));
                        stream.extend(&f);
                        expected.push(Ev::Rtcm(f));
                        n_rtcm += 1;
                    }
                    Item::BadRtcm(p, bit) => {
                        let f = flipped(&rtcm_frame(p), *bit);
                        prop_assert!(rtcm_rs::MessageFrame::new(&f).is_err());
                        stream.extend(&f);
                        n_bad += 1;
                    }
                    Item::Sync => stream.push(0),
                }
            }
            let mut rx = Rx::new();
            let got = run(&mut rx, &stream);
            if n_bad == 0 {
                prop_assert_eq!(&got, &expected);
            }
            prop_assert_eq!(verified(&got), expected);
            let c = rx.counts();
            prop_assert_eq!((c.rtcm_frames, c.rtcm_bad_crc, c.unpolled_events), (n_rtcm, n_bad, 0));
        }

        /// On a stream of COBS frames, sync bytes and junk chunks without an
        /// RTCM-like start, the link receiver yields exactly what the frame
        /// receiver alone yields.
        #[test]
        fn pure_cobs_streams_are_unchanged(
            parts in prop::collection::vec(
                prop_oneof![
                    prop::collection::vec(any::<u8>(), 1..400).prop_map(|p| cobs_frame(&p)),
                    junk(false),
                    Just(std::vec![0u8]),
                ],
                0..10,
            )
        ) {
            let stream: Vec<u8> = parts.concat();
            let mut rx = Rx::new();
            prop_assert_eq!(run(&mut rx, &stream), frames_alone(&stream));
        }

        /// Junk that starts like an RTCM header opens a candidate that fails
        /// its CRC; the frames it covers, and the one across its end, still
        /// come out in order (the framing errors may be cut differently).
        /// Excluded: a window that ends on a 0xD3, where the new candidate
        /// takes the buffer of the frame across the end (module docs).
        #[test]
        fn rtcm_like_junk_loses_no_frame(
            parts in prop::collection::vec(
                prop_oneof![
                    3 => prop::collection::vec(any::<u8>(), 1..400).prop_map(|p| cobs_frame(&p)),
                    1 => junk(false),
                    2 => junk(true),
                    1 => Just(std::vec![0u8]),
                ],
                0..10,
            )
        ) {
            let stream: Vec<u8> = parts.concat();
            // Window ends: N + 6 bytes from every RTCM-like start.
            let mut at = 0;
            for part in &parts {
                if part.len() >= 2 && part[0] == RTCM_PREAMBLE && part[1] <= 3 {
                    if let Some(&lo) = stream.get(at + 2) {
                        let n = (usize::from(part[1] & 3) << 8) | usize::from(lo);
                        prop_assume!(stream.get(at + n + 6) != Some(&RTCM_PREAMBLE));
                    }
                }
                at += part.len();
            }
            let mut rx = Rx::new();
            let got = run_then_idle(&mut rx, &stream);
            prop_assert_eq!(verified(&got), verified(&frames_alone(&stream)));
            prop_assert_eq!(rx.counts().rtcm_frames, 0);
        }

        /// Issue 35: any plausible RTCM header (reserved bits 0, a declared
        /// length longer than what follows), then noise of any bytes,
        /// zeros included, then a host frame with no pause: the frame comes
        /// out at its own delimiter, verified, preceded by one
        /// `TruncatedRtcm` that declares the header's length; no RTCM frame
        /// is reported.
        ///
        /// Verifies: SAFE-LINK-RESYNC
        #[test]
        fn a_host_frame_after_rtcm_like_noise_comes_out_at_its_delimiter(
            hi in 0u8..=3,
            lo in any::<u8>(),
            noise in prop::collection::vec(any::<u8>(), 0..40),
            payload in prop::collection::vec(any::<u8>(), 1..300),
        ) {
            let declared = ((usize::from(hi) << 8) | usize::from(lo)) + 6;
            let frame = cobs_frame(&payload);
            let mut stream = std::vec![RTCM_PREAMBLE, hi, lo];
            stream.extend(&noise);
            // The header must declare more than the bytes up to the frame's
            // end (else the candidate is decided by its CRC first).
            prop_assume!(declared > stream.len() + frame.len());
            stream.extend(&frame);
            let mut rx = Rx::new();
            let got = run(&mut rx, &stream);
            let want = Ev::Frame(Ok(payload));
            prop_assert_eq!(got.last(), Some(&want), "events {:?}", &got);
            let truncated: Vec<&Ev> =
                got.iter().filter(|e| matches!(e, Ev::Truncated { .. })).collect();
            prop_assert_eq!(truncated.len(), 1);
            prop_assert!(matches!(
                truncated[0],
                Ev::Truncated { declared: d, .. } if *d as usize == declared
            ), "declared {}", declared);
            prop_assert!(!got.iter().any(|e| matches!(e, Ev::Rtcm(_))));
            prop_assert!(rx.line_idle().is_none());
        }

        /// `completes_chunk` predicts `push`, overflows included, and
        /// `is_idle` holds exactly at chunk boundaries.
        #[test]
        fn completes_chunk_predicts_push(bytes in prop::collection::vec(
            prop_oneof![3 => 1u8..=255, 1 => Just(0u8)], 0..200)
        ) {
            let mut fr = FrameReceiver::<16>::new();
            let mut boundary = true;
            let mut discarding = false;
            for &b in &bytes {
                prop_assert_eq!(fr.is_idle(), boundary && !discarding);
                let predicted = fr.completes_chunk(b);
                let got = fr.push(b);
                prop_assert_eq!(predicted, got.is_some());
                if matches!(got, Some(Err(FrameError::Overflow { .. }))) && b != 0 {
                    discarding = true;
                }
                if b == 0 {
                    discarding = false;
                }
                boundary = b == 0 || (boundary && discarding);
            }
        }
    }
}
