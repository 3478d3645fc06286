//! The firmware's protocol loop, board-independent: bytes in from the link
//! UART, one answer per frame out on the same UART, NMEA sentences for every
//! solved epoch out on the second UART (SPEC §11, docs/PROTOCOL.md).
//!
//! It lives here rather than in `firmware/` so that the host can unit-test
//! every answer (sequence gaps, errors, counters) without an emulator; the
//! firmware only supplies the UARTs (`embedded_io::Write`) and a
//! [`Platform`] (a tick counter and the stack high-water mark).

pub mod araim;

use embedded_io::Write;
use raim_core::{Config, Epoch, EpochResult, Raim};
use serde::Serialize;

use crate::error::WireError;
use crate::frame::{encode, FrameError, FrameReceiver};
use crate::lock::{config_fingerprint, ConfigId};
#[cfg(doc)]
use crate::message::Response;
use crate::message::{Command, Request, ResetCause, ResponseBody, Status, TestFault};
use crate::nmea;
use crate::result::WireResult;
use crate::{
    CAPACITY, MAX_REQUEST_FRAME, MAX_RESPONSE_FRAME, MAX_RESPONSE_PAYLOAD, PROTOCOL_VERSION,
};

// Particle-filter RAIM (issue 14): a child module, so it reaches the
// server's fields while its code stays out of this file.
#[path = "server_pf.rs"]
mod pf;
pub use pf::{map_error as pf_error, PfEngines, PfUnit};
#[cfg(feature = "pf")]
pub use pf::{EkfEngine, Ga100Engine, Ga300Engine, Pf100Engine, Pf300Engine, PfT};

/// What the board provides besides the UARTs.
pub trait Platform {
    /// A free-running tick counter (any rate); wraps at `TICK_MASK + 1`.
    fn now(&mut self) -> u32;
    /// Mask of the counter's valid bits (SysTick: 24 bits).
    const TICK_MASK: u32 = u32::MAX;
    /// Deepest stack use so far, bytes (0 if not measured).
    fn stack_high_water_bytes(&mut self) -> u32 {
        0
    }
    /// Resets since power-on and the cause of the last one (issue 15).
    fn reset_record(&mut self) -> (u32, ResetCause) {
        (0, ResetCause::PowerOn)
    }
    /// Carry out a test-only fault (hang, panic); `false` when the build
    /// has no test hooks (the server then answers `TestHooksDisabled`).
    /// Honoured, it does not return.
    fn test_fault(&mut self, _fault: TestFault) -> bool {
        false
    }
    /// Called after every epoch with its decision, or `None` when it was
    /// answered with a typed error, before the answer goes out (the
    /// integrity-alarm output, `alert`).
    fn on_epoch(&mut self, _decision: Option<raim_core::Decision>) {}
    /// Fills the board's fields of a `Status` (link counters, the alarm
    /// output, the key) before it is sent.
    fn board_status(&mut self, _status: &mut Status) {}
}

/// A platform without a clock (host tests).
pub struct NoPlatform;
impl Platform for NoPlatform {
    fn now(&mut self) -> u32 {
        0
    }
}

/// The protocol state: receive buffer, engine, configuration, counters, the
/// transmit buffers, and the last request, result and wire result (kept
/// here rather than on the stack, issue 10). The firmware keeps it in a
/// static (BENCHMARKS.md, "Issue 10: stack, second pass").
pub struct Server {
    rx: FrameReceiver<MAX_REQUEST_FRAME>,
    raim: Raim<CAPACITY>,
    config: Config,
    expected_seq: Option<u32>,
    /// Fingerprint of `config` and the lock (issue 15; `lock`).
    config_id: ConfigId,
    /// The authentication key and the last counter accepted (`auth`).
    auth: Option<(crate::auth::AuthKey, Option<u64>)>,
    status: Status,
    /// The ISM in force and the ARAIM engines (issue 12; `server/araim.rs`).
    araim: araim::AraimState,
    scratch: [u8; MAX_RESPONSE_PAYLOAD],
    out: [u8; MAX_RESPONSE_FRAME],
    /// The last request decoded (`on_byte`): decoded here rather than on
    /// the stack (issue 10).
    request: Option<Request>,
    /// The last epoch's result (`Raim::process_into`) and its wire form,
    /// both written in place (issue 10).
    result: EpochResult<CAPACITY>,
    wire: WireResult,
    /// The PF configuration and the engines lent by the owner
    /// (`attach_pf`; a few pointers, the engines stay where they are).
    pf: PfUnit,
}

impl Default for Server {
    fn default() -> Self {
        Self::new()
    }
}

/// Either UART failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IoError<L, M> {
    Link(L),
    Nmea(M),
}

impl Server {
    pub fn new() -> Self {
        Server {
            rx: FrameReceiver::new(),
            raim: Raim::new(),
            config: Config::default(),
            expected_seq: None,
            config_id: ConfigId {
                crc32: config_fingerprint(&Config::default()),
                locked: false,
            },
            auth: None,
            status: Status {
                protocol_version: PROTOCOL_VERSION,
                capacity: CAPACITY as u16,
                ..Status::default()
            },
            araim: araim::AraimState::new(),
            scratch: [0; MAX_RESPONSE_PAYLOAD],
            out: [0; MAX_RESPONSE_FRAME],
            request: None,
            result: EpochResult::empty(),
            wire: WireResult::empty(),
            pf: PfUnit::EMPTY,
        }
    }

    /// A server that boots with `config` locked in (a build whose
    /// configuration is compiled in): `Configure` is refused from the first
    /// frame. The configuration must pass `Config::validate`.
    pub fn new_locked(config: Config) -> Result<Self, raim_core::RaimError> {
        config.validate()?;
        let mut s = Server::new();
        s.config = config;
        s.config_id = ConfigId {
            crc32: config_fingerprint(&config),
            locked: true,
        };
        Ok(s)
    }

    /// A server that accepts configurations only authenticated with `key`
    /// (`auth`): plain `Configure` is refused with `AuthRequired`.
    pub fn with_auth_key(key: crate::auth::AuthKey) -> Self {
        let mut s = Server::new();
        s.auth = Some((key, None));
        s
    }

    /// Make this server take only configurations authenticated with
    /// `key` from now on, as `with_auth_key` (the firmware provisions its
    /// static server in place at boot, without a second server on the
    /// stack).
    pub fn set_auth_key(&mut self, key: crate::auth::AuthKey) {
        self.auth = Some((key, None));
    }

    pub fn status(&self) -> Status {
        Status {
            config: self.config_id,
            ..self.status
        }
    }

    /// The fingerprint of the configuration in force and the lock state.
    pub fn config_id(&self) -> ConfigId {
        self.config_id
    }

    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Feed one received byte; writes the answers (and NMEA) when it
    /// completes a frame.
    ///
    /// Storage (issue 10, the firmware's stack): the request is decoded
    /// into the server's own `request` slot (by `decode`, whose frame is
    /// gone before the epoch runs), a range or linear epoch is answered
    /// from references into it with the wire result written in place
    /// (`wire`), and answers are encoded from references (`ResponseRef`):
    /// no request-, result- or answer-sized value is on the stack of the
    /// epoch path.
    pub fn on_byte<L: Write, M: Write, P: Platform>(
        &mut self,
        byte: u8,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M::Error>> {
        let decoded: Result<u32, (Option<u32>, WireError)> = match self.rx.push(byte) {
            None => return Ok(()),
            Some(Err(e)) => Err((None, WireError::from(e))),
            Some(Ok(payload)) => decode(payload, &mut self.request),
        };
        self.status.frames = self.status.frames.wrapping_add(1);
        let seq = match decoded {
            Ok(seq) => seq,
            Err((seq, e)) => {
                if let Some(s) = seq {
                    self.check_sequence(s, link)?;
                }
                return self.send(link, seq, BodyRef::Error(&e));
            }
        };
        self.check_sequence(seq, link)?;
        match self.request.as_ref().map(|r| &r.command) {
            Some(Command::Ranges(_) | Command::Linear(_)) => {
                self.answer_epoch(seq, link, nmea_out, platform)
            }
            Some(Command::Araim(
                crate::araim_msg::AraimCommand::Epoch(_)
                | crate::araim_msg::AraimCommand::Ranges(_),
            )) => self.answer_araim_epoch(seq, link, platform),
            _ => self.answer_other(seq, link, platform),
        }
    }

    /// A `Ranges` or `Linear` request (in `self.request`): the epoch, its
    /// NMEA sentences and the answer, the result written into `self.wire`.
    #[inline(never)]
    fn answer_epoch<L: Write, M: Write, P: Platform>(
        &mut self,
        seq: u32,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M::Error>> {
        let outcome = {
            let Server {
                request,
                raim,
                config,
                status,
                result,
                wire,
                ..
            } = self;
            let slots = (&mut *result, &mut *wire);
            match request.as_ref().map(|r| &r.command) {
                Some(Command::Ranges(e)) if e.sats.overflowed() => {
                    Err(too_many(e.sats.declared, platform))
                }
                Some(Command::Linear(e)) if e.sats.overflowed() => {
                    Err(too_many(e.sats.declared, platform))
                }
                Some(Command::Ranges(e)) => run_epoch(
                    raim,
                    config,
                    status,
                    slots,
                    &Epoch::ranges(e.time_s, &e.sats.items, e.apriori_m),
                    platform,
                ),
                Some(Command::Linear(e)) => run_epoch(
                    raim,
                    config,
                    status,
                    slots,
                    &Epoch::linear(e.time_s, &e.sats.items),
                    platform,
                ),
                // `on_byte` sends only epochs here.
                _ => return Ok(()),
            }
        };
        match outcome {
            Ok(()) => {
                write_nmea(&self.wire, self.request.as_ref(), nmea_out).map_err(IoError::Nmea)?;
                let Server {
                    scratch,
                    out,
                    status,
                    config_id,
                    wire,
                    ..
                } = self;
                send_answer(
                    Buffers {
                        scratch,
                        out,
                        status,
                        config: *config_id,
                    },
                    link,
                    Some(seq),
                    BodyRef::Result(wire),
                )
            }
            Err(e) => self.send(link, Some(seq), BodyRef::Error(&e)),
        }
    }
    /// Every request but a range or linear epoch: taken out of
    /// `self.request` (this frame holds the request and the answer; the
    /// epoch path does not pass through here).
    #[inline(never)]
    fn answer_other<L: Write, M, P: Platform>(
        &mut self,
        seq: u32,
        link: &mut L,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M>> {
        let Some(request) = self.request.take() else {
            return Ok(());
        };
        let body = match request.command {
            Command::Status => {
                self.status.stack_high_water_bytes = platform.stack_high_water_bytes();
                (self.status.resets, self.status.reset_cause) = platform.reset_record();
                self.status.auth_provisioned = self.auth.is_some();
                platform.board_status(&mut self.status);
                ResponseBody::Status(self.status())
            }
            Command::TestFault(f) => {
                let _ = platform.test_fault(f);
                ResponseBody::Error(WireError::TestHooksDisabled)
            }
            Command::Configure(_) if self.config_id.locked => {
                ResponseBody::Error(WireError::Locked {
                    config_crc32: self.config_id.crc32,
                })
            }
            Command::Configure(_) if self.auth.is_some() => {
                ResponseBody::Error(WireError::AuthRequired)
            }
            Command::Configure(c) => self.apply(c),
            Command::AuthConfigure(_) if self.config_id.locked => {
                ResponseBody::Error(WireError::Locked {
                    config_crc32: self.config_id.crc32,
                })
            }
            Command::AuthConfigure(a) => match self.auth {
                None => ResponseBody::Error(WireError::AuthNotProvisioned),
                Some((key, last)) => {
                    if !crate::auth::verify(&key, a.counter, &a.config, &a.tag) {
                        ResponseBody::Error(WireError::BadAuthTag { counter: a.counter })
                    } else if let Some(l) = last.filter(|&l| a.counter <= l) {
                        ResponseBody::Error(WireError::Replayed {
                            counter: a.counter,
                            last: l,
                        })
                    } else {
                        let body = self.apply(a.config);
                        if body == ResponseBody::Configured {
                            self.auth = Some((key, Some(a.counter)));
                        }
                        body
                    }
                }
            },
            Command::Lock => {
                self.config_id.locked = true;
                ResponseBody::LockEngaged
            }
            // Epochs are answered by `answer_epoch`.
            Command::Ranges(_) | Command::Linear(_) => return Ok(()),
            Command::Araim(c) => self.araim(c, platform),
            Command::PfConfigure(_) if self.config_id.locked => {
                ResponseBody::Error(WireError::Locked {
                    config_crc32: self.config_id.crc32,
                })
            }
            Command::PfConfigure(_) if self.auth.is_some() => {
                ResponseBody::Error(WireError::AuthRequired)
            }
            Command::PfConfigure(c) => self.pf_configure(c),
            Command::PfRanges(e) if e.sats.overflowed() => {
                ResponseBody::Error(too_many(e.sats.declared, platform))
            }
            Command::PfRanges(e) => self.pf_epoch(e.time_s, &e.sats.items, platform),
        };
        self.send(link, Some(seq), BodyRef::from(&body))
    }

    /// Validate and take a configuration.
    fn apply(&mut self, c: Config) -> ResponseBody {
        match c.validate() {
            Ok(()) => {
                self.config = c;
                // Covers the ISM and the PF configuration in force too.
                self.config_id.crc32 = self.fingerprint();
                ResponseBody::Configured
            }
            Err(e) => ResponseBody::Error(e.into()),
        }
    }

    /// A jump in the sequence numbers is reported as a notice before the
    /// answer (which still follows).
    fn check_sequence<L: Write, M>(
        &mut self,
        seq: u32,
        link: &mut L,
    ) -> Result<(), IoError<L::Error, M>> {
        let expected = self.expected_seq.replace(seq.wrapping_add(1));
        match expected {
            Some(e) if e != seq => self.send(
                link,
                Some(seq),
                BodyRef::Error(&WireError::SequenceGap {
                    expected: e,
                    received: seq,
                }),
            ),
            _ => Ok(()),
        }
    }

    fn send<L: Write, M>(
        &mut self,
        link: &mut L,
        seq: Option<u32>,
        body: BodyRef<'_>,
    ) -> Result<(), IoError<L::Error, M>> {
        let Server {
            scratch,
            out,
            status,
            config_id,
            ..
        } = self;
        send_answer(
            Buffers {
                scratch,
                out,
                status,
                config: *config_id,
            },
            link,
            seq,
            body,
        )
    }
}

/// One epoch through the engine; the result written into `result` and
/// its wire form into `wire`, or the typed error. The platform hears the
/// verdict.
fn run_epoch<P: Platform>(
    raim: &mut Raim<CAPACITY>,
    config: &Config,
    status: &mut Status,
    (result, wire): (&mut EpochResult<CAPACITY>, &mut WireResult),
    epoch: &Epoch<'_>,
    platform: &mut P,
) -> Result<(), WireError> {
    status.epochs = status.epochs.wrapping_add(1);
    let t0 = platform.now();
    let r = raim.process_into(config, epoch, result);
    let t1 = platform.now();
    status.last_epoch_ticks = t1.wrapping_sub(t0) & P::TICK_MASK;
    platform.on_epoch(r.as_ref().ok().map(|()| result.decision));
    match r {
        Ok(()) => {
            wire.set_from_result(result);
            Ok(())
        }
        Err(e) => Err(e.into()),
    }
}

/// The epoch's NMEA sentences, written one at a time as they are formed.
/// Its own frame, not on the epoch's path (issue 10). The request is the
/// epoch's (the satellites seen, for GSV and the DOPs).
#[inline(never)]
fn write_nmea<M: Write>(
    wire: &WireResult,
    request: Option<&Request>,
    nmea_out: &mut M,
) -> Result<(), M::Error> {
    let epoch = match request.map(|r| &r.command) {
        Some(Command::Ranges(e)) => Epoch::ranges(e.time_s, &e.sats.items, e.apriori_m),
        Some(Command::Linear(e)) => Epoch::linear(e.time_s, &e.sats.items),
        _ => return Ok(()),
    };
    nmea::write_epoch(
        wire,
        &nmea::Sky::new(&epoch),
        nmea::BUILT,
        &mut |s: &nmea::Sentence| nmea_out.write_all(s.as_bytes()),
    )?;
    nmea_out.flush()
}

/// Decode a request payload into `slot`; its sequence number, or the
/// error answer (with the sequence number when the payload starts with
/// one). Its own frame, not inlined: the decoder's temporaries are gone
/// before the request is acted on (issue 10).
#[inline(never)]
fn decode(payload: &[u8], slot: &mut Option<Request>) -> Result<u32, (Option<u32>, WireError)> {
    *slot = None;
    match postcard::from_bytes::<Request>(payload) {
        Ok(r) => {
            let seq = r.seq;
            *slot = Some(r);
            Ok(seq)
        }
        Err(_) => {
            let seq = postcard::take_from_bytes::<u32>(payload)
                .ok()
                .map(|(s, _)| s);
            let len = u32::try_from(payload.len()).unwrap_or(u32::MAX);
            Err((seq, WireError::from(FrameError::Undecodable { len })))
        }
    }
}

/// The server's transmit buffers and counters, borrowed apart from the
/// rest of the server so that an answer can be encoded from a reference
/// into the server (`BodyRef::Result(&self.wire)`).
struct Buffers<'a> {
    scratch: &'a mut [u8; MAX_RESPONSE_PAYLOAD],
    out: &'a mut [u8; MAX_RESPONSE_FRAME],
    status: &'a mut Status,
    config: ConfigId,
}

/// A [`ResponseBody`] by reference: encodes byte for byte as the
/// `ResponseBody` of the same variant (postcard writes an enum as its
/// variant index, then the payload; `&T` serializes as `T`; the variants
/// are in the same order: test `body_ref_encodes_as_response_body`).
#[derive(Serialize)]
enum BodyRef<'a> {
    Result(&'a WireResult),
    Configured,
    Status(&'a Status),
    Error(&'a WireError),
    LockEngaged,
    Araim(&'a crate::araim_msg::AraimAnswer),
    PfResult(&'a crate::pf_msg::WirePfResult),
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
        }
    }
}

/// A [`Response`] by reference (same encoding, field for field).
#[derive(Serialize)]
struct ResponseRef<'a> {
    seq: Option<u32>,
    body: BodyRef<'a>,
    config: ConfigId,
}

/// Encode and write one answer. Its own frame (the fallback answer), not
/// on the epoch's path (issue 10).
#[inline(never)]
fn send_answer<L: Write, M>(
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

/// An epoch with more satellites than the capacity: an epoch answered
/// with an error, for the alarm output too.
fn too_many<P: Platform>(declared: u32, platform: &mut P) -> WireError {
    platform.on_epoch(None);
    WireError::TooManySatellites {
        have: declared,
        capacity: CAPACITY as u32,
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::message::{CommandRef, RequestRef, Response};
    use raim_core::{FiRule, LinearObservation, RangeObservation, SatId, System};
    use std::vec::Vec;

    /// A byte sink for the tests.
    #[derive(Default)]
    struct Sink(Vec<u8>);
    impl embedded_io::ErrorType for Sink {
        type Error = core::convert::Infallible;
    }
    impl Write for Sink {
        fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
            self.0.extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> Result<(), Self::Error> {
            Ok(())
        }
    }

    fn frame(req: &RequestRef<'_>) -> Vec<u8> {
        let mut scratch = [0u8; 4096];
        let mut out = [0u8; 4096];
        encode(req, &mut scratch, &mut out).unwrap().to_vec()
    }

    fn responses(bytes: &[u8]) -> Vec<Response> {
        let mut rx = FrameReceiver::<MAX_RESPONSE_FRAME>::new();
        bytes
            .iter()
            .filter_map(|&b| {
                rx.push(b)
                    .map(|p| postcard::from_bytes::<Response>(p.unwrap()).unwrap())
            })
            .collect()
    }

    fn run(server: &mut Server, bytes: &[u8]) -> (Vec<Response>, std::string::String) {
        let (mut link, mut nmea) = (Sink::default(), Sink::default());
        for &b in bytes {
            server
                .on_byte(b, &mut link, &mut nmea, &mut NoPlatform)
                .unwrap();
        }
        (
            responses(&link.0),
            std::string::String::from_utf8(nmea.0).unwrap(),
        )
    }

    fn sky(step_m: f64) -> Vec<LinearObservation> {
        let sky = [
            (0.0, 85.0),
            (45.0, 30.0),
            (100.0, 50.0),
            (150.0, 20.0),
            (200.0, 60.0),
            (250.0, 25.0),
            (300.0, 40.0),
            (340.0, 15.0),
        ];
        sky.iter()
            .enumerate()
            .map(|(i, &(az, el)): (usize, &(f64, f64))| {
                let r = if i == 1 { step_m } else { 0.1 * i as f64 - 0.3 };
                let mut o = LinearObservation::from_az_el(
                    SatId::new(System::Gps, i as u8 + 1),
                    az.to_radians(),
                    el.to_radians(),
                    r,
                );
                o.sigma_m = Some(1.0);
                o
            })
            .collect()
    }

    #[test]
    fn every_frame_is_answered_in_order_with_its_sequence_number() {
        let mut server = Server::new();
        let s0 = sky(0.0);
        let s1 = sky(50.0);
        let mut bytes = frame(&RequestRef::linear(0, 0.0, &s0));
        bytes.extend(frame(&RequestRef::linear(1, 1.0, &s1)));
        bytes.extend(frame(&RequestRef {
            seq: 2,
            command: CommandRef::Status,
        }));
        let (resp, nmea) = run(&mut server, &bytes);
        assert_eq!(resp.len(), 3);
        assert_eq!(
            resp.iter().map(|r| r.seq).collect::<Vec<_>>(),
            [Some(0), Some(1), Some(2)]
        );
        let ResponseBody::Result(r1) = &resp[1].body else {
            panic!("{:?}", resp[1])
        };
        assert_eq!(r1.exclusions[0].id, SatId::new(System::Gps, 2));
        // The same result as the core on the host, bit for bit.
        let direct = Raim::<CAPACITY>::new()
            .process(&Config::default(), &Epoch::linear(1.0, &s1))
            .unwrap();
        assert_eq!(*r1, WireResult::from_result(&direct));
        let ResponseBody::Status(st) = resp[2].body else {
            panic!()
        };
        assert_eq!(
            (st.frames, st.epochs, st.errors, st.capacity),
            (3, 2, 0, 32)
        );
        // Nine sentences per solved epoch of 8 GPS satellites, in order.
        let kinds: Vec<&str> = nmea.lines().map(|l| &l[3..6]).collect();
        let one = [
            "RMC", "VTG", "GGA", "GSA", "GSV", "GSV", "GST", "GBS", "ZDA",
        ];
        assert_eq!(kinds, [one, one].concat());
        // The host's writer on the same epoch, byte for byte.
        let want: std::string::String =
            nmea::epoch_sentences(r1, &nmea::Sky::new(&Epoch::linear(1.0, &s1)), nmea::BUILT)
                .unwrap()
                .iter()
                .map(|s| s.as_str())
                .collect();
        assert!(nmea.ends_with(&want), "{nmea}");
    }

    #[test]
    fn typed_errors_for_each_kind_of_bad_frame() {
        let mut server = Server::new();
        let good = sky(0.0);
        let mut nan = sky(0.0);
        nan[3].residual_m = f64::NAN;
        let many: Vec<LinearObservation> = (0..40)
            .map(|i| LinearObservation {
                id: SatId::new(System::Gps, i),
                ..good[0]
            })
            .collect();
        let degenerate: Vec<RangeObservation> = (0..6)
            .map(|i| RangeObservation {
                id: SatId::new(System::Gps, i + 1),
                pseudorange_m: 2.0e7,
                position_m: [2.0e7, 0.0, 0.0],
                sigma_m: Some(1.0),
            })
            .collect();
        let bad_cfg = Config {
            rule: FiRule::LraimGaussian { kappa: -1.0 },
            ..Config::default()
        };
        // A frame whose CRC does not match its payload.
        let mut payload = [0u8; 4096];
        let payload = postcard::to_slice(&RequestRef::linear(3, 0.0, &good), &mut payload).unwrap();
        let env = crate::frame::Envelope {
            crc32: crate::frame::CRC32.checksum(payload) ^ 1,
            payload,
        };
        let mut out = [0u8; 4096];
        let corrupted = postcard::to_slice_cobs(&env, &mut out).unwrap().to_vec();
        let mut bytes = Vec::new();
        bytes.extend(frame(&RequestRef::linear(0, 0.0, &nan)));
        bytes.extend(frame(&RequestRef::linear(1, 0.0, &many)));
        bytes.extend(frame(&RequestRef::ranges(2, 0.0, None, &degenerate)));
        bytes.extend(&corrupted);
        bytes.extend([0x01, 0x01, 0x00]); // valid COBS, not an envelope
        bytes.extend(frame(&RequestRef {
            seq: 5,
            command: CommandRef::Configure(&bad_cfg),
        }));
        bytes.extend(std::vec![0x11; MAX_REQUEST_FRAME + 5]);
        bytes.push(0);
        bytes.extend(frame(&RequestRef {
            seq: 6,
            command: CommandRef::Status,
        }));
        let (resp, nmea) = run(&mut server, &bytes);
        assert!(nmea.is_empty());
        let got: Vec<(Option<u32>, &str)> = resp
            .iter()
            .map(|r| {
                let ResponseBody::Error(e) = &r.body else {
                    return (r.seq, "ok");
                };
                let kind = match e {
                    WireError::NonFinite { .. } => "nonfinite",
                    WireError::TooManySatellites {
                        have: 40,
                        capacity: 32,
                    } => "toomany",
                    WireError::DegenerateGeometry { .. } => "degenerate",
                    WireError::BadCrc { .. } => "crc",
                    WireError::Undecodable { .. } => "undecodable",
                    WireError::SequenceGap {
                        expected: 3,
                        received: 5,
                    } => "gap",
                    WireError::OutOfRange { field, .. } if field.as_str() == "kappa" => "range",
                    WireError::Overflow { .. } => "overflow",
                    other => panic!("{other:?}"),
                };
                (r.seq, kind)
            })
            .collect();
        assert_eq!(
            got,
            [
                (Some(0), "nonfinite"),
                (Some(1), "toomany"),
                (Some(2), "degenerate"),
                (None, "crc"),
                (None, "undecodable"),
                (Some(5), "gap"),
                (Some(5), "range"),
                (None, "overflow"),
                (Some(6), "ok"),
            ]
        );
        // The bad configuration did not replace the good one.
        assert_eq!(*server.config(), Config::default());
        let ResponseBody::Status(st) = resp[8].body else {
            panic!()
        };
        assert_eq!((st.frames, st.errors), (8, 8));
    }

    /// Issue 10: the answers are encoded from references (`ResponseRef`);
    /// the bytes are those of the owned `Response`, variant by variant.
    #[test]
    fn body_ref_encodes_as_response_body() {
        let direct = Raim::<CAPACITY>::new()
            .process(&Config::default(), &Epoch::linear(1.0, &sky(50.0)))
            .unwrap();
        let mut server = Server::new();
        let (st, _) = run(
            &mut server,
            &frame(&RequestRef {
                seq: 0,
                command: CommandRef::Status,
            }),
        );
        let ResponseBody::Status(status) = st[0].body else {
            panic!()
        };
        let bodies = [
            ResponseBody::Result(WireResult::from_result(&direct)),
            ResponseBody::Configured,
            ResponseBody::Status(status),
            ResponseBody::Error(WireError::SequenceGap {
                expected: 3,
                received: 5,
            }),
            ResponseBody::LockEngaged,
        ];
        fn enc<T: Serialize>(x: &T) -> Vec<u8> {
            let mut b = std::vec![0u8; MAX_RESPONSE_PAYLOAD];
            postcard::to_slice(x, &mut b).unwrap().to_vec()
        }
        for (i, body) in bodies.iter().enumerate() {
            let config = ConfigId {
                crc32: 0xDEAD_BEEF,
                locked: i % 2 == 0,
            };
            let seq = Some(i as u32);
            let owned = enc(&Response {
                seq,
                body: body.clone(),
                config,
            });
            let by_ref = enc(&ResponseRef {
                seq,
                body: BodyRef::from(body),
                config,
            });
            assert_eq!(owned, by_ref, "{body:?}");
        }
    }

    /// Issue 15: after `Lock` every `Configure` is refused with `Locked`
    /// carrying the fingerprint in force, the configuration in force stays,
    /// and every answer carries the fingerprint and the lock state.
    #[test]
    fn a_locked_server_refuses_configure() {
        use raim_core::Phase;
        let terminal = Config::preset(Phase::Terminal);
        let (fp_default, fp_terminal) = (
            crate::config_fingerprint(&Config::default()),
            crate::config_fingerprint(&terminal),
        );
        assert_ne!(fp_default, fp_terminal);
        let mut server = Server::new();
        let default_cfg = Config::default();
        let req = |seq, command| frame(&RequestRef { seq, command });
        let s1 = sky(50.0);
        let mut bytes = req(0, CommandRef::Status);
        bytes.extend(req(1, CommandRef::Configure(&terminal)));
        bytes.extend(req(2, CommandRef::Lock));
        bytes.extend(req(3, CommandRef::Configure(&default_cfg)));
        bytes.extend(req(4, CommandRef::Lock));
        bytes.extend(frame(&RequestRef::linear(5, 1.0, &s1)));
        bytes.extend(req(6, CommandRef::Status));
        let (resp, _) = run(&mut server, &bytes);
        assert_eq!(resp.len(), 7);
        let id = |crc32, locked| ConfigId { crc32, locked };
        let ResponseBody::Status(st0) = resp[0].body else {
            panic!("{:?}", resp[0])
        };
        assert_eq!(st0.config, id(fp_default, false));
        assert_eq!(st0.protocol_version, PROTOCOL_VERSION);
        assert_eq!(resp[1].body, ResponseBody::Configured);
        assert_eq!(resp[1].config, id(fp_terminal, false));
        assert_eq!(resp[2].body, ResponseBody::LockEngaged);
        assert_eq!(resp[2].config, id(fp_terminal, true));
        assert_eq!(
            resp[3].body,
            ResponseBody::Error(WireError::Locked {
                config_crc32: fp_terminal
            })
        );
        assert_eq!(resp[4].body, ResponseBody::LockEngaged);
        let ResponseBody::Result(r) = &resp[5].body else {
            panic!("{:?}", resp[5])
        };
        assert_eq!(resp[5].config, id(fp_terminal, true));
        // The result is the locked (terminal) configuration's.
        let direct = Raim::<CAPACITY>::new()
            .process(&terminal, &Epoch::linear(1.0, &s1))
            .unwrap();
        assert_eq!(*r, WireResult::from_result(&direct));
        let ResponseBody::Status(st) = resp[6].body else {
            panic!()
        };
        assert_eq!(st.config, id(fp_terminal, true));
        assert_eq!(*server.config(), terminal);
        // Only a reset (a new server) unlocks.
        assert!(!Server::new().config_id().locked);
    }

    /// A build with its configuration compiled in refuses `Configure` from
    /// the first frame, and refuses to boot with an invalid configuration.
    #[test]
    fn a_compiled_in_configuration_is_locked_from_boot() {
        let cfg = Config::preset(raim_core::Phase::EnRoute);
        let mut server = Server::new_locked(cfg).unwrap();
        let bytes = frame(&RequestRef {
            seq: 0,
            command: CommandRef::Configure(&Config::default()),
        });
        let (resp, _) = run(&mut server, &bytes);
        let fp = crate::config_fingerprint(&cfg);
        assert_eq!(
            resp[0].body,
            ResponseBody::Error(WireError::Locked { config_crc32: fp })
        );
        assert_eq!(
            resp[0].config,
            ConfigId {
                crc32: fp,
                locked: true
            }
        );
        let bad = Config { pfa: 1e-300, ..cfg };
        assert!(matches!(
            Server::new_locked(bad),
            Err(raim_core::RaimError::OutOfRange { field: "pfa", .. })
        ));
    }

    /// Issue 15: `Status` carries the platform's reset count and cause; a
    /// test fault on a platform without test hooks is refused, typed.
    #[test]
    fn status_reports_the_reset_record_and_test_hooks_are_off_by_default() {
        struct Rebooted;
        impl Platform for Rebooted {
            fn now(&mut self) -> u32 {
                0
            }
            fn reset_record(&mut self) -> (u32, ResetCause) {
                (3, ResetCause::Watchdog { pc: 0x1234 })
            }
        }
        let mut server = Server::new();
        let mut bytes = frame(&RequestRef {
            seq: 0,
            command: CommandRef::Status,
        });
        bytes.extend(frame(&RequestRef {
            seq: 1,
            command: CommandRef::TestFault(TestFault::Hang),
        }));
        let (mut link, mut nmea) = (Sink::default(), Sink::default());
        for &b in &bytes {
            server
                .on_byte(b, &mut link, &mut nmea, &mut Rebooted)
                .unwrap();
        }
        let resp = responses(&link.0);
        let ResponseBody::Status(st) = resp[0].body else {
            panic!("{:?}", resp[0])
        };
        assert_eq!(
            (st.resets, st.reset_cause),
            (3, ResetCause::Watchdog { pc: 0x1234 })
        );
        assert_eq!(
            resp[1].body,
            ResponseBody::Error(WireError::TestHooksDisabled)
        );
        // The host-test platform keeps no record: power-on.
        let (resp, _) = run(
            &mut Server::new(),
            &frame(&RequestRef {
                seq: 0,
                command: CommandRef::Status,
            }),
        );
        let ResponseBody::Status(st) = resp[0].body else {
            panic!()
        };
        assert_eq!((st.resets, st.reset_cause), (0, ResetCause::PowerOn));
    }

    /// Issue 15: the platform hears every epoch's verdict (typed errors as
    /// `None`, too-many-satellites included) and fills its Status fields;
    /// Status tells whether a key is provisioned.
    #[test]
    fn the_platform_hears_every_epoch_verdict_and_fills_status() {
        use crate::alert::{AlarmOutput, AlertMonitor};
        use raim_core::Decision;
        struct Discrete(AlertMonitor, u64);
        impl Platform for Discrete {
            fn now(&mut self) -> u32 {
                0
            }
            fn on_epoch(&mut self, decision: Option<Decision>) {
                self.1 += 1;
                self.0.on_epoch(self.1, decision);
            }
            fn board_status(&mut self, status: &mut Status) {
                status.alarm_output = self.0.output(self.1);
                status.alarm_pin_asserted = status.alarm_output.asserted();
                status.rx_ring_overflows = 7;
            }
        }
        let (ok, fault) = (sky(0.0), sky(50.0));
        let mut nan = sky(0.0);
        nan[0].residual_m = f64::NAN;
        let many: Vec<LinearObservation> = (0..40)
            .map(|i| LinearObservation {
                id: SatId::new(System::Gps, i),
                ..ok[0]
            })
            .collect();
        let status = |seq| {
            frame(&RequestRef {
                seq,
                command: CommandRef::Status,
            })
        };
        let mut bytes = status(0);
        bytes.extend(frame(&RequestRef::linear(1, 0.0, &ok)));
        bytes.extend(status(2));
        bytes.extend(frame(&RequestRef::linear(3, 1.0, &nan)));
        bytes.extend(status(4));
        bytes.extend(frame(&RequestRef::linear(5, 2.0, &fault)));
        bytes.extend(status(6));
        bytes.extend(frame(&RequestRef::linear(7, 3.0, &many)));
        bytes.extend(status(8));
        let mut server = Server::new();
        let mut p = Discrete(AlertMonitor::new(100), 0);
        let (mut link, mut nmea) = (Sink::default(), Sink::default());
        for &b in &bytes {
            server.on_byte(b, &mut link, &mut nmea, &mut p).unwrap();
        }
        let outputs: Vec<(AlarmOutput, bool, u32, bool)> = responses(&link.0)
            .iter()
            .filter_map(|r| match r.body {
                ResponseBody::Status(s) => Some((
                    s.alarm_output,
                    s.alarm_pin_asserted,
                    s.rx_ring_overflows,
                    s.auth_provisioned,
                )),
                _ => None,
            })
            .collect();
        // The 50 m fault on one of 8 satellites is excluded: valid.
        assert_eq!(
            outputs,
            [
                (AlarmOutput::NoValidEpoch, true, 7, false),
                (AlarmOutput::Clear, false, 7, false),
                (AlarmOutput::EpochError, true, 7, false),
                (AlarmOutput::Clear, false, 7, false),
                (AlarmOutput::EpochError, true, 7, false),
            ]
        );
        assert_eq!(p.1, 4);
        let mut keyed = Server::with_auth_key([1; 32]);
        let (resp, _) = run(&mut keyed, &status(0));
        let ResponseBody::Status(st) = resp[0].body else {
            panic!()
        };
        assert!(st.auth_provisioned);
    }

    /// Issue 15: with a key, only an authenticated configuration with a
    /// fresh counter is taken; a replayed frame (the same bytes again), a
    /// forged tag, a stale counter and a plain `Configure` are refused,
    /// typed, and the configuration in force stays.
    #[test]
    fn authenticated_configure_refuses_replay_and_forgery() {
        use crate::auth::{tag, AuthConfigure};
        let key = [0x5Au8; 32];
        let terminal = Config::preset(raim_core::Phase::Terminal);
        let enroute = Config::preset(raim_core::Phase::EnRoute);
        let signed = |counter, config: Config| AuthConfigure {
            counter,
            config,
            tag: tag(&key, counter, &config),
        };
        let a1 = signed(1, terminal);
        let recorded = frame(&RequestRef {
            seq: 0,
            command: CommandRef::AuthConfigure(&a1),
        });
        let mut forged = signed(2, enroute);
        forged.tag[0] ^= 1;
        let stale = signed(1, enroute);
        let a3 = signed(3, enroute);
        let default_cfg = Config::default();
        let mut server = Server::with_auth_key(key);
        let mut bytes = recorded.clone();
        bytes.extend(recorded.clone()); // the recorded frame, replayed
        for (seq, command) in [
            (1, CommandRef::AuthConfigure(&forged)),
            (2, CommandRef::AuthConfigure(&stale)),
            (3, CommandRef::Configure(&default_cfg)),
        ] {
            bytes.extend(frame(&RequestRef { seq, command }));
        }
        let (resp, _) = run(&mut server, &bytes);
        let bodies: Vec<&ResponseBody> = resp
            .iter()
            .filter(|r| !matches!(r.body, ResponseBody::Error(WireError::SequenceGap { .. })))
            .map(|r| &r.body)
            .collect();
        assert_eq!(
            bodies,
            [
                &ResponseBody::Configured,
                &ResponseBody::Error(WireError::Replayed {
                    counter: 1,
                    last: 1
                }),
                &ResponseBody::Error(WireError::BadAuthTag { counter: 2 }),
                &ResponseBody::Error(WireError::Replayed {
                    counter: 1,
                    last: 1
                }),
                &ResponseBody::Error(WireError::AuthRequired),
            ]
        );
        assert_eq!(*server.config(), terminal);
        // A fresh counter is accepted; after Lock even that is refused.
        let mut bytes = frame(&RequestRef {
            seq: 4,
            command: CommandRef::AuthConfigure(&a3),
        });
        bytes.extend(frame(&RequestRef {
            seq: 5,
            command: CommandRef::Lock,
        }));
        let a4 = signed(4, terminal);
        bytes.extend(frame(&RequestRef {
            seq: 6,
            command: CommandRef::AuthConfigure(&a4),
        }));
        let (resp, _) = run(&mut server, &bytes);
        assert_eq!(resp[0].body, ResponseBody::Configured);
        assert_eq!(resp[1].body, ResponseBody::LockEngaged);
        assert!(matches!(
            resp[2].body,
            ResponseBody::Error(WireError::Locked { .. })
        ));
        assert_eq!(*server.config(), enroute);
        // Without a key, authenticated frames are refused, typed.
        let (resp, _) = run(
            &mut Server::new(),
            &frame(&RequestRef {
                seq: 0,
                command: CommandRef::AuthConfigure(&a3),
            }),
        );
        assert_eq!(
            resp[0].body,
            ResponseBody::Error(WireError::AuthNotProvisioned)
        );
    }
}
