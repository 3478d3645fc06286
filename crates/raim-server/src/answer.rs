//! Requests in, answers out: the decoder of a request payload, the
//! encoder of an answer (from references into the server, so that no
//! answer-sized value passes through the stack) and the NMEA writer.

use embedded_io::Write;
use serde::Serialize;

use raim_core::Epoch;
use raim_proto::error::WireError;
use raim_proto::frame::{encode, FrameError};
use raim_proto::lock::ConfigId;
use raim_proto::message::{Command, Request, ResponseBody, Status};
use raim_proto::nmea;
use raim_proto::result::WireResult;
use raim_proto::{CAPACITY, MAX_RESPONSE_FRAME, MAX_RESPONSE_PAYLOAD};

use crate::IoError;

/// The epoch's NMEA sentences, written one at a time as they are formed.
/// Its own frame, not on the epoch's path. The request is the epoch's (the
/// satellites seen, for GSV and the DOPs); without one, the sentences of an
/// epoch with no satellites. `cn0_dbhz`: the C/N0 of the epoch's
/// satellites for GSV, when known (a stream epoch's, from its MSM; the
/// protocol's epochs carry none: empty); `velocity`: the speed and course
/// over ground for RMC and VTG, when known (a stream epoch's, from its
/// Doppler, `stream::StreamState::velocity`).
#[inline(never)]
pub(crate) fn write_nmea<M: Write>(
    wire: &WireResult,
    request: Option<&Request>,
    cn0_dbhz: &[u8],
    velocity: Option<nmea::GroundVelocity>,
    nmea_out: &mut M,
) -> Result<(), M::Error> {
    write_nmea_for(
        wire,
        request.map(|r| &r.command),
        cn0_dbhz,
        velocity,
        nmea_out,
    )
}

/// [`write_nmea`] for an epoch command taken out of the request slot.
#[inline(never)]
pub(crate) fn write_nmea_for<M: Write>(
    wire: &WireResult,
    command: Option<&Command>,
    cn0_dbhz: &[u8],
    velocity: Option<nmea::GroundVelocity>,
    nmea_out: &mut M,
) -> Result<(), M::Error> {
    use raim_proto::araim_msg::AraimCommand;
    let epoch = match command {
        Some(
            Command::Ranges(e) | Command::PfRanges(e) | Command::Araim(AraimCommand::Ranges(e)),
        ) => Epoch::ranges(e.time_s, &e.sats.items, e.apriori_m),
        Some(Command::Linear(e) | Command::Araim(AraimCommand::Epoch(e))) => {
            Epoch::linear(e.time_s, &e.sats.items)
        }
        _ => Epoch::linear(wire.time_s, &[]),
    };
    nmea::write_epoch(
        wire,
        &nmea::Sky {
            epoch: &epoch,
            cn0_dbhz,
            velocity,
        },
        nmea::BUILT,
        &mut |s: &nmea::Sentence| nmea_out.write_all(s.as_bytes()),
    )?;
    nmea_out.flush()
}

/// A request refused before it is acted on: undecodable, or carrying a
/// satellite list longer than the capacity.
pub(crate) struct Refusal {
    /// The request's sequence number, when the payload starts with one.
    pub(crate) seq: Option<u32>,
    pub(crate) error: WireError,
    /// The refused request was an epoch (its refusal drives the alarm
    /// output, as an epoch answered with an error does).
    pub(crate) epoch: bool,
    /// The time of a refused snapshot epoch, whose no-fix NMEA sentences
    /// are written (NaN: a frame that could not be read, whose time is
    /// unknown; its sentences carry empty time and date fields).
    pub(crate) nmea_time_s: Option<f64>,
}

impl Refusal {
    /// A frame that could not be read (overflow, COBS or envelope, CRC,
    /// or a payload that is not a request): it may have been an epoch, so
    /// it is refused as one (the alarm output hears a refused epoch, the
    /// no-fix sentences go out), whatever it was (issue 35).
    pub(crate) fn unread(seq: Option<u32>, error: WireError) -> Self {
        Refusal {
            seq,
            error,
            epoch: true,
            nmea_time_s: Some(f64::NAN),
        }
    }
}

/// Decode a request payload into `slot` and check it once: its sequence
/// number, or the refusal. A list that overflowed the capacity is refused
/// here (`TooManySatellites` with the declared count), so that nothing
/// downstream sees a truncated list. Its own frame, not inlined: the
/// decoder's temporaries are gone before the request is acted on.
#[inline(never)]
pub(crate) fn decode(payload: &[u8], slot: &mut Option<Request>) -> Result<u32, Refusal> {
    *slot = None;
    match postcard::from_bytes::<Request>(payload) {
        Ok(r) => {
            let seq = r.seq;
            if let Some(declared) = r.command.overflowed_list() {
                return Err(Refusal {
                    seq: Some(seq),
                    error: WireError::TooManySatellites {
                        have: declared,
                        capacity: CAPACITY as u32,
                    },
                    epoch: r.command.is_epoch(),
                    nmea_time_s: r.command.nmea_epoch_time_s(),
                });
            }
            *slot = Some(r);
            Ok(seq)
        }
        Err(_) => {
            let seq = postcard::take_from_bytes::<u32>(payload)
                .ok()
                .map(|(s, _)| s);
            let len = u32::try_from(payload.len()).unwrap_or(u32::MAX);
            Err(Refusal::unread(
                seq,
                WireError::from(FrameError::Undecodable { len }),
            ))
        }
    }
}

/// The server's transmit buffers and counters, borrowed apart from the
/// rest of the server so that an answer can be encoded from a reference
/// into the server (`BodyRef::Result(&self.wire)`).
pub(crate) struct Buffers<'a> {
    pub(crate) scratch: &'a mut [u8; MAX_RESPONSE_PAYLOAD],
    pub(crate) out: &'a mut [u8; MAX_RESPONSE_FRAME],
    pub(crate) status: &'a mut Status,
    pub(crate) config: ConfigId,
}

/// A [`ResponseBody`] by reference: encodes byte for byte as the
/// `ResponseBody` of the same variant (postcard writes an enum as its
/// variant index, then the payload; `&T` serializes as `T`; the variants
/// are in the same order: test `body_ref_encodes_as_response_body`).
#[derive(Serialize)]
pub(crate) enum BodyRef<'a> {
    Result(&'a WireResult),
    Configured,
    Status(&'a Status),
    Error(&'a WireError),
    LockEngaged,
    Araim(&'a raim_proto::araim_msg::AraimAnswer),
    PfResult(&'a raim_proto::pf_msg::WirePfResult),
    Boot(&'a raim_proto::message::BootNotice),
}

impl<'a> From<&'a ResponseBody> for BodyRef<'a> {
    fn from(b: &'a ResponseBody) -> Self {
        match b {
            ResponseBody::Result(r) => BodyRef::Result(r),
            ResponseBody::Configured => BodyRef::Configured,
            ResponseBody::Status(s) => BodyRef::Status(s),
            ResponseBody::Error(e) => BodyRef::Error(e),
            ResponseBody::LockEngaged => BodyRef::LockEngaged,
            ResponseBody::Araim(a) => BodyRef::Araim(a),
            ResponseBody::PfResult(p) => BodyRef::PfResult(p),
            ResponseBody::Boot(b) => BodyRef::Boot(b),
        }
    }
}

/// A [`Response`] by reference (same encoding, field for field).
#[derive(Serialize)]
pub(crate) struct ResponseRef<'a> {
    pub(crate) seq: Option<u32>,
    pub(crate) body: BodyRef<'a>,
    pub(crate) config: ConfigId,
}

/// Encode and write one answer. Its own frame (the fallback answer), not
/// on the epoch's path.
#[inline(never)]
pub(crate) fn send_answer<L: Write, M>(
    buf: Buffers<'_>,
    link: &mut L,
    seq: Option<u32>,
    body: BodyRef<'_>,
) -> Result<(), IoError<L::Error, M>> {
    if matches!(body, BodyRef::Error(_)) {
        buf.status.errors = buf.status.errors.wrapping_add(1);
    }
    let config = buf.config;
    let resp = ResponseRef { seq, body, config };
    // The buffers hold the largest response (test
    // `result::tests::largest_response_fits`); should encoding ever
    // fail, a minimal error answer still goes out.
    let frame = match encode(&resp, buf.scratch, buf.out) {
        Ok(f) => f,
        Err(_) => {
            let fallback = ResponseRef {
                seq,
                config,
                body: BodyRef::Error(&WireError::Overflow {
                    capacity: MAX_RESPONSE_PAYLOAD as u32,
                }),
            };
            match encode(&fallback, buf.scratch, buf.out) {
                Ok(f) => f,
                Err(_) => return Ok(()),
            }
        }
    };
    link.write_all(frame).map_err(IoError::Link)?;
    link.flush().map_err(IoError::Link)
}
