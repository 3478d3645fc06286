//! raim-server: the RAIM unit's protocol loop, board-independent: bytes in
//! from the link UART, one answer per frame out on the same UART, NMEA
//! sentences for every solved epoch out on the second UART (SPEC §11,
//! docs/PROTOCOL.md). The frames and messages are the wire crate's
//! (`raim-proto`); this crate holds the engines and answers them.
//!
//! It is sans-IO and lives outside `firmware/` so that the host can
//! unit-test every answer (sequence gaps, errors, counters) without an
//! emulator; the firmware only supplies the UARTs (`embedded_io::Write`)
//! and a [`Platform`] (a tick counter and the stack high-water mark).
#![no_std]
#![forbid(unsafe_code)]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// `!(a < b)` is deliberate: it is true for NaN, so NaN never wins a
// comparison it should lose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub mod araim;

use embedded_io::Write;
use raim_core::{Config, Epoch, EpochResult, Raim};

use raim_proto::error::WireError;
use raim_proto::frame::FrameReceiver;
use raim_proto::lock::{config_fingerprint, ConfigId};
#[cfg(doc)]
use raim_proto::message::Response;
use raim_proto::message::{Command, Request, ResetCause, ResponseBody, Status, TestFault};
use raim_proto::result::WireResult;
use raim_proto::{
    DevicePrecision, CAPACITY, MAX_REQUEST_FRAME, MAX_RESPONSE_FRAME, MAX_RESPONSE_PAYLOAD,
    PROTOCOL_VERSION,
};

mod answer;
mod gate;

use answer::{send_answer, BodyRef, Buffers};
use gate::Change;

// Particle-filter RAIM (issue 14): a child module, so it reaches the
// server's fields while its code stays out of this file.
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
    raim: Raim<CAPACITY, DevicePrecision>,
    config: Config,
    expected_seq: Option<u32>,
    /// Fingerprint of `config` and the lock (issue 15; `lock`).
    config_id: ConfigId,
    /// The authentication key and the last counter accepted (`auth`).
    auth: Option<(raim_proto::auth::AuthKey, Option<u64>)>,
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
    pub fn with_auth_key(key: raim_proto::auth::AuthKey) -> Self {
        let mut s = Server::new();
        s.auth = Some((key, None));
        s
    }

    /// Make this server take only configurations authenticated with
    /// `key` from now on, as `with_auth_key` (the firmware provisions its
    /// static server in place at boot, without a second server on the
    /// stack).
    pub fn set_auth_key(&mut self, key: raim_proto::auth::AuthKey) {
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
    /// The request is decoded once, into the server's own `request` slot,
    /// and checked once (`answer::decode`); [`Server::dispatch`] then
    /// answers it. Epochs are answered from references into that slot with
    /// the wire result written in place, and answers are encoded from
    /// references (`answer::ResponseRef`): no request-, result- or
    /// answer-sized value is on the stack of the epoch path.
    pub fn on_byte<L: Write, M: Write, P: Platform>(
        &mut self,
        byte: u8,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M::Error>> {
        let decoded = match self.rx.push(byte) {
            None => return Ok(()),
            Some(Err(e)) => Err(answer::Refusal {
                seq: None,
                error: WireError::from(e),
                epoch: false,
            }),
            Some(Ok(payload)) => answer::decode(payload, &mut self.request),
        };
        self.status.frames = self.status.frames.wrapping_add(1);
        match decoded {
            Ok(seq) => {
                self.check_sequence(seq, link)?;
                self.dispatch(seq, link, nmea_out, platform)
            }
            Err(refusal) => {
                if let Some(s) = refusal.seq {
                    self.check_sequence(s, link)?;
                }
                if refusal.epoch {
                    platform.on_epoch(None);
                }
                self.send(link, refusal.seq, BodyRef::Error(&refusal.error))
            }
        }
    }

    /// Answers the request in `self.request`: the one place where a
    /// request kind meets its handler. Epochs are answered from references
    /// into the request slot; every other request is taken out of it.
    fn dispatch<L: Write, M: Write, P: Platform>(
        &mut self,
        seq: u32,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M::Error>> {
        use raim_proto::araim_msg::AraimCommand;
        let Some(command) = self.request.as_ref().map(|r| &r.command) else {
            return Ok(());
        };
        match command {
            Command::Ranges(_) | Command::Linear(_) => {
                self.answer_epoch(seq, link, nmea_out, platform)
            }
            Command::Araim(AraimCommand::Epoch(_) | AraimCommand::Ranges(_)) => {
                self.answer_araim_epoch(seq, link, platform)
            }
            _ => self.answer_other(seq, link, platform),
        }
    }

    /// Every request but an epoch answered from the request slot: taken
    /// out of the slot, in a frame of its own so that the request-sized
    /// value is not on the stack of the epoch path.
    #[inline(never)]
    fn answer_other<L: Write, M, P: Platform>(
        &mut self,
        seq: u32,
        link: &mut L,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M>> {
        use raim_proto::araim_msg::AraimCommand;
        let Some(request) = self.request.take() else {
            return Ok(());
        };
        let body = match request.command {
            Command::Status => ResponseBody::Status(self.fill_status(platform)),
            Command::TestFault(f) => {
                let _ = platform.test_fault(f);
                ResponseBody::Error(WireError::TestHooksDisabled)
            }
            Command::Lock => {
                self.config_id.locked = true;
                ResponseBody::LockEngaged
            }
            Command::Configure(c) => self.change(None, Change::Configure(c)),
            Command::AuthConfigure(a) => {
                let signed = gate::Signed::configure(&a);
                self.change(Some(signed), Change::Configure(a.config))
            }
            Command::Araim(AraimCommand::Ism(frame)) => self.change(None, Change::Ism(frame)),
            Command::Araim(AraimCommand::AuthIsm { counter, ism, tag }) => {
                let signed = gate::Signed::ism(counter, &ism, tag);
                self.change(Some(signed), Change::Ism(ism))
            }
            Command::PfConfigure(c) => self.change(None, Change::Pf(c)),
            Command::PfRanges(e) => self.pf_epoch(e.time_s, &e.sats.items, platform),
            // Answered from the request slot above.
            Command::Ranges(_)
            | Command::Linear(_)
            | Command::Araim(AraimCommand::Epoch(_) | AraimCommand::Ranges(_)) => return Ok(()),
        };
        self.send(link, Some(seq), BodyRef::from(&body))
    }

    /// `Status`, with the platform's fields filled in.
    fn fill_status<P: Platform>(&mut self, platform: &mut P) -> Status {
        self.status.stack_high_water_bytes = platform.stack_high_water_bytes();
        (self.status.resets, self.status.reset_cause) = platform.reset_record();
        self.status.auth_provisioned = self.auth.is_some();
        platform.board_status(&mut self.status);
        self.status()
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
                // `dispatch` sends only epochs here.
                _ => return Ok(()),
            }
        };
        match outcome {
            Ok(()) => {
                answer::write_nmea(&self.wire, self.request.as_ref(), nmea_out)
                    .map_err(IoError::Nmea)?;
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
    raim: &mut Raim<CAPACITY, DevicePrecision>,
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

#[cfg(test)]
mod tests;
